// Progress text, rate and ETA against hand-computed values.
#include "client/progress_bar.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace keel::client {
namespace {

TEST(ProgressMath, FormatsBytes) {
  EXPECT_EQ(format_bytes(0), "0 B");
  EXPECT_EQ(format_bytes(1023), "1023 B");
  EXPECT_EQ(format_bytes(1536), "1.50 KiB");
  EXPECT_EQ(format_bytes(12.5 * 1024 * 1024), "12.5 MiB");
  EXPECT_EQ(format_bytes(300.0 * 1024 * 1024), "300 MiB");
  EXPECT_EQ(format_bytes(1024.0 * 1024 * 1024), "1.00 GiB");
}

TEST(ProgressMath, FormatsDurations) {
  EXPECT_EQ(format_duration(0), "0:00");
  EXPECT_EQ(format_duration(7.4), "0:07");
  EXPECT_EQ(format_duration(59.6), "1:00");
  EXPECT_EQ(format_duration(3723), "1:02:03");
  EXPECT_EQ(format_duration(-1), "--:--");
  EXPECT_EQ(format_duration(NAN), "--:--");
}

TEST(ProgressMath, RateAndEtaIgnoreResumedBytes) {
  // A resumed upload: 100 MiB were on the server when it started at t = 10 s; at t = 14 s
  // 140 MiB are done of 200 MiB. Rate = 40 MiB / 4 s = 10 MiB/s; ETA = 60 MiB / 10 MiB/s = 6 s.
  const int64_t mib = 1 << 20;
  const TransferRate rate{100 * mib, 10.0};
  EXPECT_DOUBLE_EQ(rate.bytes_per_s(140 * mib, 14.0), 10.0 * mib);
  EXPECT_DOUBLE_EQ(rate.eta_s(140 * mib, 200 * mib, 14.0), 6.0);
  EXPECT_DOUBLE_EQ(rate.bytes_per_s(100 * mib, 10.0), 0.0);  // no time yet
  EXPECT_LT(rate.eta_s(100 * mib, 200 * mib, 10.0), 0.0);    // unknown
  EXPECT_LT(rate.eta_s(140 * mib, -1, 14.0), 0.0);           // total unknown
}

TEST(ProgressBar, RendersBytesRateAndEta) {
  const int64_t mib = 1 << 20;
  ProgressBar bar("bundle m1", ProgressBarOptions{}, stderr);
  bar.update(0, 48 * mib, 100.0);  // start: nothing done
  // 12 MiB in 3 s = 4 MiB/s; 36 MiB left = 9 s.
  EXPECT_EQ(bar.render(12 * mib, 48 * mib, 103.0),
            "bundle m1  12.0 MiB / 48.0 MiB  25%  4.00 MiB/s  ETA 0:09");
  ProgressBarOptions terminal;
  terminal.terminal = true;
  terminal.width = 10;
  ProgressBar tty("f", terminal, stderr);
  tty.update(0, 100, 0.0);
  EXPECT_EQ(tty.render(50, 100, 5.0), "f  [#####.....] 50 B / 100 B  50%  10 B/s  ETA 0:05");
}

TEST(ProgressBar, PlainLinesAreThrottled) {
  char* text = nullptr;
  size_t size = 0;
  std::FILE* out = open_memstream(&text, &size);
  ProgressBarOptions options;
  options.line_interval_s = 5.0;
  ProgressBar bar("x", options, out);
  for (int i = 0; i <= 10; ++i) bar.update(i * 10, 100, i * 1.0);  // t = 0..10 s
  bar.finish(10.0);
  std::fclose(out);
  const std::string lines(text, size);
  std::free(text);
  // Drawn at t = 0, 5, 10, plus the final line.
  EXPECT_EQ(std::count(lines.begin(), lines.end(), '\n'), 4) << lines;
}

}  // namespace
}  // namespace keel::client
