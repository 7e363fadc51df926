// Meshes: PLY, OBJ, STL (ascii and binary) and OFF (worker/io/mesh/mesh_reader.h), and the PLY
// header parser shared with clouds. Any bytes are read or refused naming the file.
#include <stdexcept>
#include <string_view>

#include "tests/fuzz/fuzz_util.h"
#include "worker/io/mesh/mesh_reader.h"
#include "worker/io/cloud/ply_header.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  namespace io = keel::io;
  const auto input = keel::fuzz::split_selector(data, size);
  static const char* const kNames[] = {"mesh.ply", "mesh.obj", "mesh.stl", "mesh.off"};
  try {
    if (input.selector % 5 == 4) {
      (void)io::parse_ply_header(
          std::string_view(reinterpret_cast<const char*>(input.data), input.size), "mesh.ply");
      return 0;
    }
    const auto file = keel::fuzz::write_input(kNames[input.selector % 5], input.data, input.size);
    (void)io::read_mesh(file);
  } catch (const std::runtime_error&) {
  }
  return 0;
}
