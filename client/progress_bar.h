// Transfer progress for people: bytes, bytes/s, ETA on stderr. On a terminal one line is
// redrawn in place; otherwise (logs, CI) plain lines are printed at most every few seconds.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>

namespace keel::client {

// "0 B", "512 B", "1.5 KiB", "12.3 MiB", "1.00 GiB": binary units, 3 significant digits.
std::string format_bytes(double bytes);
// "0:07", "1:02:03" (h:mm:ss); "--:--" for a negative or non-finite duration.
std::string format_duration(double seconds);

// Rate and ETA of one transfer. Bytes that were already done when it started (a resumed
// upload) count toward progress but not toward the rate.
struct TransferRate {
  int64_t start_bytes = 0;
  double start_s = 0.0;

  // Bytes per second since the start; 0 before any time has passed.
  double bytes_per_s(int64_t done, double now_s) const;
  // Seconds until `total`; negative when unknown (no rate yet, or total unknown).
  double eta_s(int64_t done, int64_t total, double now_s) const;
};

struct ProgressBarOptions {
  bool terminal = false;         // redraw one line ('\r') instead of printing lines
  double line_interval_s = 5.0;  // plain-line mode: at most one line per interval
  int width = 30;                // characters of the bar itself (terminal mode)
};

class ProgressBar {
 public:
  // `label` names the transfer ("bundle 3f2a….tar"); output goes to `out` (stderr).
  ProgressBar(std::string label, ProgressBarOptions options, std::FILE* out = stderr);

  // Feeds a progress report; draws when due. `now_s` is a monotonic clock in seconds.
  void update(int64_t done, int64_t total, double now_s);
  // Draws the final state and ends the line.
  void finish(double now_s);
  // Clears the terminal line so other output can be printed above the bar.
  void clear();

  // The text of one report, e.g. "bundle  12.0 MiB / 48.0 MiB  25%  4.00 MiB/s  ETA 0:09".
  std::string render(int64_t done, int64_t total, double now_s) const;

 private:
  std::string label_;
  ProgressBarOptions options_;
  std::FILE* out_;
  bool started_ = false;
  TransferRate rate_;
  int64_t done_ = 0;
  int64_t total_ = -1;
  double last_draw_s_ = -1e300;
  bool line_open_ = false;
};

// Seconds on the steady clock, for ProgressBar::update.
double monotonic_seconds();
// True when the stream is a terminal.
bool is_terminal(std::FILE* stream);

}  // namespace keel::client
