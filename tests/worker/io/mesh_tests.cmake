# Mesh and Draco I/O tests (owner: mesh). Included from tests/worker/io/CMakeLists.txt.
keel_test(io/mesh_reader SOURCES ${CMAKE_CURRENT_LIST_DIR}/mesh_reader_test.cc DEPS keel_mesh_io)
