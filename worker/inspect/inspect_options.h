// Options of model-assisted visual mapping (seed 001, section 3), defaults from the paper.
#pragma once

#include <nlohmann/json.hpp>

namespace keel::inspect {

struct InspectOptions {
  // Line 6 of Algorithm 1: a feature is clustered when its structural deviation |h| > tau, with
  // tau = max(tau_m, |median h| + tau_noise_sigmas * robust sigma of h about that median, over
  // on-model features; tau_m alone when tau_noise_sigmas is 0), see deviation_threshold.h. tau_m =
  // 0 is the paper's preferred setting (Section 4.2.2, Fig. 21(b)); 0.06 m its setting where false
  // positives matter (Fig. 21(c)), which misses bumps whose features mostly stand 1-3 cm off the
  // hull.
  double tau_m = 0.0;
  // Not in the paper: how many noise sigmas of h tau must clear, so that clean hull (whose h is
  // reconstruction noise) yields no shape. The noise is heavier-tailed than a Gaussian: features
  // seen from few views (ends of lanes) scatter more, and on keel-sim hauv-hull (exact tracks,
  // sigma ~1.4 mm) clean-hull features reached 5 sigma in clusters of 3-4, so 8.
  double tau_noise_sigmas = 8.0;
  // DBSCAN (line 11) over (f_x, f_y, d). The paper gives no radius. Every DBSCAN link (<= eps)
  // must stay shorter than the alpha disc's diameter (2 alpha_m), so that a cluster's alpha
  // shape is not torn apart by spacing DBSCAN accepted; within that, 0.14 rather than alpha_m
  // (0.12, the earlier value): keel-sim hauv-hull seed 8's 7.8 cm patch carries 5 texture blobs
  // (the fewest of the 40 objects of seeds 1-10, bench_texture) and its features above tau lie
  // in pairs 0.12-0.14 m apart in every view, so 0.12 never clustered three. Seeds 1-10 keep
  // no shape on clean hull at 0.14, and unseen seeds 11-16 too (docs/stage-options.md).
  double dbscan_eps_m = 0.14;
  // Section 4.2.1: "DBSCAN requires a minimum number of datapoints per cluster (... 3)".
  // Counts the point itself, as Ester et al. (1996) do.
  int dbscan_min_pts = 3;
  // Not in the paper: a shape (the per-view detections merged into one object, shape_report.h)
  // is kept only when Algorithm 1 found it in at least this many views; the rest are neither
  // fused nor reported. The standard a monocular feature must meet to be triangulated at all
  // (ba triangulation.min_monocular_views = 3): a single view's cluster can be three features
  // whose noise happens to agree in that view, while a structure on the hull stays in the
  // camera for ~10 images of a lane (2 Hz, 0.25 m/s, a footprint over 1 m wide).
  int min_shape_views = 3;
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
  // Not in the paper: a shape's height_sampling_sigma_m (how far its top may lie beyond its
  // highest feature, top_sampling.h) is the mean of top_spacings spacings between the highest
  // sampling sites, heights within top_site_noise_sigmas deviation-noise sigmas of a higher one
  // being one site. On keel-sim hauv-hull the top lay within 3 of these sigmas of the highest
  // feature for 67 of 73 objects (92 %; 89 % for an exponential gap, docs/stage-options.md).
  double top_site_noise_sigmas = 3.0;
  int top_spacings = 4;

  nlohmann::json to_json() const;
};

}  // namespace keel::inspect
