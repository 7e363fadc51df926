#include "worker/io/cloud/packed_cloud.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "worker/io/io_error.h"

namespace keel::io {

namespace {

template <typename T>
T load(const uint8_t* p) {
  T value;
  std::memcpy(&value, p, sizeof(T));
  return value;
}

// Calls visit(i, value) for every point's value of `field`, value typed as stored.
template <typename Visit>
void read_column(const PackedCloudView& view, const PackedField& field, Visit&& visit) {
  auto run = [&](auto tag) {
    using T = decltype(tag);
    const uint8_t* p = view.data + field.offset;
    const size_t step = field.stride ? field.stride : view.point_step;
    for (size_t i = 0; i < view.num_points; ++i, p += step) {
      T value;
      std::memcpy(&value, p, sizeof(T));
      visit(i, value);
    }
  };
  switch (field.type) {
    case FieldType::kInt8:
      return run(int8_t{});
    case FieldType::kUint8:
      return run(uint8_t{});
    case FieldType::kInt16:
      return run(int16_t{});
    case FieldType::kUint16:
      return run(uint16_t{});
    case FieldType::kInt32:
      return run(int32_t{});
    case FieldType::kUint32:
      return run(uint32_t{});
    case FieldType::kInt64:
      return run(int64_t{});
    case FieldType::kUint64:
      return run(uint64_t{});
    case FieldType::kFloat32:
      return run(float{});
    case FieldType::kFloat64:
      return run(double{});
  }
}

// Removes points with a NaN or infinite coordinate, keeping every field in step.
void drop_non_finite(PointCloud& cloud) {
  const size_t n = cloud.xyz.size();
  size_t kept = 0;
  for (size_t i = 0; i < n; ++i) {
    if (!cloud.xyz[i].allFinite()) continue;
    if (kept != i) {
      cloud.xyz[kept] = cloud.xyz[i];
      if (!cloud.intensity.empty()) cloud.intensity[kept] = cloud.intensity[i];
      if (!cloud.ring.empty()) cloud.ring[kept] = cloud.ring[i];
      if (!cloud.time_s.empty()) cloud.time_s[kept] = cloud.time_s[i];
    }
    ++kept;
  }
  if (kept == n) return;
  cloud.xyz.resize(kept);
  if (!cloud.intensity.empty()) cloud.intensity.resize(kept);
  if (!cloud.ring.empty()) cloud.ring.resize(kept);
  if (!cloud.time_s.empty()) cloud.time_s.resize(kept);
}

double load_double(const uint8_t* p, FieldType type) {
  switch (type) {
    case FieldType::kInt8:
      return load<int8_t>(p);
    case FieldType::kUint8:
      return load<uint8_t>(p);
    case FieldType::kInt16:
      return load<int16_t>(p);
    case FieldType::kUint16:
      return load<uint16_t>(p);
    case FieldType::kInt32:
      return load<int32_t>(p);
    case FieldType::kUint32:
      return load<uint32_t>(p);
    case FieldType::kInt64:
      return static_cast<double>(load<int64_t>(p));
    case FieldType::kUint64:
      return static_cast<double>(load<uint64_t>(p));
    case FieldType::kFloat32:
      return load<float>(p);
    case FieldType::kFloat64:
      return load<double>(p);
  }
  return 0.0;
}

// Integer fields only; uint64 above int64 range saturates (and then fails the range check).
int64_t load_int64(const uint8_t* p, FieldType type) {
  if (type == FieldType::kUint64) {
    const uint64_t v = load<uint64_t>(p);
    return v > static_cast<uint64_t>(std::numeric_limits<int64_t>::max())
               ? std::numeric_limits<int64_t>::max()
               : static_cast<int64_t>(v);
  }
  if (type == FieldType::kInt64) return load<int64_t>(p);
  return static_cast<int64_t>(load_double(p, type));
}

int64_t ns_per_unit(proto::TimeUnit unit) {
  switch (unit) {
    case proto::TimeUnit::kSeconds:
      return 1000000000;
    case proto::TimeUnit::kMilliseconds:
      return 1000000;
    case proto::TimeUnit::kMicroseconds:
      return 1000;
    case proto::TimeUnit::kNanoseconds:
      return 1;
  }
  return 1;
}

std::string number_text(double x) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.6g", x);
  return buffer;
}

// Units whose scaling of the raw values would give offsets that fit `limit_s`.
std::string fitting_units(double raw_min, double raw_max, double base_s, double limit_s) {
  std::string out;
  for (auto unit : {proto::TimeUnit::kSeconds, proto::TimeUnit::kMilliseconds,
                    proto::TimeUnit::kMicroseconds, proto::TimeUnit::kNanoseconds}) {
    const double s = proto::seconds_per_unit(unit);
    const double lo = raw_min * s - base_s, hi = raw_max * s - base_s;
    if (std::max(std::abs(lo), std::abs(hi)) <= limit_s && (hi - lo) > 0.0 &&
        (hi - lo) >= 1e-4 * limit_s / 10.0)
      out += (out.empty() ? "" : " or ") + proto::to_string(unit);
  }
  return out;
}

}  // namespace

