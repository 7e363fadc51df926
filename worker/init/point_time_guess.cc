#include "worker/init/point_time_guess.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

namespace keel::init {

namespace {

using proto::PointTimeSpec;
using proto::TimeReference;
using proto::TimeUnit;

// The names drivers give a single time field, most specific first.
const char* const kTimeNames[] = {"time",        "t",           "timestamp", "time_stamp",
                                  "offset_time", "time_offset", "ts",        "stamp"};
// Suffix pairs of split integer time: whole seconds + nanoseconds.
const std::pair<const char*, const char*> kSplitSuffixes[] = {
    {"sec", "nsec"},      {"_sec", "_nsec"},  {"secs", "nsecs"},
    {"_sec", "_nanosec"}, {"sec", "nanosec"}, {"_s", "_ns"}};

double load_value(const uint8_t* p, io::FieldType type) {
  auto get = [&](auto v) {
    std::memcpy(&v, p, sizeof(v));
    return static_cast<double>(v);
  };
  switch (type) {
    case io::FieldType::kInt8:
      return get(int8_t{});
    case io::FieldType::kUint8:
      return get(uint8_t{});
    case io::FieldType::kInt16:
      return get(int16_t{});
    case io::FieldType::kUint16:
      return get(uint16_t{});
    case io::FieldType::kInt32:
      return get(int32_t{});
    case io::FieldType::kUint32:
      return get(uint32_t{});
    case io::FieldType::kInt64:
      return get(int64_t{});
    case io::FieldType::kUint64:
      return get(uint64_t{});
    case io::FieldType::kFloat32:
      return get(float{});
    case io::FieldType::kFloat64:
      return get(double{});
  }
  return 0.0;
}

struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  bool finite = true;
};

Range range_of(const io::PackedCloudView& view, const io::PackedField& f) {
  Range r;
  for (size_t i = 0; i < view.num_points; ++i) {
    const double v = load_value(view.data + i * view.point_step + f.offset, f.type);
    if (!std::isfinite(v)) {
      r.finite = false;
      continue;
    }
    r.lo = std::min(r.lo, v);
    r.hi = std::max(r.hi, v);
  }
  return r;
}

std::string text(double x) {
  char b[32];
  std::snprintf(b, sizeof(b), "%.6g", x);
  return b;
}

// Offsets [lo, hi] s relative to the stamp: scan_end when none is after it.
TimeReference relative_reference(double lo, double hi) {
  const double slack = 1e-3 * std::max(hi - lo, 1e-9);
  return hi <= slack && lo < 0.0 ? TimeReference::kScanEnd : TimeReference::kScanStart;
}

std::string where_stamp(double lo, double hi) {
  const double slack = 0.05 * std::max(hi - lo, 1e-6);
  if (lo >= -slack) return "the stamp marks the first point";
  if (hi <= slack) return "the stamp marks the last point";
  return "the stamp falls inside the sweep";
}

}  // namespace

