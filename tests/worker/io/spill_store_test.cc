// SpillStore: streams read back in append order whatever was spilled, memory held within the
// budget (plus the append in progress), nothing spilled under the budget, thread-safe appends,
// and a backing file that never shows in the folder.
#include <gtest/gtest.h>

#include <filesystem>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "worker/io/cloud/spill_store.h"

namespace keel::io {
namespace {

namespace fs = std::filesystem;

fs::path temp_folder(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("keel_spill_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

StreamKey key(int tile, uint8_t kind = 0) { return StreamKey{1, kind, 0, tile, -tile, 2 * tile}; }

// Appends pseudo-random chunks to 40 streams and checks every stream's bytes.
void fill_and_check(SpillStore& store, size_t chunks, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<std::string> expected(40);
  for (size_t c = 0; c < chunks; ++c) {
    const int tile = static_cast<int>(rng() % 40);
    std::string bytes(1 + rng() % 3000, '\0');
    for (char& b : bytes) b = static_cast<char>(rng());
    store.append(key(tile), bytes.data(), bytes.size());
    expected[tile] += bytes;
  }
  for (int tile = 0; tile < 40; ++tile) {
    EXPECT_EQ(store.size(key(tile)), expected[tile].size());
    EXPECT_TRUE(store.read(key(tile)) == expected[tile]) << "stream " << tile;
  }
}

TEST(SpillStore, SpilledStreamsReadBackInAppendOrderWithinTheBudget) {
  const fs::path dir = temp_folder("order");
  SpillStore store(dir, 64 * 1024);
  fill_and_check(store, 4000, 1);  // ~6 MB through a 64 KiB budget
  EXPECT_GT(store.bytes_spilled(), 5u * 1000 * 1000);
  // Buffers count by capacity (at most 2x their bytes); the budget holds but for one append.
  EXPECT_LE(store.peak_bytes_buffered(), 64u * 1024 + 2 * 6000);
  EXPECT_LE(store.bytes_buffered(), 64u * 1024);
  EXPECT_TRUE(fs::is_empty(dir));  // the backing file has no name
  fs::remove_all(dir);
}

TEST(SpillStore, NothingIsSpilledUnderTheBudget) {
  const fs::path dir = temp_folder("memory");
  SpillStore store(dir, 64 * 1024 * 1024);
  fill_and_check(store, 2000, 2);
  EXPECT_EQ(store.bytes_spilled(), 0u);
  EXPECT_GT(store.bytes_buffered(), 2000u * 1000);
  fs::remove_all(dir);
}

TEST(SpillStore, EraseAndKeys) {
  const fs::path dir = temp_folder("erase");
  SpillStore store(dir, 1024);
  const std::string a(5000, 'a'), b(100, 'b');
  store.append(key(1), a.data(), a.size());  // spilled
  store.append(key(2), b.data(), b.size());
  store.append(key(2, 1), b.data(), b.size());
  EXPECT_EQ(store.keys(1, 0).size(), 2u);
  EXPECT_EQ(store.keys(1, 1).size(), 1u);
  EXPECT_TRUE(store.keys(2, 0).empty());
  store.erase(key(2));
  EXPECT_EQ(store.size(key(2)), 0u);
  EXPECT_EQ(store.read(key(2)), "");
  EXPECT_EQ(store.read(key(1)), a);
  EXPECT_EQ(store.read(key(2, 1)), b);
  EXPECT_LE(store.bytes_buffered(), 1024u);
  fs::remove_all(dir);
}

TEST(SpillStore, ConcurrentAppendsAndReads) {
  const fs::path dir = temp_folder("threads");
  SpillStore store(dir, 32 * 1024);
  // Each thread owns its streams (tiles t, t + 2, ...) and reads them back while the other
  // thread appends and spills.
  auto work = [&](int first) {
    std::string expected[20];
    for (int round = 0; round < 300; ++round)
      for (int s = 0; s < 20; ++s) {
        const std::string bytes(50 + (round * 7 + s) % 200, static_cast<char>('A' + first + s));
        store.append(key(first + 2 * s), bytes.data(), bytes.size());
        expected[s] += bytes;
        if (round % 50 == 49) {
          EXPECT_TRUE(store.read(key(first + 2 * s)) == expected[s]);
        }
      }
  };
  std::thread other(work, 1);
  work(0);
  other.join();
  EXPECT_GT(store.bytes_spilled(), 0u);
  fs::remove_all(dir);
}

TEST(SpillStore, AFolderThatIsNotThereIsNamed) {
  try {
    SpillStore store("/nonexistent/keel", 1024);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/keel"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace keel::io
