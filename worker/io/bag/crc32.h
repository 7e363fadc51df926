// CRC-32 (IEEE 802.3, the zlib/PNG polynomial 0xEDB88320, reflected), as MCAP uses for its
// chunk, data-section and summary checksums. Incremental: crc32(b, crc32(a)) = crc32(a + b).
#pragma once

#include <cstddef>
#include <cstdint>

namespace keel::io {

uint32_t crc32(const uint8_t* data, size_t size, uint32_t crc = 0);

}  // namespace keel::io
