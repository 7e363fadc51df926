#include "tests/fuzz/file_seeds.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>

#include "server/bundle_check.h"
#include "tests/fuzz/csv_streams.h"
#include "tests/server/tar_builder.h"
#include "worker/io/loop_closures.h"
#include "worker/io/mesh/mesh_ply_writer.h"
#include "worker/io/mesh/mesh_reader.h"
#include "worker/io/cloud/scan_file.h"
#include "worker/io/tum.h"
#include "worker/main/trajectory_source.h"

namespace fs = std::filesystem;

namespace keel::fuzz {
namespace {

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void write_bytes(const fs::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

// Reads `file` with `check` (which throws when Keel refuses it), then writes its bytes as a
// seed for each selector.
int add_seed(const fs::path& dir, const std::string& name, const fs::path& file,
             const std::function<void(const fs::path&)>& check,
             std::initializer_list<char> selectors) {
  try {
    check(file);
  } catch (const std::exception& e) {
    throw std::runtime_error("seed " + name + " is not read by Keel: " + e.what());
  }
  const std::string bytes = read_bytes(file);
  fs::remove(file);
  for (char s : selectors) write_bytes(dir / (name + "-" + std::to_string(int(s))), s + bytes);
  return static_cast<int>(selectors.size());
}

int add_text_seed(const fs::path& dir, const std::string& name, const std::string& extension,
                  const std::string& text, const std::function<void(const fs::path&)>& check,
                  std::initializer_list<char> selectors) {
  const fs::path file = dir / (".candidate" + extension);
  write_bytes(file, text);
  return add_seed(dir, name, file, check, selectors);
}

PointCloud sweep(bool with_non_finite) {
  PointCloud cloud;
  for (int i = 0; i < 8; ++i) {
    cloud.xyz.emplace_back(0.5f * i, std::sin(0.3f * i), -1.0f + 0.1f * i);
    cloud.intensity.push_back(10.0f * i);
    cloud.ring.push_back(static_cast<uint16_t>(i % 4));
    cloud.time_s.push_back(0.001f * i);
  }
  if (with_non_finite) cloud.xyz[3].y() = std::numeric_limits<float>::quiet_NaN();
  cloud.t_ns = 1700000000000000000LL;
  return cloud;
}

// Big-endian bytes of a value (PLY binary_big_endian).
template <typename T>
std::string big_endian(T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  std::string out(bytes, sizeof(T));
  return std::string(out.rbegin(), out.rend());
}

std::string little_endian_u32(uint32_t v) {
  std::string out(4, '\0');
  for (int i = 0; i < 4; ++i) out[i] = static_cast<char>((v >> (8 * i)) & 0xff);
  return out;
}

std::string little_endian_f32(float v) {
  std::string out(4, '\0');
  std::memcpy(out.data(), &v, 4);  // x86 and ARM are little endian; fuzz_seeds runs there
  return out;
}

const char* const kAsciiPlyMesh =
    "ply\nformat ascii 1.0\ncomment fuzz seed\nobj_info scanned hull\n"
    "element vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
    "property float nx\nproperty float ny\nproperty float nz\n"
    "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty float quality\n"
    "element face 2\nproperty list uchar int vertex_indices\n"
    "element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n"
    "0 0 0 0 0 1 255 0 0 0.5\n1 0 0 0 0 1 0 255 0 0.25\n1 1 0.5 0 0 1 0 0 255 1\n"
    "0 1 0 0 0 1 9 9 9 0\n0.5 0.5 1e-3 0 0 1 1 2 3 7\n"
    "4 0 1 2 3\n3 0 2 4\n0 2\n";

std::string big_endian_ply_mesh() {
  std::string ply =
      "ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty double x\n"
      "property double y\nproperty double z\nelement face 2\n"
      "property list uchar uint vertex_index\nend_header\n";
  const double xyz[4][3] = {{0, 0, 0}, {2, 0, 0}, {2, 1, 0.25}, {0, 1, 0}};
  for (const auto& v : xyz)
    for (double c : v) ply += big_endian(c);
  const uint32_t faces[2][3] = {{0, 1, 2}, {0, 2, 3}};
  for (const auto& f : faces) {
    ply += '\3';
    for (uint32_t i : f) ply += big_endian(i);
  }
  return ply;
}

const char* const kObj =
    "# fuzz seed\nmtllib hull.mtl\no hull\nv 0 0 0\nv 1 0 0\nv 1 1 0.5\nv 0 1 0 1.0\n"
    "vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\ng plate\nusemtl steel\ns off\n"
    "f 1 2 3\nf 1/1 3/3 4/2\nf -4/1/1 -3/2/1 -2/3/1 -1/1/1\nf 1//1 2//1 4//1\nl 1 2\n";

const char* const kAsciiStl =
    "solid plate\n"
    "  facet normal 0 0 1\n    outer loop\n      vertex 0 0 0\n      vertex 1 0 0\n"
    "      vertex 1 1 0\n    endloop\n  endfacet\n"
    "  facet normal 0 0 1\n    outer loop\n      vertex 0 0 0\n      vertex 1 1 0\n"
    "      vertex 0 1 0\n    endloop\n  endfacet\nendsolid plate\n";

// Binary STL whose 80-byte header starts with "solid", as many CAD exporters write it.
std::string binary_stl() {
  std::string stl = "solid exported by a CAD tool";
  stl.resize(80, ' ');
  const float triangles[2][3][3] = {{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}},
                                    {{0, 0, 0}, {1, 1, 0}, {0, 1, 0}}};
  stl += little_endian_u32(2);
  for (const auto& t : triangles) {
    for (float n : {0.0f, 0.0f, 1.0f}) stl += little_endian_f32(n);
    for (const auto& v : t)
      for (float c : v) stl += little_endian_f32(c);
    stl += std::string(2, '\0');  // attribute byte count
  }
  return stl;
}

const char* const kOff =
    "OFF\n# fuzz seed\n5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 1\n4 0 1 2 3\n3 0 2 4\n";
const char* const kCoff =
    "COFF\n4 2 5\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n1 1 0 0 0 255 255\n0 1 0 9 9 9 255\n"
    "3 0 1 2 0.5 0.5 0.5\n3 0 2 3\n";

const char* const kTum =
    "# timestamp tx ty tz qx qy qz qw\n"
    "1700000000.000000 0 0 0 0 0 0 1\n"
    "1700000000.100000 0.1 0.0 -0.01 0 0 0.0499792 0.9987503\n"
    "1700000000.200000 0.2 0.01 -0.02 0 0 0.0998334 0.9950042\n"
    "1700000000.300000 0.3 0.03 -0.02 0.0010 0 0.1494381 0.9887711\n";

const char* const kKitti =
    "1 0 0 0 0 1 0 0 0 0 1 0\n"
    "0.9950042 -0.0998334 0 0.5 0.0998334 0.9950042 0 0.05 0 0 1 0\n"
    "9.800666e-01 -1.986693e-01 0.000000e+00 1.000000e+00 1.986693e-01 9.800666e-01 "
    "0.000000e+00 1.500000e-01 0.000000e+00 0.000000e+00 1.000000e+00 -1.000000e-02\n";

struct CsvSeed {
  const char* name;
  char selector;  // fuzz_csv_streams: 0 imu, 1 dvl, 2 dvl ranges, 3 depth, 4 servo, 5 loops
  const char* text;
};

const CsvSeed kCsvSeeds[] = {
    {"imu.csv", 0,
     "t,wx,wy,wz,ax,ay,az\n1700000000.000,0.01,-0.02,0.003,0.1,0.2,9.81\n"
     "1700000000.005,0.011,-0.021,0.0031,0.12,0.19,9.79\n"},
    {"dvl.csv", 1,
     "t,vx,vy,vz,valid\n1700000000.0,0.5,0.01,-0.02,1\n1700000000.2,0,0,0,0\n"
     "1700000000.4,0.52,0.0,-0.01,1\n"},
    {"dvl_no_valid.csv", 1, "t,vx,vy,vz\n1700000000.0,0.5,0.01,-0.02\n1700000000.2,0.49,0.02,0\n"},
    {"dvl_ranges.csv", 2,
     "t,r0,r1,r2,r3\n1700000000.0,3.1,3.2,3.05,2.98\n"
     "1700000000.2,nan,3.3,3.1,nan\n"},
    {"depth.csv", 3, "t,depth\n1700000000.0,2.5\n1700000000.1,2.51\n"},
    {"servo.csv", 4, "t,angle\n1700000000.0,-0.5\n1700000000.1,0.25\n"},
};

}  // namespace

int write_csv_seeds(const fs::path& dir) {
  const auto read = [](char selector) {
    return [selector](const fs::path& f) { read_csv_stream(selector, f); };
  };
  int n = 0;
  for (const CsvSeed& seed : kCsvSeeds)
    n += add_text_seed(dir, seed.name, ".csv", seed.text, read(seed.selector), {seed.selector});
  io::LoopClosure loop;
  loop.t_i_ns = 1700000000000000000LL;
  loop.t_j_ns = 1700000042500000000LL;
  loop.T_body_i_body_j.translation() = Eigen::Vector3d(0.2, -0.1, 0.05);
  loop.sigma_t_m = 0.05;
  loop.sigma_r_rad = 0.01;
  const fs::path file = dir / ".candidate.csv";
  io::write_loop_closures(file, {loop, loop});
  return n + add_seed(dir, "loops.csv", file, read(5), {5});
}

int write_scan_seeds(const fs::path& dir) {
  using io::FieldType;
  using io::ScanEncoding;
  using proto::TimeReference;
  using proto::TimeUnit;
  struct Case {
    const char* name;
    ScanEncoding encoding;
    FieldType time_type;
    TimeUnit unit;
    TimeReference reference;
  };
  const Case cases[] = {
      {"ascii.pcd", ScanEncoding::kAscii, FieldType::kFloat32, TimeUnit::kSeconds,
       TimeReference::kScanStart},
      {"binary.pcd", ScanEncoding::kBinary, FieldType::kUint32, TimeUnit::kNanoseconds,
       TimeReference::kScanStart},
      {"compressed.pcd", ScanEncoding::kBinaryCompressed, FieldType::kFloat64, TimeUnit::kSeconds,
       TimeReference::kAbsolute},
      {"ascii.ply", ScanEncoding::kAscii, FieldType::kFloat64, TimeUnit::kMicroseconds,
       TimeReference::kScanStart},
      {"binary.ply", ScanEncoding::kBinary, FieldType::kFloat32, TimeUnit::kSeconds,
       TimeReference::kScanStart},
  };
  int n = 0;
  for (const Case& c : cases) {
    const bool pcd = fs::path(c.name).extension() == ".pcd";
    for (bool non_finite : {false, true}) {
      const fs::path file =
          dir / (std::string(".candidate") + fs::path(c.name).extension().string());
      io::write_scan_file(
          file, sweep(non_finite),
          {c.encoding, io::PointTimeEncoding{{"t", c.unit, c.reference}, c.time_type}});
      const std::string name = std::string(c.name) + (non_finite ? "-nan" : "");
      n += add_seed(dir, name, file, [](const fs::path& f) { (void)io::read_scan_file(f, 0); },
                    {static_cast<char>(pcd ? 0 : 1), static_cast<char>(pcd ? 2 : 3)});
    }
  }
  return n;
}

int write_mesh_seeds(const fs::path& dir) {
  const auto read = [](const fs::path& f) { (void)io::read_mesh(f); };
  int n = 0;
  n += add_text_seed(dir, "ascii.ply", ".ply", kAsciiPlyMesh, read, {0, 4});
  n += add_text_seed(dir, "big_endian.ply", ".ply", big_endian_ply_mesh(), read, {0, 4});
  TriangleMesh mesh;
  for (int i = 0; i < 4; ++i) mesh.vertices.emplace_back(i % 2, i / 2, 0.1 * i);
  mesh.faces = {{0, 1, 3}, {0, 3, 2}};
  for (bool double_positions : {false, true}) {
    const fs::path file = dir / ".candidate.ply";
    io::PlyMeshWriteOptions options;
    options.double_positions = double_positions;
    io::write_ply_mesh(file, mesh, {{"deviation", {0.0f, 0.1f, -0.2f, 0.3f}}}, options);
    n += add_seed(dir, double_positions ? "little_endian_double.ply" : "little_endian.ply", file,
                  read, {0, 4});
  }
  n += add_text_seed(dir, "mesh.obj", ".obj", kObj, read, {1});
  n += add_text_seed(dir, "ascii.stl", ".stl", kAsciiStl, read, {2});
  n += add_text_seed(dir, "binary.stl", ".stl", binary_stl(), read, {2});
  n += add_text_seed(dir, "mesh.off", ".off", kOff, read, {3});
  n += add_text_seed(dir, "colour.off", ".off", kCoff, read, {3});
  return n;
}

int write_bundle_seeds(const fs::path& dir) {
  using namespace server::testing;
  const std::string manifest = minimal_manifest("fuzz-seed");
  const std::vector<TarMember> plain = {tar_dir("./"), tar_file("./mission.yaml", manifest),
                                        tar_dir("cam0"), tar_file("cam0/000001.png", "\x89PNG\r\n"),
                                        tar_file("depth.csv", "t,depth\n0,1\n")};
  const std::vector<TarMember> links = {
      tar_file("mission.yaml", manifest),
      tar_dir("lidar"),
      tar_file("lidar/" + std::string(120, 'x') + "/scan_000001.pcd", "# .PCD v0.7\n"),
      tar_file("dvl/sub folder/with spaces.csv", "t,depth\n"),
      tar_symlink("latest", "lidar"),
      tar_symlink("lidar/up", "../mission.yaml"),
      tar_hardlink("copy.yaml", "mission.yaml")};
  const std::vector<TarMember> hostile = {tar_file("mission.yaml", manifest),
                                          tar_file("/etc/keel", "x"),
                                          tar_file("a/../../b", "x"),
                                          tar_symlink("out", "/etc"),
                                          tar_symlink("deep", "x/../../y"),
                                          tar_file("out/passwd", "x"),
                                          tar_hardlink("h", "../../etc/shadow"),
                                          {"dev", TarMember::Kind::kCharDevice, ""}};
  struct Bundle {
    const char* name;
    const std::vector<TarMember>* members;
    bool gzip;
    int format;
    bool accepted;
  };
  const Bundle bundles[] = {
      {"ustar.tar", &plain, false, ARCHIVE_FORMAT_TAR_USTAR, true},
      {"gnu.tar", &links, false, ARCHIVE_FORMAT_TAR_GNUTAR, true},
      {"pax.tar", &links, false, ARCHIVE_FORMAT_TAR_PAX_RESTRICTED, true},
      {"pax_full.tar", &plain, false, ARCHIVE_FORMAT_TAR_PAX_INTERCHANGE, true},
      {"gzip.tar", &plain, true, ARCHIVE_FORMAT_TAR_PAX_RESTRICTED, false},
      {"hostile_gnu.tar", &hostile, false, ARCHIVE_FORMAT_TAR_GNUTAR, false},
      {"hostile_pax.tar", &hostile, false, ARCHIVE_FORMAT_TAR_PAX_RESTRICTED, false},
  };
  int n = 0;
  for (const Bundle& b : bundles) {
    const fs::path file = dir / b.name;
    write_bytes(file, build_tar(*b.members, b.gzip, b.format));
    bool accepted = true;
    try {
      (void)server::check_mission_bundle(file);
    } catch (const server::BundleError&) {
      accepted = false;
    }
    if (accepted != b.accepted)
      throw std::runtime_error(std::string("seed ") + b.name +
                               (accepted ? " was accepted" : " was refused"));
    ++n;
  }
  return n;
}

int write_trajectory_seeds(const fs::path& dir) {
  int n = add_text_seed(dir, "poses.tum", ".tum", kTum,
                        [](const fs::path& f) { (void)io::read_tum(f); }, {0});
  n += add_text_seed(dir, "poses.kitti", ".txt", kKitti,
                     [](const fs::path& f) { (void)worker::read_kitti_poses(f); }, {1});
  return n;
}

}  // namespace keel::fuzz
