#include "worker/io/cloud/lzf.h"

#include <cstring>

namespace keel::io {

namespace {
constexpr size_t kMaxLiteral = 32;      // literal runs of 1..32 bytes
constexpr size_t kMaxOffset = 1 << 13;  // back references reach 8192 bytes
constexpr size_t kMaxMatch = 264;       // (7 + 255) + 2
constexpr int kHashBits = 14;
}  // namespace

std::optional<std::vector<uint8_t>> lzf_decompress(const uint8_t* in, size_t size,
                                                   size_t expected) {
  std::vector<uint8_t> out(expected);
  uint8_t* const begin = out.data();
  uint8_t* o = begin;
  uint8_t* const end = begin + expected;
  const uint8_t* i = in;
  const uint8_t* const in_end = in + size;
  while (i < in_end) {
    const unsigned control = *i++;
    if (control < 32) {
      const size_t run = control + 1;
      if (run > static_cast<size_t>(in_end - i) || run > static_cast<size_t>(end - o))
        return std::nullopt;
      std::memcpy(o, i, run);
      o += run;
      i += run;
      continue;
    }
    size_t length = control >> 5;
    if (length == 7) {
      if (i >= in_end) return std::nullopt;
      length += *i++;
    }
    length += 2;
    if (i >= in_end) return std::nullopt;
    const size_t distance = (static_cast<size_t>(control & 31) << 8 | *i++) + 1;
    if (distance > static_cast<size_t>(o - begin) || length > static_cast<size_t>(end - o))
      return std::nullopt;
    const uint8_t* from = o - distance;
    if (distance >= length)
      std::memcpy(o, from, length);
    else if (distance == 1)
      std::memset(o, *from, length);  // a run of one byte
    else
      for (size_t k = 0; k < length; ++k) o[k] = from[k];  // overlapping: byte by byte
    o += length;
  }
  if (o != end) return std::nullopt;
  return out;
}

std::vector<uint8_t> lzf_compress(const uint8_t* in, size_t size) {
  std::vector<uint8_t> out;
  out.reserve(size + size / 32 + 1);
  std::vector<uint32_t> table(size_t{1} << kHashBits, UINT32_MAX);
  size_t literal_start = 0;  // first byte of the pending literal run
  auto flush_literals = [&](size_t upto) {
    while (literal_start < upto) {
      const size_t run = std::min(kMaxLiteral, upto - literal_start);
      out.push_back(static_cast<uint8_t>(run - 1));
      out.insert(out.end(), in + literal_start, in + literal_start + run);
      literal_start += run;
    }
  };
  auto hash = [&](size_t p) {
    const uint32_t v = uint32_t{in[p]} << 16 | uint32_t{in[p + 1]} << 8 | in[p + 2];
    return (v * 2654435761u) >> (32 - kHashBits);
  };
  size_t p = 0;
  while (p + 2 < size) {
    const uint32_t h = hash(p);
    const uint32_t candidate = table[h];
    table[h] = static_cast<uint32_t>(p);
    if (candidate != UINT32_MAX && p - candidate <= kMaxOffset &&
        std::memcmp(in + candidate, in + p, 3) == 0) {
      size_t length = 3;
      const size_t limit = std::min(kMaxMatch, size - p);
      while (length < limit && in[candidate + length] == in[p + length]) ++length;
      flush_literals(p);
      const size_t distance = p - candidate - 1;
      const size_t code = length - 2;
      if (code < 7) {
        out.push_back(static_cast<uint8_t>(code << 5 | distance >> 8));
      } else {
        out.push_back(static_cast<uint8_t>(7 << 5 | distance >> 8));
        out.push_back(static_cast<uint8_t>(code - 7));
      }
      out.push_back(static_cast<uint8_t>(distance & 0xff));
      p += length;
      literal_start = p;
      continue;
    }
    ++p;
  }
  flush_literals(size);
  return out;
}

}  // namespace keel::io
