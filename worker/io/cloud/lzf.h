// LZF, the compression of PCD's binary_compressed bodies (liblzf's format, as PCL writes it):
// a stream of runs, each led by a control byte c: c < 32 is a literal run of c + 1 bytes;
// otherwise a back reference of length (c >> 5) + 2 (c >> 5 == 7: plus the next byte) at
// distance ((c & 31) << 8 | next byte) + 1 behind the output's end.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace keel::io {

// Decodes `size` bytes into exactly `expected` bytes. Nothing when the stream is malformed: a
// run past either end, a reference before the output's start, or a length other than
// `expected`.
std::optional<std::vector<uint8_t>> lzf_decompress(const uint8_t* data, size_t size,
                                                   size_t expected);

// Encodes `size` bytes; the result is at most size + size / 32 + 1 bytes (all literals).
std::vector<uint8_t> lzf_compress(const uint8_t* data, size_t size);

}  // namespace keel::io
