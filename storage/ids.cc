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

bool is_id(const std::string& text, const std::string& prefix) {
  if (text.size() < prefix.size() || text.compare(0, prefix.size(), prefix) != 0) return false;
  const size_t digits = text.size() - prefix.size();
  if (digits < 16 || digits > 64) return false;
  for (size_t i = prefix.size(); i < text.size(); ++i) {
    const char c = text[i];
    if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
  }
  return true;
}

}  // namespace keel::storage
