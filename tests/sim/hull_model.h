// A procedural, ship-like hull (the "CAD model" of seed 001's hull missions), the foreign
// objects attached to the real hull (a cylinder of known height, biofouling patches) and
// the hull's visual landmarks.
//
// CAD frame: x forward (bow), y to port, z up, waterline at z = 0, keel at z = -draft.
#pragma once

#include <Eigen/Geometry>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/pose.h"
#include "core/triangle_mesh.h"

namespace keel::sim {

struct HullOptions {
  double length_m = 40.0;
  double beam_m = 10.0;
  double draft_m = 4.0;
  double freeboard_m = 1.5;
  double section_exponent = 6.0;  // superellipse exponent: flat bottom, round bilge
  double end_xi = 0.98;           // the mesh stops at |2x/L| = end_xi and is capped there
  int length_segments = 160;
  int section_segments = 64;  // waterline to waterline around the keel
  int freeboard_segments = 4;
};

struct SurfacePoint {
  Eigen::Vector3d p;
  Eigen::Vector3d normal;  // outward unit normal
};

// The smooth hull surface below the waterline. Sections are superellipses
// |y/(B/2 f(xi))|^m + |z/T|^m = 1 with f the waterline taper; they are parameterised by
// normalised arc length sigma in [-1, 1]: -1 port waterline, 0 keel, +1 starboard waterline,
// so the mesh is evenly spaced around the bilge.
class HullShape {
 public:
  explicit HullShape(const HullOptions& options);
  const HullOptions& options() const { return options_; }
  // xi = 2x/L.
  SurfacePoint surface(double xi, double sigma) const;
  double taper(double xi) const;  // f(xi): half-breadth factor along the length

 private:
  Eigen::Vector3d point(double xi, double sigma) const;
  HullOptions options_;
  std::vector<double> arc_;  // normalised arc length at table_phi_
  std::vector<double> table_phi_;
};

// The closed CAD mesh (hull, transom caps, deck), faces counter-clockwise from outside.
TriangleMesh make_hull_mesh(const HullOptions& options);

struct ForeignObject {
  enum class Kind { kCylinder, kPatch };
  Kind kind = Kind::kCylinder;
  Eigen::Vector3d center;  // base centre on the real hull surface (world)
  Eigen::Vector3d axis;    // outward unit normal of the hull there (world)
  double radius_m = 0.0;
  double height_m = 0.0;  // how far the object stands out of the hull
  std::string kind_name() const { return kind == Kind::kCylinder ? "cylinder" : "patch"; }
};

// Triangle mesh of an object (its base sinks 1 cm into the hull so no gap shows).
TriangleMesh foreign_object_mesh(const ForeignObject& object);

struct Landmark {
  int64_t id = 0;
  Eigen::Vector3d p_world;
  Eigen::Vector3d normal_world;
  double radius_m = 0.03;
  double albedo = 0.1;
  bool on_cad = true;  // false: on a foreign object
};

// Landmarks scattered over the faces of `mesh` (world frame), `density_per_m2` on average,
// skipping faces whose normal points up more than max_normal_z (the deck) and, when `keep` is
// given, points it refuses.
std::vector<Landmark> scatter_landmarks(
    const TriangleMesh& mesh_world, double density_per_m2, double max_normal_z, bool on_cad,
    int64_t first_id, uint64_t seed, uint64_t stream_index,
    const std::function<bool(const Eigen::Vector3d&)>& keep = nullptr);

TriangleMesh transform_mesh(const TriangleMesh& mesh, const Pose3& T);
void append_mesh(TriangleMesh* into, const TriangleMesh& mesh);
double mesh_signed_volume(const TriangleMesh& mesh);

}  // namespace keel::sim
