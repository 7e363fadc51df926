// Every per-point time convention real drivers write (Velodyne float s from the sweep start,
// Ouster uint32 ns, Livox/Hesai absolute float64 epoch seconds, split integer seconds +
// nanoseconds, stamps at the sweep's end) read from a scan file and from a PointCloud2 and
// deskewed: the points must equal the reference deskew of the same sweep held in memory with
// its stamp at the first point.
//
// Tolerances (points within 28 m of the sensor, body at 2.5 m/s turning at 0.8 rad/s, so a
// point moves at most ~25 m/s): deskewed coordinates are float32, so a deskew expressed at
// another stamp (scan_end) differs by the rounding of each side, <= 2 * sqrt(3)/2 ulp(28 m) =
// 3.3e-6 m, plus a float32 offset near 0.1 s off by <= 3.7e-9 s (1e-7 m): 3.5e-6 m. An
// absolute float64 epoch second near 1.7e9 s is within half its ulp, 2^-23 s = 119 ns (3e-6 m
// at 25 m/s): 7e-6 m. Measured worst: 2.8e-6 m (scan_end), 4.5e-6 m (float64 absolute).
// Conventions that carry the same float32 offset as the reference (Velodyne, Ouster ns, split,
// integer absolute, all stamped at the first point) must match exactly.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <random>

#include "io_test_util.h"
#include "tests/worker/mapping/test_clouds.h"
#include "worker/io/bag/ros_messages.h"
#include "worker/io/cloud/scan_file.h"
#include "worker/mapping/deskew.h"

namespace keel::io {
namespace {

using proto::PointTimeSpec;
using proto::TimeReference;
using proto::TimeUnit;
using testing::expect_error;
using testing::TempDir;

constexpr TimeNs kScanStart = 1700000000123456789LL;  // odd ns: exercises every carry
constexpr double kSweepS = 0.1;

// Exact firing times (ns) and the points in the sensor frame at those times.
struct Sweep {
  std::vector<TimeNs> t_ns;
  std::vector<Eigen::Vector3f> xyz;
};

Sweep make_sweep(size_t n) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-20.0f, 20.0f);
  Sweep s;
  for (size_t i = 0; i < n; ++i) {
    // Uneven spacing with odd nanoseconds, the last point at the end of the sweep.
    s.t_ns.push_back(
        kScanStart +
        static_cast<TimeNs>(std::llround(kSweepS * 1e9 * std::pow(double(i) / (n - 1), 1.3))) +
        (i == 0 || i == n - 1 ? 0 : static_cast<TimeNs>(i % 97)));
    s.xyz.emplace_back(u(rng), u(rng), 0.1f * u(rng));
  }
  return s;
}

// The sweep as a cloud stamped at `stamp_ns`: offsets are float32 seconds from it.
PointCloud as_cloud(const Sweep& s, TimeNs stamp_ns) {
  PointCloud c;
  c.t_ns = stamp_ns;
  c.xyz = s.xyz;
  for (TimeNs t : s.t_ns) c.time_s.push_back(static_cast<float>(ns_to_seconds(t - stamp_ns)));
  return c;
}

mapping::TransformTree moving_tree() {
  const double t0 = ns_to_seconds(kScanStart);
  mapping::TransformTree tree(mapping::testing::sample_trajectory(
      t0 - 1.0, t0 + 1.0, 0.01, Eigen::Vector3d(1.5, 2.0, 0.1), 0.8));
  tree.set_extrinsic("lidar",
                     make_pose(Eigen::Quaterniond(Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitX())),
                               Eigen::Vector3d(0.3, -0.1, 0.4)));
  return tree;
}

// Deskewed points in the world frame (double), whatever stamp the scan is expressed at.
std::vector<Eigen::Vector3d> deskew_to_world(PointCloud cloud) {
  const mapping::TransformTree tree = moving_tree();
  const Pose3 T_world_sensor = mapping::deskew_scan(tree, "lidar", cloud);
  std::vector<Eigen::Vector3d> out;
  for (const auto& p : cloud.xyz) out.push_back(T_world_sensor * p.cast<double>());
  return out;
}

