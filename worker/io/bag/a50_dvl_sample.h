// The DvlSample of one Water Linked A50 message (a50_messages.h), by the rule of
// docs/mission-format.md "DVLs that publish beams":
//  - velocity_valid: the published velocity (must be finite) and its figure of merit;
//  - otherwise, with >= 3 valid beams: the velocity solved from the beams' radial velocities
//    by least squares (dvl_beams.h, the A50's beam directions; equal beam weights, the driver
//    publishes no per-beam noise), beams_used = the beams it came from;
//  - otherwise: an invalid sample (valid = false), which the stages leave out.
#pragma once

#include <string>

#include "worker/io/bag/a50_messages.h"
#include "worker/io/stream_samples.h"

namespace keel::io {

// `what` names the message in errors ("<bag>: topic '/dvl/data' message 17"); fails on a
// non-finite valid velocity, or a valid beam whose id is not a transducer 0-3 or repeats one.
DvlSample a50_dvl_sample(const A50Dvl& message, TimeNs t_ns, const std::string& what);

}  // namespace keel::io