size_t field_size(FieldType type) {
  switch (type) {
    case FieldType::kInt8:
    case FieldType::kUint8:
      return 1;
    case FieldType::kInt16:
    case FieldType::kUint16:
      return 2;
    case FieldType::kInt32:
    case FieldType::kUint32:
    case FieldType::kFloat32:
      return 4;
    case FieldType::kInt64:
    case FieldType::kUint64:
    case FieldType::kFloat64:
      return 8;
  }
  return 0;
}

bool is_integer(FieldType type) {
  return type != FieldType::kFloat32 && type != FieldType::kFloat64;
}

std::string to_string(FieldType type) {
  switch (type) {
    case FieldType::kInt8:
      return "int8";
    case FieldType::kUint8:
      return "uint8";
    case FieldType::kInt16:
      return "int16";
    case FieldType::kUint16:
      return "uint16";
    case FieldType::kInt32:
      return "int32";
    case FieldType::kUint32:
      return "uint32";
    case FieldType::kInt64:
      return "int64";
    case FieldType::kUint64:
      return "uint64";
    case FieldType::kFloat32:
      return "float32";
    case FieldType::kFloat64:
      return "float64";
  }
  return "unknown";
}

const PackedField* PackedCloudView::find(const std::string& name) const {
  for (const auto& f : fields)
    if (f.name == name) return &f;
  return nullptr;
}

namespace {

// The reference under which offsets [lo, hi] s from the stamp fit one sweep: all after it
// (the stamp marks the first point) or all before it (the last point); "" for neither.
std::string fitting_reference(double lo, double hi, double sweep_s) {
  const double slack = 0.05 * sweep_s;
  if (lo >= -slack && hi <= sweep_s + slack) return "scan_start";
  if (hi <= slack && lo >= -sweep_s - slack) return "scan_end";
  return "";
}

}  // namespace

