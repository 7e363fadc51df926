// Shared by the fuzz harnesses: the input written to a file (most readers take a path), and
// the rule every harness checks: bad input may only end in the parser's documented error.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace keel::fuzz {

// A per-process scratch folder, made once.
inline const std::filesystem::path& scratch() {
  static const std::filesystem::path dir = [] {
    auto path = std::filesystem::temp_directory_path() /
                ("keel-fuzz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(path);
    return path;
  }();
  return dir;
}

// Writes the bytes to scratch()/name and returns the path.
inline std::filesystem::path write_input(const std::string& name, const uint8_t* data, size_t size) {
  const auto path = scratch() / name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path;
}

// The first byte picks a variant (which reader); the rest is the input.
struct Split {
  uint8_t selector = 0;
  const uint8_t* data = nullptr;
  size_t size = 0;
};
inline Split split_selector(const uint8_t* data, size_t size) {
  if (size == 0) return {};
  return {data[0], data + 1, size - 1};
}

}  // namespace keel::fuzz
