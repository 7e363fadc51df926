#include "client/progress_bar.h"

#include <unistd.h>

#include <chrono>
#include <cmath>

namespace keel::client {

std::string format_bytes(double bytes) {
  static const char* kUnits[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  int unit = 0;
  while (bytes >= 1024.0 && unit < 4) {
    bytes /= 1024.0;
    ++unit;
  }
  char text[32];
  if (unit == 0) {
    std::snprintf(text, sizeof(text), "%.0f B", bytes);
  } else {
    const int decimals = bytes < 10 ? 2 : (bytes < 100 ? 1 : 0);
    std::snprintf(text, sizeof(text), "%.*f %s", decimals, bytes, kUnits[unit]);
  }
  return text;
}

std::string format_duration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "--:--";
  const auto total = static_cast<int64_t>(std::llround(seconds));
  const int64_t h = total / 3600, m = (total / 60) % 60, s = total % 60;
  char text[32];
  if (h > 0) {
    std::snprintf(text, sizeof(text), "%lld:%02lld:%02lld", static_cast<long long>(h),
                  static_cast<long long>(m), static_cast<long long>(s));
  } else {
    std::snprintf(text, sizeof(text), "%lld:%02lld", static_cast<long long>(m),
                  static_cast<long long>(s));
  }
  return text;
}

double TransferRate::bytes_per_s(int64_t done, double now_s) const {
  const double elapsed = now_s - start_s;
  if (elapsed <= 0) return 0.0;
  return static_cast<double>(done - start_bytes) / elapsed;
}

double TransferRate::eta_s(int64_t done, int64_t total, double now_s) const {
  const double rate = bytes_per_s(done, now_s);
  if (total < 0 || rate <= 0) return -1.0;
  return static_cast<double>(total - done) / rate;
}

ProgressBar::ProgressBar(std::string label, ProgressBarOptions options, std::FILE* out)
    : label_(std::move(label)), options_(options), out_(out) {}

std::string ProgressBar::render(int64_t done, int64_t total, double now_s) const {
  std::string text = label_ + "  ";
  if (options_.terminal && total > 0) {
    const int filled = static_cast<int>(options_.width * static_cast<double>(done) / total);
    text += "[" + std::string(filled, '#') + std::string(options_.width - filled, '.') + "] ";
  }
  text += format_bytes(static_cast<double>(done));
  if (total >= 0) {
    text += " / " + format_bytes(static_cast<double>(total));
    const int percent = total > 0 ? static_cast<int>(100.0 * done / total) : 100;
    text += "  " + std::to_string(percent) + "%";
  }
  text += "  " + format_bytes(rate_.bytes_per_s(done, now_s)) + "/s";
  if (total >= 0) text += "  ETA " + format_duration(rate_.eta_s(done, total, now_s));
  return text;
}

void ProgressBar::update(int64_t done, int64_t total, double now_s) {
  if (!started_) {
    rate_ = TransferRate{done, now_s};
    started_ = true;
  }
  done_ = done;
  total_ = total;
  const double interval = options_.terminal ? 0.1 : options_.line_interval_s;
  if (now_s - last_draw_s_ < interval) return;
  last_draw_s_ = now_s;
  const std::string text = render(done, total, now_s);
  if (options_.terminal) {
    std::fprintf(out_, "\r%s\033[K", text.c_str());
    line_open_ = true;
  } else {
    std::fprintf(out_, "%s\n", text.c_str());
  }
  std::fflush(out_);
}

void ProgressBar::finish(double now_s) {
  if (!started_) return;
  const std::string text = render(done_, total_, now_s);
  if (options_.terminal) {
    std::fprintf(out_, "\r%s\033[K\n", text.c_str());
  } else {
    std::fprintf(out_, "%s\n", text.c_str());
  }
  line_open_ = false;
  std::fflush(out_);
}

void ProgressBar::clear() {
  if (!line_open_) return;
  std::fprintf(out_, "\r\033[K");
  std::fflush(out_);
  line_open_ = false;
  last_draw_s_ = -1e300;  // redraw on the next update
}

double monotonic_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

bool is_terminal(std::FILE* stream) { return ::isatty(::fileno(stream)) == 1; }

}  // namespace keel::client
