#include "worker/inspect/inspect_options.h"

namespace keel::inspect {

nlohmann::json InspectOptions::to_json() const {
  return {{"tau_m", tau_m},
          {"tau_noise_sigmas", tau_noise_sigmas},
          {"dbscan_eps_m", dbscan_eps_m},
          {"dbscan_min_pts", dbscan_min_pts},
          {"min_shape_views", min_shape_views},
          {"alpha_m", alpha_m},
          {"view_range_m", view_range_m},
          {"max_behind_vertex_m", max_behind_vertex_m},
          {"top_site_noise_sigmas", top_site_noise_sigmas},
          {"top_spacings", top_spacings}};
}

}  // namespace keel::inspect