struct Convention {
  const char* name;
  PointTimeSpec spec;
  FieldType type;
  bool stamp_at_end;
  double tolerance_m;
};

std::vector<Convention> conventions() {
  auto split = [](TimeReference reference) {
    PointTimeSpec spec{"time_sec", TimeUnit::kSeconds, reference};
    spec.nsec_field = "time_nsec";
    return spec;
  };
  return {
      {"velodyne",
       {"time", TimeUnit::kSeconds, TimeReference::kScanStart},
       FieldType::kFloat32,
       false,
       0.0},
      {"ouster",
       {"t", TimeUnit::kNanoseconds, TimeReference::kScanStart},
       FieldType::kUint32,
       false,
       0.0},
      {"livox_hesai",
       {"timestamp", TimeUnit::kSeconds, TimeReference::kAbsolute},
       FieldType::kFloat64,
       false,
       7e-6},
      {"absolute_ns",
       {"timestamp", TimeUnit::kNanoseconds, TimeReference::kAbsolute},
       FieldType::kUint64,
       false,
       0.0},
      {"split_absolute", split(TimeReference::kAbsolute), FieldType::kUint32, false, 0.0},
      {"split_absolute_end", split(TimeReference::kAbsolute), FieldType::kUint32, true, 3.5e-6},
      {"split_relative_end", split(TimeReference::kScanEnd), FieldType::kInt32, true, 3.5e-6},
      {"velodyne_end",
       {"time", TimeUnit::kSeconds, TimeReference::kScanEnd},
       FieldType::kFloat32,
       true,
       3.5e-6},
      {"ouster_end_int",
       {"t", TimeUnit::kNanoseconds, TimeReference::kScanEnd},
       FieldType::kInt32,
       true,
       3.5e-6},
  };
}

ScanReadOptions read_options(const PointTimeSpec& spec) {
  ScanReadOptions o;
  o.point_time = spec;
  o.sweep_period_s = kSweepS;
  return o;
}

template <typename T>
void put(uint8_t* p, T value) {
  std::memcpy(p, &value, sizeof(T));
}

void put_number(uint8_t* p, FieldType type, long double value) {
  switch (type) {
    case FieldType::kInt32:
      return put<int32_t>(p, static_cast<int32_t>(value));
    case FieldType::kUint32:
      return put<uint32_t>(p, static_cast<uint32_t>(value));
    case FieldType::kUint64:
      return put<uint64_t>(p, static_cast<uint64_t>(value));
    case FieldType::kFloat32:
      return put<float>(p, static_cast<float>(value));
    case FieldType::kFloat64:
      return put<double>(p, static_cast<double>(value));
    default:
      FAIL() << "no such time type in these tests";
  }
}

// What a driver writes: the sweep's exact firing times in the convention, stamped at
// `stamp_ns` (integer values exact, floats the nearest to the true time).
PackedCloud pack_sweep(const Sweep& s, TimeNs stamp_ns, const PointTimeSpec& spec, FieldType type) {
  PackedCloud out;
  auto add = [&](const std::string& name, FieldType t) {
    out.fields.push_back({name, t, out.point_step, 1});
    out.point_step += field_size(t);
  };
  for (const char* axis : {"x", "y", "z"}) add(axis, FieldType::kFloat32);
  add(spec.field, type);
  if (spec.is_split()) add(spec.nsec_field, FieldType::kUint32);
  out.num_points = s.t_ns.size();
  out.data.assign(out.num_points * out.point_step, 0);
  const bool absolute = spec.reference == TimeReference::kAbsolute;
  for (size_t i = 0; i < out.num_points; ++i) {
    uint8_t* record = out.data.data() + i * out.point_step;
    for (int a = 0; a < 3; ++a) put<float>(record + 4 * a, s.xyz[i][a]);
    uint8_t* p = record + out.fields[3].offset;
    const TimeNs t = absolute ? s.t_ns[i] : s.t_ns[i] - stamp_ns;
    if (spec.is_split()) {
      TimeNs sec = t / 1000000000, nsec = t % 1000000000;
      if (nsec < 0) nsec += 1000000000, --sec;
      put_number(p, type, sec);
      put<uint32_t>(record + out.fields[4].offset, static_cast<uint32_t>(nsec));
    } else if (type == FieldType::kFloat32 || type == FieldType::kFloat64) {
      // Seconds: whole and fraction in long double, so only the final cast rounds.
      const long double t_s = static_cast<long double>(t / 1000000000) +
                              static_cast<long double>(t % 1000000000) * 1e-9L;
      put_number(p, type, absolute ? t_s : static_cast<long double>(ns_to_seconds(t)));
    } else {
      put_number(p, type, t);  // nanoseconds
    }
  }
  return out;
}