PointTimeGuess guess_point_time(const io::PackedCloudView& view, TimeNs stamp_ns,
                                double sweep_period_s) {
  PointTimeGuess g;
  const double period = sweep_period_s > 0.0 ? sweep_period_s : 0.1;
  const double stamp_s = ns_to_seconds(stamp_ns);
  if (view.num_points == 0) {
    g.evidence = "the first message has no points: time field not checked";
    return g;
  }

  // Split integer pairs first: their names are unambiguous.
  for (const auto& nsec : view.fields) {
    if (!io::is_integer(nsec.type)) continue;
    for (const auto& [sec_suffix, nsec_suffix] : kSplitSuffixes) {
      const std::string ns_suffix = nsec_suffix;
      if (nsec.name.size() < ns_suffix.size() ||
          nsec.name.compare(nsec.name.size() - ns_suffix.size(), ns_suffix.size(), ns_suffix))
        continue;
      const std::string prefix = nsec.name.substr(0, nsec.name.size() - ns_suffix.size());
      const io::PackedField* sec = view.find(prefix + sec_suffix);
      if (!sec || sec == &nsec || !io::is_integer(sec->type)) continue;
      const Range rs = range_of(view, *sec), rn = range_of(view, nsec);
      PointTimeSpec spec;
      spec.field = sec->name;
      spec.nsec_field = nsec.name;
      const bool absolute = rs.lo > 1e8;
      // Offsets from the stamp per point, in seconds (whole seconds subtracted first).
      const double base_s = absolute ? std::floor(stamp_s) : 0.0;
      const double stamp_frac_s = absolute ? stamp_s - base_s : 0.0;
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      for (size_t i = 0; i < view.num_points; ++i) {
        const uint8_t* record = view.data + i * view.point_step;
        const double t = (load_value(record + sec->offset, sec->type) - base_s) +
                         load_value(record + nsec.offset, nsec.type) * 1e-9 - stamp_frac_s;
        lo = std::min(lo, t);
        hi = std::max(hi, t);
      }
      spec.reference = absolute ? TimeReference::kAbsolute : relative_reference(lo, hi);
      g.spec = spec;
      g.certain =
          rn.lo >= 0 && rn.hi < 1e9 && std::abs(lo) <= 10 * period && std::abs(hi) <= 10 * period;
      g.evidence = "split integer time '" + sec->name + "' + '" + nsec.name +
                   "': " + (absolute ? "epoch seconds" : "seconds from the stamp") + ", offsets [" +
                   text(lo) + ", " + text(hi) + "] s from the header stamp; " + where_stamp(lo, hi);
      return g;
    }
  }

  for (const char* name : kTimeNames) {
    const io::PackedField* f = view.find(name);
    if (!f) continue;
    const Range r = range_of(view, *f);
    const std::string what = "field '" + f->name + "' (" + io::to_string(f->type) +
                             "): values in [" + text(r.lo) + ", " + text(r.hi) + "]";
    if (!r.finite) {
      g.evidence = what + " include non-finite values: not used as point time";
      return g;
    }
    PointTimeSpec spec;
    spec.field = f->name;
    // Absolute stamps: epoch values, by magnitude (1e9 s, 1e12 ms, 1e15 us, 1e18 ns).
    const std::pair<double, TimeUnit> kAbsolute[] = {{1e17, TimeUnit::kNanoseconds},
                                                     {1e14, TimeUnit::kMicroseconds},
                                                     {1e11, TimeUnit::kMilliseconds},
                                                     {1e8, TimeUnit::kSeconds}};
    for (const auto& [floor_value, unit] : kAbsolute) {
      if (r.lo < floor_value) continue;
      spec.unit = unit;
      spec.reference = TimeReference::kAbsolute;
      const double s = proto::seconds_per_unit(unit);
      const double lo = r.lo * s - stamp_s, hi = r.hi * s - stamp_s;
      g.spec = spec;
      g.certain = std::abs(lo) <= 10 * period && std::abs(hi) <= 10 * period;
      g.evidence = what + ": absolute " + proto::to_string(unit) + " since the epoch, offsets [" +
                   text(lo) + ", " + text(hi) + "] s from the header stamp; " + where_stamp(lo, hi);
      return g;
    }
    // Relative: the unit that makes the span closest to a sweep.
    const double span = r.hi - r.lo;
    if (span <= 0.0) {
      spec.unit = io::is_integer(f->type) ? TimeUnit::kNanoseconds : TimeUnit::kSeconds;
      g.spec = spec;
      g.evidence = what + ": every point has the same time; unit and reference not checked";
      return g;
    }
    double best = std::numeric_limits<double>::infinity();
    for (TimeUnit unit : {TimeUnit::kSeconds, TimeUnit::kMilliseconds, TimeUnit::kMicroseconds,
                          TimeUnit::kNanoseconds}) {
      if (io::is_integer(f->type) && unit == TimeUnit::kSeconds) continue;
      const double miss = std::abs(std::log(span * proto::seconds_per_unit(unit) / period));
      if (miss < best) best = miss, spec.unit = unit;
    }
    const double s = proto::seconds_per_unit(spec.unit);
    spec.reference = relative_reference(r.lo * s, r.hi * s);
    g.spec = spec;
    g.certain = best < std::log(3.0);
    g.evidence = what + ": " + proto::to_string(spec.unit) + " from the stamp, a sweep of " +
                 text(span * s) + " s (period " + text(period) + " s); " +
                 where_stamp(r.lo * s, r.hi * s);
    return g;
  }
  g.evidence = "no per-point time field recognised (fields:";
  for (const auto& f : view.fields) g.evidence += " " + f.name;
  g.evidence += ")";
  return g;
}

}  // namespace keel::init
