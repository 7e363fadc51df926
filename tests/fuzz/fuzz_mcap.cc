// libFuzzer target: an MCAP file in memory, opened, every message read and decoded by its
// schema's type.
#include <memory>

#include "tests/fuzz/fuzz_decode.h"
#include "worker/io/bag/byte_source.h"
#include "worker/io/io_error.h"
#include "worker/io/bag/mcap_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace keel::io;
  try {
    McapReadOptions options;
    options.max_record_bytes = 16 << 20;  // a hostile length may not allocate more
    McapReader reader(std::make_shared<MemoryBytes>(data, size), options);
    auto cursor = reader.messages();
    McapMessage m;
    for (int n = 0; n < 100000 && cursor.next(m); ++n)
      keel::fuzz::decode_as(m.channel->schema_name, m.data, m.size);
  } catch (const BagFormatError&) {
  } catch (const IoError&) {
  }
  return 0;
}
