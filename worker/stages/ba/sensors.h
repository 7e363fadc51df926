// Step 1 of stage `ba`: its sensors (camera, DVL ranges, servo, depth) and the rig they make.
#pragma once

#include "proto/mission_manifest.h"
#include "worker/ba/ba_problem.h"
#include "worker/io/mission_reader.h"
#include "worker/stages/ba/options.h"

namespace keel::pipeline {

struct BaSensors {
  const proto::SensorSpec* camera = nullptr;
  const proto::SensorSpec* dvl = nullptr;
  const proto::SensorSpec* servo = nullptr;
  const proto::SensorSpec* depth = nullptr;  // null when unused or absent
};

// The named sensors, else the first of each type (depth: the first depth stream, none when
// `use_depth` is false); the camera and the DVL must ride the servo's tray.
BaSensors pick_sensors(const io::MissionReader& reader, const BaStageOptions& options);

// The camera intrinsics and the tray's geometry from the extrinsics (docs/mission-format.md
// "Servo trays": the tray turns about the servo's `axis` through the servo frame, so
// T_servo_sensor = T_body_servo^-1 T_body_sensor(0)).
ba::BaRig build_rig(const io::MissionReader& reader, const BaSensors& sensors);

}  // namespace keel::pipeline