std::vector<double> point_time_offsets(const PackedCloudView& view, const PackedField& field,
                                       TimeNs t_ns, const proto::PointTimeSpec& spec,
                                       double sweep_period_s, const std::string& source) {
  const size_t n = view.num_points;
  const bool absolute = spec.reference == proto::TimeReference::kAbsolute;
  const bool split = spec.is_split();
  const double unit_s = split ? 1.0 : proto::seconds_per_unit(spec.unit);
  std::vector<double> offsets(n);
  double raw_min = std::numeric_limits<double>::infinity();
  double raw_max = -raw_min;
  const uint8_t* base = view.data + field.offset;
  const size_t step = field.stride ? field.stride : view.point_step;
  const PackedField* nsec = split ? view.find(spec.nsec_field) : nullptr;
  const std::string what =
      split ? source + ": fields '" + field.name + "' (" + to_string(field.type) + ") + '" +
                  spec.nsec_field + "' (" + (nsec ? to_string(nsec->type) : "missing") +
                  "), split seconds + nanoseconds, reference " + proto::to_string(spec.reference)
            : source + ": field '" + field.name + "' (" + to_string(field.type) +
                  ", declared unit " + proto::to_string(spec.unit) + ", reference " +
                  proto::to_string(spec.reference) + ")";
  if (split) {
    if (!nsec) {
      std::string names;
      for (const auto& f : view.fields) names += (names.empty() ? "" : " ") + f.name;
      throw IoError(source + ": no nanoseconds field '" + spec.nsec_field +
                    "' of the split time (fields: " + names + ")");
    }
    if (!is_integer(field.type) || !is_integer(nsec->type))
      throw IoError(what + ": a split time needs integer fields");
    // Exact: sec * 1e9 + nsec in int64 ns, minus the integer stamp when absolute.
    constexpr int64_t kMaxSec = std::numeric_limits<int64_t>::max() / 1000000000 - 1;
    const uint8_t* nsec_base = view.data + nsec->offset;
    const size_t nsec_step = nsec->stride ? nsec->stride : view.point_step;
    for (size_t i = 0; i < n; ++i) {
      const int64_t sec = load_int64(base + i * step, field.type);
      const int64_t ns = load_int64(nsec_base + i * nsec_step, nsec->type);
      if (ns < 0 || ns >= 1000000000)
        throw IoError(what + ": point " + std::to_string(i) + " has " + std::to_string(ns) +
                      " ns; expected 0 <= nanoseconds < 1e9");
      if (sec > kMaxSec || sec < -kMaxSec)
        throw IoError(what + ": point " + std::to_string(i) + " has " + std::to_string(sec) +
                      " s, beyond int64 nanoseconds");
      const int64_t total_ns = sec * 1000000000 + ns;
      raw_min = std::min(raw_min, static_cast<double>(total_ns) * 1e-9);
      raw_max = std::max(raw_max, static_cast<double>(total_ns) * 1e-9);
      offsets[i] = static_cast<double>(absolute ? total_ns - t_ns : total_ns) * 1e-9;
    }
  } else if (absolute && is_integer(field.type)) {
    // Exact: integer stamps minus the integer scan stamp, in nanoseconds.
    const int64_t scale = ns_per_unit(spec.unit);
    for (size_t i = 0; i < n; ++i) {
      const int64_t raw = load_int64(base + i * step, field.type);
      raw_min = std::min(raw_min, static_cast<double>(raw));
      raw_max = std::max(raw_max, static_cast<double>(raw));
      const bool overflow = raw > std::numeric_limits<int64_t>::max() / scale ||
                            raw < std::numeric_limits<int64_t>::min() / scale;
      offsets[i] = overflow ? std::numeric_limits<double>::infinity()
                            : static_cast<double>(raw * scale - t_ns) * 1e-9;
    }
  } else {
    // Absolute float stamps: the raw value's whole units are converted to integer ns and
    // subtracted from the stamp exactly; only the fraction is scaled in floating point. The
    // error is then the float64 value's own rounding: an epoch time near 1.7e9 s has an ulp
    // of 2^-22 s = 238 ns (at most 119 ns off), well under a microsecond.
    const int64_t scale = ns_per_unit(spec.unit);
    const double max_whole = static_cast<double>(std::numeric_limits<int64_t>::max() / scale);
    for (size_t i = 0; i < n; ++i) {
      const double raw = load_double(base + i * step, field.type);
      if (!std::isfinite(raw))
        throw IoError(what + ": point " + std::to_string(i) + " has time " + number_text(raw) +
                      "; expected finite values");
      raw_min = std::min(raw_min, raw);
      raw_max = std::max(raw_max, raw);
      if (!absolute) {
        offsets[i] = raw * unit_s;
        continue;
      }
      const double whole = std::floor(raw);
      if (std::abs(whole) >= max_whole) {
        offsets[i] = std::numeric_limits<double>::infinity();
        continue;
      }
      const int64_t whole_ns = static_cast<int64_t>(whole) * scale;
      offsets[i] = static_cast<double>(whole_ns - t_ns) * 1e-9 + (raw - whole) * unit_s;
    }
  }
  if (n == 0 || sweep_period_s <= 0.0) return offsets;

  const auto [lo_it, hi_it] = std::minmax_element(offsets.begin(), offsets.end());
  const double lo = *lo_it, hi = *hi_it;
  const double limit_s = 10.0 * sweep_period_s;
  const double stamp_s = absolute ? ns_to_seconds(t_ns) : 0.0;
  const double raw_unit_s = split ? 1.0 : unit_s;  // raw_min/max are in this unit
  const std::string found = "values in [" + number_text(raw_min) + ", " + number_text(raw_max) +
                            "]" + (split ? " s" : "");
  const std::string offsets_text = "offsets [" + number_text(lo) + ", " + number_text(hi) +
                                   "] s from the scan stamp " + format_seconds(t_ns);
  if (std::max(std::abs(lo), std::abs(hi)) > limit_s) {
    std::string hint;
    const std::string units =
        split ? std::string() : fitting_units(raw_min, raw_max, stamp_s, limit_s);
    if (!units.empty()) hint = "; they fit unit " + units;
    if (!absolute && raw_min * raw_unit_s > 1e8)
      hint = "; they look like absolute stamps (reference absolute?)";
    if (absolute) {
      const std::string reference =
          fitting_reference(raw_min * raw_unit_s, raw_max * raw_unit_s, sweep_period_s);
      if (!reference.empty())
        hint = std::string("; they look like offsets ") +
               (reference == "scan_start" ? "from the scan start" : "to the scan end") +
               " (reference " + reference + "?)";
      else if (!split && !fitting_units(raw_min, raw_max, 0.0, limit_s).empty())
        hint = "; they look like offsets from the scan start (reference scan_start?)";
    }
    throw IoError(what + ": " + found + " give " + offsets_text + ", beyond 10 sweep periods (" +
                  number_text(limit_s) + " s)" + hint);
  }
  // The stamp marks the sweep's first (scan_start) or last (scan_end) point: points more than
  // a sweep before (after) it mean the other reference.
  const bool before = spec.reference == proto::TimeReference::kScanStart && lo < -sweep_period_s;
  const bool after = spec.reference == proto::TimeReference::kScanEnd && hi > sweep_period_s;
  if (before || after) {
    const std::string reference = fitting_reference(lo, hi, sweep_period_s);
    throw IoError(what + ": " + found + " give " + offsets_text + ", more than a sweep (" +
                  number_text(sweep_period_s) + " s) " + (before ? "before" : "after") +
                  " the stamp" +
                  (reference.empty() ? std::string() : "; they fit reference " + reference));
  }
  const double span = hi - lo;
  if (!split && span > 0.0 && span < 1e-4 * sweep_period_s) {
    const std::string units = fitting_units(raw_min, raw_max, stamp_s, limit_s);
    if (!units.empty() && units.find(proto::to_string(spec.unit)) == std::string::npos)
      throw IoError(what + ": " + found + " span only " + number_text(span) + " s of a " +
                    number_text(sweep_period_s) + " s sweep; they fit unit " + units);
  }
  return offsets;
}

