#include "worker/io/bag/a50_dvl_sample.h"

#include <cmath>

#include "worker/io/bag/ros_messages.h"
#include "worker/io/dvl_beams.h"
#include "worker/io/io_error.h"

namespace keel::io {

DvlSample a50_dvl_sample(const A50Dvl& message, TimeNs t_ns, const std::string& what) {
  DvlSample s;
  s.t_ns = t_ns;
  if (message.velocity_valid) {
    const Eigen::Vector3d& v = message.velocity_m_s;
    s.velocity_m_s = finite_vector(v.x(), v.y(), v.z(), what + " velocity");
    if (std::isfinite(message.fom_m_s) && message.fom_m_s >= 0.0) s.fom_m_s = message.fom_m_s;
    return s;
  }
  const auto directions = a50_beam_directions();
  std::vector<BeamMeasurement> beams;
  bool seen[4] = {false, false, false, false};
  for (size_t k = 0; k < message.beams.size(); ++k) {
    const A50Beam& beam = message.beams[k];
    if (!beam.valid) continue;
    const std::string field = what + " beams[" + std::to_string(k) + "]";
    if (beam.id < 0 || beam.id > 3)
      throw IoError(field + ".id is " + std::to_string(beam.id) +
                    "; the A50's transducers are 0-3");
    if (seen[beam.id])
      throw IoError(field + ".id " + std::to_string(beam.id) + " repeats an earlier beam");
    seen[beam.id] = true;
    beams.push_back({directions[beam.id], beam.velocity_m_s, 1.0, true});
  }
  const BeamSolution solution = solve_beam_velocity(beams);
  s.velocity_m_s = message.velocity_m_s;
  s.valid = solution.valid;
  if (solution.valid) {
    s.velocity_m_s = solution.velocity_m_s;
    s.beams_used = solution.beams_used;
  }
  return s;
}

}  // namespace keel::io
