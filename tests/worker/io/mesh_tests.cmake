# Mesh and Draco I/O tests (owner: mesh). Included from tests/worker/io/CMakeLists.txt.
keel_test(io/mesh_reader SOURCES ${CMAKE_CURRENT_LIST_DIR}/mesh_reader_test.cc DEPS keel_mesh_io)
keel_test(io/mesh_check SOURCES ${CMAKE_CURRENT_LIST_DIR}/mesh_check_test.cc DEPS keel_mesh_io)
keel_test(io/mesh_ply_writers SOURCES ${CMAKE_CURRENT_LIST_DIR}/mesh_ply_writers_test.cc DEPS keel_mesh_io keel_pcl_io)
keel_test(io/draco_codec SOURCES ${CMAKE_CURRENT_LIST_DIR}/draco_codec_test.cc DEPS keel_mesh_io)
keel_test(io/draco_header_check SOURCES ${CMAKE_CURRENT_LIST_DIR}/draco_header_check_test.cc DEPS keel_mesh_io)
keel_test(io/ply_header SOURCES ${CMAKE_CURRENT_LIST_DIR}/ply_header_test.cc DEPS keel_mesh_io)
keel_test(io/draco_summary SOURCES ${CMAKE_CURRENT_LIST_DIR}/draco_summary_test.cc DEPS keel_mesh_io draco::draco)
keel_test(io/display_path SOURCES ${CMAKE_CURRENT_LIST_DIR}/display_path_test.cc DEPS keel_mesh_io)
