// Options of model-assisted visual mapping (seed 001, section 3), defaults from the paper.
#pragma once

#include <nlohmann/json.hpp>

namespace keel::inspect {

struct InspectOptions {
  // Line 6 of Algorithm 1: a feature is clustered when its structural deviation |h| > tau_m.
  // Section 4.2.2 uses 0 m for the most detail (Fig. 21(b)) and 0.06 m where false positives
  // matter (Fig. 21(c)). shapes.json lists foreign objects for an inspector, so the default is
  // 0.06 m: just above the +-5 cm label decision boundary of the BA max-mixture (Fig. 7,
  // sigma0 = 1 m, sigma1 = 0.02 m), i.e. only features the BA let leave the surface count.
  double tau_m = 0.06;
  // DBSCAN (line 11) over (f_x, f_y, d). The paper gives no radius; we use alpha_m so that every
  // DBSCAN link (<= eps) is shorter than the alpha disc's diameter and a cluster's alpha shape
  // is not torn apart by spacing DBSCAN accepted.
  double dbscan_eps_m = 0.12;
  // Section 4.2.1: "DBSCAN requires a minimum number of datapoints per cluster (... 3)".
  // Counts the point itself, as Ester et al. (1996) do.
  int dbscan_min_pts = 3;
  // Section 3.2: "a fixed value of 12 cm". The radius of the alpha disc; CGAL's Alpha_shape_2
  // takes its square (0.0144 m^2), see alpha_shape_25d.h.
  double alpha_m = 0.12;
  // nearby_vertices() of Algorithm 2 (section 3.3): "we conservatively use 5 m".
  double view_range_m = 5.0;
  // Section 3.3: vertices move only if the *segment* camera centre -> vertex meets a shape, so
  // only structure in front of the CAD surface (protrusions) is fused: 0 m, the paper's choice.
  // A positive value lets the ray run that far beyond the vertex so that structure behind the
  // surface (dents, missing material; h < -tau) is fused too.
  double max_behind_vertex_m = 0.0;

  nlohmann::json to_json() const;
};

}  // namespace keel::inspect
