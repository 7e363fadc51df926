# Mesh and Draco I/O (owner: mesh). Included from worker/io/CMakeLists.txt; a library of its
# own so the mesh readers/writers and the other io readers build and change independently.
keel_library(keel_mesh_io
  SOURCES
    ${CMAKE_CURRENT_LIST_DIR}/display_path.cc
    ${CMAKE_CURRENT_LIST_DIR}/mesh_parse_util.cc
    ${CMAKE_CURRENT_LIST_DIR}/mesh_reader.cc
    ${CMAKE_CURRENT_LIST_DIR}/ply_header.cc
    ${CMAKE_CURRENT_LIST_DIR}/mesh_ply_reader.cc
    ${CMAKE_CURRENT_LIST_DIR}/mesh_obj_reader.cc
    ${CMAKE_CURRENT_LIST_DIR}/mesh_stl_reader.cc
    ${CMAKE_CURRENT_LIST_DIR}/mesh_off_reader.cc
    ${CMAKE_CURRENT_LIST_DIR}/mesh_check.cc
    ${CMAKE_CURRENT_LIST_DIR}/mesh_scalar_field.cc
    ${CMAKE_CURRENT_LIST_DIR}/replaced_file.cc
    ${CMAKE_CURRENT_LIST_DIR}/mesh_ply_binary_writer.cc
    ${CMAKE_CURRENT_LIST_DIR}/mesh_ply_writer.cc
    ${CMAKE_CURRENT_LIST_DIR}/ply_cloud_writer.cc
    ${CMAKE_CURRENT_LIST_DIR}/draco_codec.cc
    ${CMAKE_CURRENT_LIST_DIR}/draco_header_check.cc
    ${CMAKE_CURRENT_LIST_DIR}/draco_summary.cc
  DEPS keel_core nlohmann_json::nlohmann_json)
# Draco stays private: its headers are not in any public header of this library.
target_link_libraries(keel_mesh_io PRIVATE draco::draco)