// The records as a binary PCD file, as a recording tool would save them.
void write_pcd_records(const std::filesystem::path& path, const PackedCloud& packed) {
  std::string fields, sizes, types, counts;
  for (const auto& f : packed.fields) {
    fields += " " + f.name;
    sizes += " " + std::to_string(field_size(f.type));
    types += f.type == FieldType::kFloat32 || f.type == FieldType::kFloat64
                 ? " F"
                 : (f.type == FieldType::kInt32 || f.type == FieldType::kInt64 ? " I" : " U");
    counts += " 1";
  }
  std::ofstream out(path, std::ios::binary);
  out << "VERSION .7\nFIELDS" << fields << "\nSIZE" << sizes << "\nTYPE" << types << "\nCOUNT"
      << counts << "\nWIDTH " << packed.num_points << "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS "
      << packed.num_points << "\nDATA binary\n";
  out.write(reinterpret_cast<const char*>(packed.data.data()),
            static_cast<std::streamsize>(packed.data.size()));
}

// The packed records as a sensor_msgs/PointCloud2 (one row), as the bag readers see them.
PointCloud via_point_cloud2(const PackedCloud& packed, TimeNs stamp_ns,
                            const ScanReadOptions& options) {
  const uint8_t kRosType[] = {1, 2, 3, 4, 5, 6, 0, 0, 7, 8};  // FieldType -> PointField
  PointCloud2View msg;
  msg.height = 1;
  msg.width = static_cast<uint32_t>(packed.num_points);
  msg.point_step = static_cast<uint32_t>(packed.point_step);
  msg.row_step = msg.point_step * msg.width;
  msg.data = packed.data.data();
  msg.data_size = packed.data.size();
  for (const auto& f : packed.fields)
    msg.fields.push_back(
        {f.name, static_cast<uint32_t>(f.offset), kRosType[static_cast<int>(f.type)], 1});
  return unpack_point_cloud2(msg, stamp_ns, options, "test.bag: topic '/points' message 0");
}

void expect_points_near(const std::vector<Eigen::Vector3d>& reference,
                        const std::vector<Eigen::Vector3d>& got, double tolerance_m,
                        const std::string& what) {
  ASSERT_EQ(reference.size(), got.size()) << what;
  double worst = 0.0;
  for (size_t i = 0; i < got.size(); ++i) worst = std::max(worst, (got[i] - reference[i]).norm());
  EXPECT_LE(worst, tolerance_m) << what;
  if (tolerance_m == 0.0) {
    for (size_t i = 0; i < got.size(); ++i) ASSERT_EQ(got[i], reference[i]) << what << " " << i;
  }
}

