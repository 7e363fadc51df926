#include "core/time.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace keel {

TimeNs seconds_to_ns(double t_s) { return static_cast<TimeNs>(std::llround(t_s * 1e9)); }

TimeNs parse_seconds_exact(std::string_view text) {
  auto fail = [&] { return std::invalid_argument("not a time in seconds: '" + std::string(text) + "'"); };
  size_t i = 0;
  while (i < text.size() && (text[i] == ' ' || text[i] == '\t')) ++i;
  size_t end = text.size();
  while (end > i && (text[end - 1] == ' ' || text[end - 1] == '\t' || text[end - 1] == '\r')) --end;
  bool negative = false;
  if (i < end && (text[i] == '-' || text[i] == '+')) negative = text[i++] == '-';
  int64_t whole = 0;
  int64_t fraction = 0;
  int digits = 0, fraction_digits = 0;
  for (; i < end && text[i] != '.'; ++i, ++digits) {
    if (text[i] < '0' || text[i] > '9' || whole > std::numeric_limits<int64_t>::max() / 10 / 1000000000)
      throw fail();
    whole = whole * 10 + (text[i] - '0');
  }
  if (i < end) {  // '.'
    for (++i; i < end; ++i, ++fraction_digits) {
      if (text[i] < '0' || text[i] > '9') throw fail();
      if (fraction_digits < 9) fraction = fraction * 10 + (text[i] - '0');
    }
  }
  if (digits + fraction_digits == 0) throw fail();
  for (int k = std::min(fraction_digits, 9); k < 9; ++k) fraction *= 10;
  const TimeNs value = whole * 1000000000 + fraction;
  return negative ? -value : value;
}

std::string format_seconds(TimeNs t_ns) {
  const bool negative = t_ns < 0;
  const uint64_t magnitude = negative ? static_cast<uint64_t>(-(t_ns + 1)) + 1 : static_cast<uint64_t>(t_ns);
  char buffer[48];
  std::snprintf(buffer, sizeof(buffer), "%s%llu.%09llu", negative ? "-" : "",
                static_cast<unsigned long long>(magnitude / 1000000000ULL),
                static_cast<unsigned long long>(magnitude % 1000000000ULL));
  return buffer;
}

}  // namespace keel
