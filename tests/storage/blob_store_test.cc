#include "storage/blob_store.h"

#include <gtest/gtest.h>

#include <thread>
#include <vector>

#include "core/sha256.h"
#include "store_fixture.h"

namespace keel::storage {
namespace {

namespace fs = std::filesystem;

// Every regular file under `root`, recursively.
std::vector<fs::path> files_under(const fs::path& root) {
  std::vector<fs::path> files;
  for (const auto& entry : fs::recursive_directory_iterator(root))
    if (entry.is_regular_file()) files.push_back(entry.path());
  return files;
}

class BlobStoreTest : public ::testing::Test {
 protected:
  testing::TempDir dir_;
  BlobStore blobs_{dir_.path() / "blobs", dir_.path() / "tmp"};
};

TEST_F(BlobStoreTest, SameContentSameIdOneFile) {
  const std::string first = blobs_.put("hello keel");
  const std::string second = blobs_.put("hello keel");
  EXPECT_EQ(first, second);
  EXPECT_EQ(first, sha256_bytes("hello keel"));
  EXPECT_EQ(files_under(blobs_.blobs_dir()).size(), 1u);
  EXPECT_NE(blobs_.put("other"), first);
  EXPECT_EQ(files_under(blobs_.blobs_dir()).size(), 2u);
}

TEST_F(BlobStoreTest, LayoutIsTwoHexFolderThenFullHash) {
  const std::string sha = blobs_.put("abc");
  EXPECT_EQ(blobs_.path_of(sha),
            dir_.path() / "blobs" / "ba" /
                "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(testing::read_file(blobs_.path_of(sha)), "abc");
}

TEST_F(BlobStoreTest, SizesMatchContent) {
  const std::string empty = blobs_.put("");
  const std::string big = blobs_.put(testing::random_bytes(300'000, 7));
  EXPECT_EQ(blobs_.size_of(empty), 0);
  EXPECT_EQ(blobs_.size_of(big), 300'000);
  EXPECT_TRUE(blobs_.contains(big));
  EXPECT_FALSE(blobs_.contains(sha256_bytes("never stored")));
}

TEST_F(BlobStoreTest, TempFilesNeverUnderBlobsAndTmpEmptyAfterWrites) {
  std::vector<std::thread> writers;
  for (unsigned t = 0; t < 4; ++t)
    writers.emplace_back([&, t] {
      for (unsigned i = 0; i < 20; ++i) blobs_.put(testing::random_bytes(10'000, t * 100 + i % 5));
    });
  for (auto& writer : writers) writer.join();
  // Only finished blobs in blobs/: each named by its own hash, 2-hex folder = its prefix.
  const auto files = files_under(blobs_.blobs_dir());
  EXPECT_EQ(files.size(), 20u);  // 4 threads x 5 distinct seeds
  for (const fs::path& file : files) {
    const std::string name = file.filename().string();
    EXPECT_TRUE(proto::is_sha256_hex(name)) << file;
    EXPECT_EQ(file.parent_path().filename().string(), name.substr(0, 2));
    EXPECT_EQ(sha256_file(file), name);
  }
  EXPECT_TRUE(fs::is_empty(blobs_.tmp_dir()));
}

TEST_F(BlobStoreTest, AdoptMovesFileOrDropsDuplicate) {
  const std::string bytes = testing::random_bytes(5000, 3);
  const fs::path part = dir_.path() / "tmp" / "x.part";
  testing::write_file(part, bytes);
  const std::string sha = sha256_bytes(bytes);
  blobs_.adopt(part, sha);
  EXPECT_FALSE(fs::exists(part));
  EXPECT_EQ(testing::read_file(blobs_.path_of(sha)), bytes);
  testing::write_file(part, bytes);
  blobs_.adopt(part, sha);  // already stored: the duplicate is just removed
  EXPECT_FALSE(fs::exists(part));
  EXPECT_EQ(files_under(blobs_.blobs_dir()).size(), 1u);
}

TEST_F(BlobStoreTest, ClearTmpRemovesLeftovers) {
  testing::write_file(blobs_.temp_path(), "half a blob");
  blobs_.clear_tmp();
  EXPECT_TRUE(fs::is_empty(blobs_.tmp_dir()));
}

TEST_F(BlobStoreTest, MalformedIdRejected) {
  EXPECT_THROW(blobs_.path_of("../../etc/passwd"), std::invalid_argument);
  EXPECT_THROW(blobs_.path_of(std::string(64, 'A')), std::invalid_argument);
}

}  // namespace
}  // namespace keel::storage
