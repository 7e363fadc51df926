// SHA-256 against the FIPS 180-2 / NIST CSHS example vectors.
#include "core/sha256.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace keel {
namespace {

TEST(Sha256, FipsOneBlockMessageAbc) {
  EXPECT_EQ(sha256_bytes("abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
}

TEST(Sha256, EmptyMessage) {
  EXPECT_EQ(sha256_bytes(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
}

TEST(Sha256, FipsTwoBlock448BitMessage) {
  EXPECT_EQ(sha256_bytes("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
}

TEST(Sha256, FipsMillionAsStreamedAndFromFile) {
  const std::string expected = "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0";
  Sha256 hash;
  const std::string block(1000, 'a');
  for (int i = 0; i < 1000; ++i) hash.update(block.data(), block.size());
  EXPECT_EQ(hash.hex_digest(), expected);

  const auto file = std::filesystem::temp_directory_path() / "keel-sha256-test-a.bin";
  std::ofstream(file, std::ios::binary) << std::string(1'000'000, 'a');
  EXPECT_EQ(sha256_file(file), expected);  // spans the 1 MiB read blocks
  std::filesystem::remove(file);
}

TEST(Sha256, MissingFileErrorNamesIt) {
  try {
    sha256_file("/nonexistent/keel-file.bin");
    FAIL() << "expected an error";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("/nonexistent/keel-file.bin"), std::string::npos);
  }
}

}  // namespace
}  // namespace keel
