// SHA-256 through OpenSSL's EVP interface, as 64 lowercase hex digits.
#pragma once

#include <cstddef>
#include <filesystem>
#include <memory>
#include <string>

namespace keel {

class Sha256 {
 public:
  Sha256();
  ~Sha256();
  Sha256(const Sha256&) = delete;
  Sha256& operator=(const Sha256&) = delete;
  void update(const void* data, size_t size);
  std::string hex_digest();  // finishes the hash; call once

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

std::string sha256_bytes(const std::string& bytes);
// Streams the file in 1 MiB blocks; throws std::runtime_error naming the file on I/O errors.
std::string sha256_file(const std::filesystem::path& file);

}  // namespace keel
