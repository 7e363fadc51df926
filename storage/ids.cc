#include "storage/ids.h"

#include <openssl/rand.h>

#include <stdexcept>
#include <vector>

namespace keel::storage {

std::string random_hex(size_t bytes) {
  std::vector<unsigned char> buffer(bytes);
  if (bytes > 0 && RAND_bytes(buffer.data(), static_cast<int>(bytes)) != 1)
    throw std::runtime_error("random_hex: OpenSSL RAND_bytes failed");
  static const char* kHex = "0123456789abcdef";
  std::string out;
  out.reserve(2 * bytes);
  for (unsigned char byte : buffer) {
    out.push_back(kHex[byte >> 4]);
    out.push_back(kHex[byte & 15]);
  }
  return out;
}

std::string new_id(const std::string& prefix) { return prefix + random_hex(8); }

}  // namespace keel::storage
