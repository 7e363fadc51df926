#include "worker/io/bag/a50_messages.h"

#include <string>

#include "worker/io/bag/bag_format_error.h"
#include "worker/io/bag/cdr_reader.h"
#include "worker/io/bag/ros1_reader.h"

namespace keel::io {
namespace {

constexpr size_t kBeamBytesRos1 = 8 + 4 * 8 + 1;  // id, 4 float64, bool

void check_nanoseconds(uint64_t nsec) {
  if (nsec >= 1000000000u)
    throw BagFormatError("field 'header.stamp.nsec' is " + std::to_string(nsec) +
                         ", expected below 1e9");
}

}  // namespace

A50Dvl decode_a50_ros1(const uint8_t* data, size_t size) {
  Ros1Reader r(data, size);
  A50Dvl m;
  r.u32("header.seq");
  const uint32_t sec = r.u32("header.stamp.sec");
  const uint32_t nsec = r.u32("header.stamp.nsec");
  check_nanoseconds(nsec);
  m.stamp_ns = static_cast<TimeNs>(sec) * 1000000000 + nsec;
  r.string("header.frame_id");
  m.time_ms = r.f64("time");
  for (int i = 0; i < 3; ++i) m.velocity_m_s(i) = r.f64("velocity");
  m.fom_m_s = r.f64("fom");
  m.altitude_m = r.f64("altitude");
  const uint32_t beams = r.sequence("beams", kBeamBytesRos1);
  m.beams.resize(beams);
  for (A50Beam& b : m.beams) {
    b.id = r.read<int64_t>("beams[].id");
    b.velocity_m_s = r.f64("beams[].velocity");
    b.distance_m = r.f64("beams[].distance");
    b.rssi_dbm = r.f64("beams[].rssi");
    b.nsd_dbm = r.f64("beams[].nsd");
    b.valid = r.read<uint8_t>("beams[].valid") != 0;
  }
  m.velocity_valid = r.read<uint8_t>("velocity_valid") != 0;
  m.status = r.read<int64_t>("status");
  r.string("form");
  return m;
}

A50Dvl decode_a50_ros2(const uint8_t* data, size_t size) {
  CdrReader cdr(data, size);
  A50Dvl m;
  const int32_t sec = cdr.i32("header.stamp.sec");
  const uint32_t nanosec = cdr.u32("header.stamp.nanosec");
  check_nanoseconds(nanosec);
  m.stamp_ns = static_cast<TimeNs>(sec) * 1000000000 + nanosec;
  cdr.string("header.frame_id");
  m.time_ms = cdr.f64("time");
  for (int i = 0; i < 3; ++i) m.velocity_m_s(i) = cdr.f64("velocity");
  m.fom_m_s = cdr.f64("fom");
  for (double& c : m.covariance_m2_s2) c = cdr.f64("covariance");
  m.has_covariance = true;
  m.altitude_m = cdr.f64("altitude");
  const uint32_t beams = cdr.sequence("beams", 8 + 4 * 8 + 1);
  m.beams.resize(beams);
  for (A50Beam& b : m.beams) {
    b.id = static_cast<int64_t>(cdr.u64("beams[].id"));
    b.velocity_m_s = cdr.f64("beams[].velocity");
    b.distance_m = cdr.f64("beams[].distance");
    b.rssi_dbm = cdr.f64("beams[].rssi");
    b.nsd_dbm = cdr.f64("beams[].nsd");
    b.valid = cdr.boolean("beams[].valid");
  }
  m.velocity_valid = cdr.boolean("velocity_valid");
  m.status = static_cast<int64_t>(cdr.u64("status"));
  return m;
}

}  // namespace keel::io