TEST(PointTimeConventions, DeskewEqualsTheReferenceDeskew) {
  TempDir dir;
  const Sweep sweep = make_sweep(3000);
  const std::vector<Eigen::Vector3d> reference = deskew_to_world(as_cloud(sweep, kScanStart));
  // The sweep moves points by centimetres: the comparison below is not trivially met.
  {
    PointCloud still = as_cloud(sweep, kScanStart);
    still.time_s.clear();
    const auto undeskewed = deskew_to_world(still);
    EXPECT_GT((undeskewed.back() - reference.back()).norm(), 0.05);
  }
  for (const Convention& c : conventions()) {
    const TimeNs stamp_ns = c.stamp_at_end ? sweep.t_ns.back() : kScanStart;
    const PackedCloud packed = pack_sweep(sweep, stamp_ns, c.spec, c.type);
    const ScanReadOptions options = read_options(c.spec);

    const auto file = dir.path() / (std::string(c.name) + ".pcd");
    write_pcd_records(file, packed);
    const PointCloud from_file = read_scan_file(file, stamp_ns, options);
    if (c.stamp_at_end) {
      EXPECT_LE(*std::max_element(from_file.time_s.begin(), from_file.time_s.end()), 0.0f)
          << c.name;
    }
    expect_points_near(reference, deskew_to_world(from_file), c.tolerance_m,
                       std::string(c.name) + " scan file");
    if (c.type == FieldType::kUint64) continue;  // PointField has no 64-bit integers
    expect_points_near(reference, deskew_to_world(via_point_cloud2(packed, stamp_ns, options)),
                       c.tolerance_m, std::string(c.name) + " PointCloud2");
  }
}

TEST(PointTimeConventions, SplitTimeIsCombinedExactlyInNanoseconds) {
  const Sweep sweep = make_sweep(50);
  PointTimeSpec spec{"sec", TimeUnit::kSeconds, TimeReference::kAbsolute};
  spec.nsec_field = "nsec";
  PointCloud cloud = as_cloud(sweep, kScanStart);
  // Offsets exact in float32 ns: the written integers are then exactly the firing times.
  for (size_t i = 0; i < cloud.size(); ++i) cloud.time_s[i] = static_cast<float>(i) * 0.001f;
  const PackedCloud packed = pack_cloud(cloud, PointTimeEncoding{spec, FieldType::kUint32});
  const PackedCloudView view = packed.view();  // find() points into this view's fields
  const PackedField& sec = *view.find("sec");
  const auto offsets = point_time_offsets(view, sec, kScanStart, spec, kSweepS, "split.pcd");
  for (size_t i = 0; i < cloud.size(); ++i) {
    const TimeNs expected_ns = std::llround(double(cloud.time_s[i]) * 1e9);
    EXPECT_EQ(std::llround(offsets[i] * 1e9), expected_ns) << i;
  }
}

TEST(PointTimeConventions, AbsoluteFloat64KeepsSubMicrosecondPrecision) {
  // One point per 10 ns step across a second boundary: float64 epoch seconds resolve 238 ns.
  PackedCloud packed;
  packed.fields = {{"x", FieldType::kFloat32, 0, 1},
                   {"y", FieldType::kFloat32, 4, 1},
                   {"z", FieldType::kFloat32, 8, 1},
                   {"timestamp", FieldType::kFloat64, 12, 1}};
  packed.point_step = 20;
  const TimeNs stamp_ns = 1700000000999990000LL;
  std::vector<TimeNs> truth;
  for (int i = 0; i < 5000; ++i) truth.push_back(stamp_ns + 17LL * i);
  packed.num_points = truth.size();
  packed.data.assign(packed.num_points * packed.point_step, 0);
  for (size_t i = 0; i < truth.size(); ++i) {
    // The nearest float64 to the true epoch second, from exact integer parts.
    const long double t = static_cast<long double>(truth[i] / 1000000000) +
                          static_cast<long double>(truth[i] % 1000000000) * 1e-9L;
    const double value = static_cast<double>(t);
    std::memcpy(packed.data.data() + i * packed.point_step + 12, &value, 8);
  }
  const PointTimeSpec spec{"timestamp", TimeUnit::kSeconds, TimeReference::kAbsolute};
  const auto offsets =
      point_time_offsets(packed.view(), packed.fields[3], stamp_ns, spec, kSweepS, "abs.pcd");
  double worst_s = 0.0;
  for (size_t i = 0; i < truth.size(); ++i)
    worst_s = std::max(worst_s, std::abs(offsets[i] - ns_to_seconds(truth[i] - stamp_ns)));
  EXPECT_LE(worst_s, 0.5 * std::ldexp(1.0, -22) + 1e-12);  // half an ulp of 1.7e9 s
}