PointCloud unpack_cloud(const PackedCloudView& view, TimeNs t_ns, const ScanReadOptions& options,
                        const std::string& source) {
  const char* axes[3] = {"x", "y", "z"};
  const PackedField* xyz[3];
  for (int a = 0; a < 3; ++a) {
    xyz[a] = view.find(axes[a]);
    if (!xyz[a]) throw IoError(source + ": no field '" + axes[a] + "' (a scan needs x, y, z)");
    if (xyz[a]->type != FieldType::kFloat32 && xyz[a]->type != FieldType::kFloat64)
      throw IoError(source + ": field '" + axes[a] + "' is " + to_string(xyz[a]->type) +
                    "; expected float32 or float64");
  }
  const PackedField* intensity = view.find("intensity");
  const PackedField* ring = view.find("ring");
  const PackedField* time = nullptr;
  std::vector<double> offsets;
  if (options.point_time) {
    time = view.find(options.point_time->field);
    if (!time) {
      std::string names;
      for (const auto& f : view.fields) names += (names.empty() ? "" : " ") + f.name;
      throw IoError(source + ": no per-point time field '" + options.point_time->field +
                    "' (fields: " + names + ")");
    }
    offsets =
        point_time_offsets(view, *time, t_ns, *options.point_time, options.sweep_period_s, source);
  }

  PointCloud cloud;
  cloud.t_ns = t_ns;
  cloud.frame = options.frame;
  const size_t n = view.num_points;
  // Field by field, each in one typed loop (a switch per field, not per value).
  cloud.xyz.resize(n);
  for (int a = 0; a < 3; ++a)
    read_column(view, *xyz[a],
                [&](size_t i, auto value) { cloud.xyz[i][a] = static_cast<float>(value); });
  if (intensity) {
    cloud.intensity.resize(n);
    read_column(view, *intensity,
                [&](size_t i, auto value) { cloud.intensity[i] = static_cast<float>(value); });
  }
  if (ring) {
    cloud.ring.resize(n);
    read_column(view, *ring, [&](size_t i, auto value) {
      // A ring is a laser's index: converting anything outside 0..65535 (or NaN) to uint16 is
      // undefined (UBSan, fuzz_scan_file: a float ring of -12208.1).
      // Points dropped below for a non-finite coordinate are not checked (nor kept).
      const double d = static_cast<double>(value);
      const bool checked = options.keep_non_finite || cloud.xyz[i].allFinite();
      if (!checked) return;
      if (!(d >= 0.0 && d <= 65535.0 && d == std::floor(d)))
        throw IoError(source + ": point " + std::to_string(i) + ": ring " + number_text(d) +
                      " is not a laser index (an integer in 0..65535)");
      cloud.ring[i] = static_cast<uint16_t>(value);
    });
  }
  if (time) {
    cloud.time_s.resize(n);
    for (size_t i = 0; i < n; ++i) cloud.time_s[i] = static_cast<float>(offsets[i]);
  }
  if (!options.keep_non_finite) drop_non_finite(cloud);
  return cloud;
}

}  // namespace keel::io

