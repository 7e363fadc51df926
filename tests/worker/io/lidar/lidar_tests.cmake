# tests/worker/io/lidar: raw lidar packets. The check against nebula's decoded clouds reads
# KEEL_NEBULA_TESTDATA (nebula's src/nebula_velodyne folder; environment or cache).
set(KEEL_NEBULA_TESTDATA "" CACHE PATH "nebula's src/nebula_velodyne folder (decoder ground truth)")
keel_test(io/velodyne_packet SOURCES lidar/velodyne_packet_test.cc DEPS keel_lidar)
keel_test(io/velodyne_nebula SOURCES lidar/velodyne_nebula_test.cc DEPS keel_io keel_lidar)
if(KEEL_NEBULA_TESTDATA)
  set_tests_properties(io/velodyne_nebula PROPERTIES
    ENVIRONMENT "KEEL_NEBULA_TESTDATA=${KEEL_NEBULA_TESTDATA}")
endif()
keel_test(io/velodyne_bag SOURCES lidar/velodyne_bag_test.cc DEPS keel_io keel_lidar)
if(KEEL_NEBULA_TESTDATA)
  set_tests_properties(io/velodyne_bag PROPERTIES
    ENVIRONMENT "KEEL_NEBULA_TESTDATA=${KEEL_NEBULA_TESTDATA}")
endif()