TEST(PointTimeConventions, WrongReferenceOrMissingFieldNamesTheFit) {
  const Sweep sweep = make_sweep(100);
  const PointCloud at_end = as_cloud(sweep, sweep.t_ns.back());
  const PointTimeSpec velodyne{"time", TimeUnit::kSeconds, TimeReference::kScanStart};
  // 2 sweeps late: the stamp marks neither end.
  PointCloud late = at_end;
  for (float& t : late.time_s) t -= 0.2f;
  const PackedCloud packed_late =
      pack_cloud(late, PointTimeEncoding{velodyne, FieldType::kFloat32});
  expect_error(
      [&] {
        point_time_offsets(packed_late.view(), *packed_late.view().find("time"), 0, velodyne,
                           kSweepS, "scans/000001.pcd");
      },
      {"scans/000001.pcd", "field 'time'", "reference scan_start", "more than a sweep",
       "before the stamp"});
  // Declared scan_end with offsets after the stamp.
  PointCloud at_start = as_cloud(sweep, kScanStart);
  for (float& t : at_start.time_s) t += 0.15f;
  PointTimeSpec end = velodyne;
  end.reference = TimeReference::kScanEnd;
  const PackedCloud packed_after =
      pack_cloud(at_start, PointTimeEncoding{end, FieldType::kFloat32});
  expect_error(
      [&] {
        point_time_offsets(packed_after.view(), *packed_after.view().find("time"), 0, end, kSweepS,
                           "bag: topic '/points' message 3");
      },
      {"topic '/points' message 3", "reference scan_end", "after the stamp"});
  // Split absolute fields declared relative: they look like absolute stamps.
  PointTimeSpec split{"s", TimeUnit::kSeconds, TimeReference::kAbsolute};
  split.nsec_field = "ns";
  const PackedCloud packed_split =
      pack_cloud(as_cloud(sweep, kScanStart), PointTimeEncoding{split, FieldType::kUint32});
  PointTimeSpec as_relative = split;
  as_relative.reference = TimeReference::kScanStart;
  expect_error(
      [&] {
        point_time_offsets(packed_split.view(), *packed_split.view().find("s"), kScanStart,
                           as_relative, kSweepS, "x.pcd");
      },
      {"x.pcd", "fields 's' (uint32) + 'ns' (uint32)", "split seconds + nanoseconds",
       "reference absolute?"});
  // Split relative offsets declared absolute: they fit scan_start.
  PointCloud relative_cloud = as_cloud(sweep, kScanStart);
  PointTimeSpec split_rel = split;
  split_rel.reference = TimeReference::kScanStart;
  const PackedCloud packed_rel =
      pack_cloud(relative_cloud, PointTimeEncoding{split_rel, FieldType::kUint32});
  expect_error(
      [&] {
        point_time_offsets(packed_rel.view(), *packed_rel.view().find("s"), kScanStart, split,
                           kSweepS, "y.pcd");
      },
      {"y.pcd", "reference scan_start?"});
  // The nanoseconds field missing.
  PointTimeSpec missing = split;
  missing.nsec_field = "nanos";
  expect_error(
      [&] { unpack_cloud(packed_split.view(), kScanStart, read_options(missing), "z.pcd"); },
      {"z.pcd", "no nanoseconds field 'nanos'", "fields: x y z s ns"});
}

}  // namespace
}  // namespace keel::io