namespace keel::io {

namespace {

template <typename T>
void store(uint8_t* p, T value) {
  std::memcpy(p, &value, sizeof(T));
}

void store_number(uint8_t* p, FieldType type, double value) {
  switch (type) {
    case FieldType::kInt8:
      return store<int8_t>(p, static_cast<int8_t>(std::llround(value)));
    case FieldType::kUint8:
      return store<uint8_t>(p, static_cast<uint8_t>(std::llround(value)));
    case FieldType::kInt16:
      return store<int16_t>(p, static_cast<int16_t>(std::llround(value)));
    case FieldType::kUint16:
      return store<uint16_t>(p, static_cast<uint16_t>(std::llround(value)));
    case FieldType::kInt32:
      return store<int32_t>(p, static_cast<int32_t>(std::llround(value)));
    case FieldType::kUint32:
      return store<uint32_t>(p, static_cast<uint32_t>(std::llround(value)));
    case FieldType::kInt64:
      return store<int64_t>(p, static_cast<int64_t>(std::llround(value)));
    case FieldType::kUint64:
      return store<uint64_t>(p, static_cast<uint64_t>(std::llround(value)));
    case FieldType::kFloat32:
      return store<float>(p, static_cast<float>(value));
    case FieldType::kFloat64:
      return store<double>(p, value);
  }
}

}  // namespace

PackedCloud pack_cloud(const PointCloud& cloud, const std::optional<PointTimeEncoding>& time) {
  PackedCloud out;
  auto add = [&](const std::string& name, FieldType type) {
    out.fields.push_back({name, type, out.point_step, 1});
    out.point_step += field_size(type);
  };
  add("x", FieldType::kFloat32);
  add("y", FieldType::kFloat32);
  add("z", FieldType::kFloat32);
  if (cloud.has_intensity()) add("intensity", FieldType::kFloat32);
  if (cloud.has_ring()) add("ring", FieldType::kUint16);
  const bool with_time = time && cloud.has_time();
  if (with_time) add(time->spec.field, time->type);
  const bool split = with_time && time->spec.is_split();
  if (split) add(time->spec.nsec_field, FieldType::kUint32);
  out.num_points = cloud.size();
  out.data.resize(out.num_points * out.point_step);
  const bool absolute = with_time && time->spec.reference == proto::TimeReference::kAbsolute;
  const double unit_s = with_time ? proto::seconds_per_unit(time->spec.unit) : 1.0;
  for (size_t i = 0; i < cloud.size(); ++i) {
    uint8_t* record = out.data.data() + i * out.point_step;
    size_t f = 0;
    for (int a = 0; a < 3; ++a) store<float>(record + out.fields[f++].offset, cloud.xyz[i][a]);
    if (cloud.has_intensity()) store<float>(record + out.fields[f++].offset, cloud.intensity[i]);
    if (cloud.has_ring()) store<uint16_t>(record + out.fields[f++].offset, cloud.ring[i]);
    if (!with_time) continue;
    uint8_t* p = record + out.fields[f].offset;
    const double offset_s = cloud.time_s[i];
    if (split) {
      // Whole seconds (floor) and nanoseconds in [0, 1e9) of the time in ns.
      const int64_t t = std::llround(offset_s * 1e9) + (absolute ? cloud.t_ns : 0);
      int64_t sec = t / 1000000000, nsec = t % 1000000000;
      if (nsec < 0) {
        nsec += 1000000000;
        --sec;
      }
      store_number(p, time->type, static_cast<double>(sec));
      if (time->type == FieldType::kInt64 || time->type == FieldType::kUint64)
        store<int64_t>(p, sec);
      store<uint32_t>(record + out.fields[f + 1].offset, static_cast<uint32_t>(nsec));
    } else if (absolute && is_integer(time->type)) {
      const int64_t stamp_ns = cloud.t_ns + std::llround(offset_s * 1e9);
      store_number(p, time->type, static_cast<double>(stamp_ns / ns_per_unit(time->spec.unit)));
      if (time->type == FieldType::kInt64 || time->type == FieldType::kUint64)
        store<int64_t>(p, stamp_ns / ns_per_unit(time->spec.unit));  // exact beyond 2^53
    } else if (absolute) {
      // One rounding: whole seconds (exact in a double) plus the fraction and the offset.
      const double whole_s = static_cast<double>(cloud.t_ns / 1000000000);
      const double frac_s = static_cast<double>(cloud.t_ns % 1000000000) * 1e-9 + offset_s;
      store_number(p, time->type, (whole_s + frac_s) / unit_s);
    } else {
      store_number(p, time->type, offset_s / unit_s);
    }
  }
  return out;
}

}  // namespace keel::io
