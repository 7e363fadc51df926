// libFuzzer target: a rosbag2 SQLite3 file in memory (sqlite3_deserialize), its topics read
// and every message decoded by the topic's type.
#include "tests/fuzz/fuzz_decode.h"
#include "worker/io/bag/db3_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace keel::io;
  try {
    Db3Reader reader(data, size);
    for (const auto& topic : reader.topics()) {
      auto cursor = reader.messages(topic.id);
      Db3Message m;
      for (int n = 0; n < 100000 && cursor.next(m); ++n)
        keel::fuzz::decode_as(topic.type, m.data, m.size);
    }
  } catch (const BagFormatError&) {
  }
  return 0;
}
