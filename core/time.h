// Time: int64 nanoseconds at rest, double seconds in math (docs/design.md "Conventions").
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace keel {

using TimeNs = int64_t;

inline double ns_to_seconds(TimeNs t_ns) { return static_cast<double>(t_ns) * 1e-9; }
TimeNs seconds_to_ns(double t_s);

// Parses decimal seconds ("1700000000.123456789", "-0.5", "12") exactly into nanoseconds,
// without rounding through double. Throws std::invalid_argument naming the text otherwise.
TimeNs parse_seconds_exact(std::string_view text);
// Formats nanoseconds as decimal seconds with 9 fractional digits.
std::string format_seconds(TimeNs t_ns);

}  // namespace keel
