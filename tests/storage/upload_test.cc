// Resumable uploads through the Store: chunk order, conflicts, completion and crash recovery.
#include <gtest/gtest.h>

#include <chrono>

#include "core/sha256.h"
#include "store_fixture.h"

namespace keel::storage {
namespace {

namespace fs = std::filesystem;
using testing::StoreTest;

class UploadTest : public StoreTest {
 protected:
  fs::path part_file(const std::string& upload_id) const {
    return dir_.path() / "uploads" / (upload_id + ".part");
  }
  proto::Upload append(const std::string& id, int64_t offset, const std::string& chunk) {
    return store_->append_upload(id, offset, chunk.data(), chunk.size());
  }
  int64_t upload_rows() { return count_rows("uploads"); }
};

TEST_P(UploadTest, ChunksInOrderThenCompleteGivesBlob) {
  const std::string bytes = testing::random_bytes(100'000, 1);
  proto::Upload upload = store_->create_upload({"m.tar", 100'000});
  EXPECT_EQ(upload.id.substr(0, 2), "u_");
  EXPECT_EQ(upload.offset, 0);
  for (int64_t at = 0; at < 100'000; at += 30'000) {
    const std::string chunk = bytes.substr(static_cast<size_t>(at), 30'000);
    upload = append(upload.id, at, chunk);
    EXPECT_EQ(upload.offset, std::min<int64_t>(at + 30'000, 100'000));
    EXPECT_EQ(store_->get_upload(upload.id).offset, upload.offset);
  }
  EXPECT_EQ(store_->metrics().uploads_open, 1);
  const std::string sha = store_->complete_upload(upload.id, sha256_bytes(bytes));
  EXPECT_EQ(sha, sha256_bytes(bytes));
  EXPECT_TRUE(store_->has_blob(sha));
  EXPECT_EQ(store_->blob_size(sha), 100'000);
  EXPECT_EQ(testing::read_file(store_->blob_path(sha)), bytes);
  EXPECT_FALSE(fs::exists(part_file(upload.id)));
  EXPECT_THROW(store_->get_upload(upload.id), NotFound);
  EXPECT_EQ(store_->metrics().uploads_open, 0);
}

TEST_P(UploadTest, WrongOffsetIsConflictWithCommittedOffset) {
  const proto::Upload upload = store_->create_upload({"m.tar", 10});
  append(upload.id, 0, "abcd");
  try {
    append(upload.id, 2, "cdef");  // overlaps committed bytes
    FAIL() << "expected OffsetMismatch";
  } catch (const OffsetMismatch& error) {
    EXPECT_EQ(error.committed_offset, 4);
    EXPECT_NE(std::string(error.what()).find(upload.id), std::string::npos);
  }
  EXPECT_THROW(append(upload.id, 6, "gh"), Conflict);  // a gap
  EXPECT_EQ(store_->get_upload(upload.id).offset, 4);
  EXPECT_EQ(testing::read_file(part_file(upload.id)), "abcd");
}

TEST_P(UploadTest, ChunkBeyondAnnouncedSizeIsInvalidAndCommitsNothing) {
  const proto::Upload upload = store_->create_upload({"m.tar", 6});
  append(upload.id, 0, "abcd");
  EXPECT_THROW(append(upload.id, 4, "efg"), Invalid);
  EXPECT_EQ(store_->get_upload(upload.id).offset, 4);
  EXPECT_EQ(append(upload.id, 4, "ef").offset, 6);
  EXPECT_THROW(append(upload.id, 6, "x"), Invalid);
}

TEST_P(UploadTest, WrongHashDeletesEverything) {
  const std::string bytes = "the mission bytes";
  const proto::Upload upload = store_->create_upload({"m.tar", static_cast<int64_t>(bytes.size())});
  append(upload.id, 0, bytes);
  const std::string wrong = sha256_bytes("something else");
  try {
    store_->complete_upload(upload.id, wrong);
    FAIL() << "expected Sha256Mismatch";
  } catch (const Sha256Mismatch& error) {
    const std::string text = error.what();
    EXPECT_NE(text.find(upload.id), std::string::npos) << text;
    EXPECT_NE(text.find(wrong), std::string::npos) << text;                // expected
    EXPECT_NE(text.find(sha256_bytes(bytes)), std::string::npos) << text;  // actual
  }
  EXPECT_FALSE(fs::exists(part_file(upload.id)));
  EXPECT_THROW(store_->get_upload(upload.id), NotFound);
  EXPECT_EQ(upload_rows(), 0);
  EXPECT_FALSE(store_->has_blob(sha256_bytes(bytes)));
  EXPECT_FALSE(store_->has_blob(wrong));
  EXPECT_EQ(store_->metrics().blobs, 0);
}

TEST_P(UploadTest, ShortUploadIsSizeMismatchAndDeleted) {
  const proto::Upload upload = store_->create_upload({"m.tar", 10});
  append(upload.id, 0, "abc");
  try {
    store_->complete_upload(upload.id, sha256_bytes("abc"));
    FAIL() << "expected SizeMismatch";
  } catch (const SizeMismatch& error) {
    const std::string text = error.what();
    EXPECT_NE(text.find("expected 10 bytes, got 3"), std::string::npos) << text;
  }
  EXPECT_EQ(upload_rows(), 0);
  EXPECT_FALSE(fs::exists(part_file(upload.id)));
}

TEST_P(UploadTest, SameContentTwiceIsOneBlob) {
  std::string shas[2];
  for (std::string& sha : shas) {
    const proto::Upload upload = store_->create_upload({"m.tar", 5});
    append(upload.id, 0, "hello");
    sha = store_->complete_upload(upload.id, sha256_bytes("hello"));
  }
  EXPECT_EQ(shas[0], shas[1]);
  EXPECT_EQ(store_->metrics().blobs, 1);
  EXPECT_EQ(store_->metrics().blob_bytes, 5);
  EXPECT_TRUE(fs::is_empty(dir_.path() / "uploads"));
}

TEST_P(UploadTest, EmptyUploadCompletes) {
  const proto::Upload upload = store_->create_upload({"empty", 0});
  EXPECT_EQ(store_->complete_upload(upload.id, sha256_bytes("")), sha256_bytes(""));
  EXPECT_EQ(store_->blob_size(sha256_bytes("")), 0);
}

TEST_P(UploadTest, CrashBetweenWriteAndCommitIsCutOnReopenAndResumes) {
  const std::string bytes = testing::random_bytes(50'000, 9);
  const proto::Upload upload = store_->create_upload({"m.tar", 50'000});
  append(upload.id, 0, bytes.substr(0, 20'000));
  // As after SIGKILL between the chunk's fsync and the offset commit: the part file holds
  // 30,000 bytes but only 20,000 are committed. The extra bytes are garbage on purpose.
  store_.reset();
  {
    std::ofstream out(part_file(upload.id), std::ios::binary | std::ios::app);
    const std::string garbage = testing::random_bytes(10'000, 99);
    out.write(garbage.data(), static_cast<std::streamsize>(garbage.size()));
  }
  ASSERT_EQ(fs::file_size(part_file(upload.id)), 30'000u);
  reopen();
  EXPECT_EQ(fs::file_size(part_file(upload.id)), 20'000u);
  EXPECT_EQ(store_->get_upload(upload.id).offset, 20'000);
  append(upload.id, 20'000, bytes.substr(20'000));
  EXPECT_EQ(store_->complete_upload(upload.id, sha256_bytes(bytes)), sha256_bytes(bytes));
  EXPECT_EQ(testing::read_file(store_->blob_path(sha256_bytes(bytes))), bytes);
}

TEST_P(UploadTest, LeftoverBytesAreCutOnAppendToo) {
  // The same uncommitted tail, but found by the next append rather than by a reopen.
  const std::string bytes = "0123456789";
  const proto::Upload upload = store_->create_upload({"m", 10});
  append(upload.id, 0, "0123");
  testing::write_file(part_file(upload.id), "0123XXXXXXXX");
  append(upload.id, 4, "456789");
  EXPECT_EQ(testing::read_file(part_file(upload.id)), bytes);
  EXPECT_EQ(store_->complete_upload(upload.id, sha256_bytes(bytes)), sha256_bytes(bytes));
}

TEST_P(UploadTest, LostCommittedBytesMoveTheOffsetBack) {
  const proto::Upload upload = store_->create_upload({"m", 8});
  append(upload.id, 0, "0123");
  testing::write_file(part_file(upload.id), "01");  // damaged: two committed bytes gone
  try {
    append(upload.id, 4, "4567");
    FAIL() << "expected OffsetMismatch";
  } catch (const OffsetMismatch& error) {
    EXPECT_EQ(error.committed_offset, 2);
  }
  EXPECT_EQ(store_->get_upload(upload.id).offset, 2);
  append(upload.id, 2, "234567");
  EXPECT_EQ(store_->complete_upload(upload.id, sha256_bytes("01234567")), sha256_bytes("01234567"));
}

TEST_P(UploadTest, ReopenRemovesOrphanPartsAndTempFiles) {
  testing::write_file(dir_.path() / "uploads" / "u_00000000deadbeef.part", "orphan");
  const fs::path old_temp = dir_.path() / "tmp" / "abc.tmp";
  testing::write_file(old_temp, "half a blob");
  fs::last_write_time(old_temp, fs::file_time_type::clock::now() - std::chrono::hours(2));
  reopen();
  EXPECT_TRUE(fs::is_empty(dir_.path() / "uploads"));
  EXPECT_TRUE(fs::is_empty(dir_.path() / "tmp"));
}

// Replicas share the blob folder: a fresh temp file may be another replica's blob being
// written, so a PostgreSQL store opening leaves it (SQLite owns its folder alone).
TEST_P(UploadTest, ReopenKeepsAFreshTempFileOfAnotherReplica) {
  if (!postgres()) GTEST_SKIP() << "one SQLite store owns its folder";
  const fs::path fresh = dir_.path() / "tmp" / "def.tmp";
  testing::write_file(fresh, "a blob another replica is writing");
  auto replica = open_another();
  EXPECT_TRUE(fs::exists(fresh));
}

// An upload continues on another replica: the committed offset is in the database and the
// part file in the shared folder.
TEST_P(UploadTest, ResumesOnAnotherStoreOfTheSameData) {
  const std::string bytes = testing::random_bytes(30'000, 5);
  const proto::Upload upload = store_->create_upload({"m.tar", 30'000});
  append(upload.id, 0, bytes.substr(0, 10'000));
  auto replica = open_another();
  EXPECT_EQ(replica->get_upload(upload.id).offset, 10'000);
  replica->append_upload(upload.id, 10'000, bytes.data() + 10'000, 10'000);
  EXPECT_THROW(append(upload.id, 10'000, bytes.substr(10'000, 10'000)), OffsetMismatch)
      << "the first store sees the offset the other committed";
  append(upload.id, 20'000, bytes.substr(20'000));
  EXPECT_EQ(replica->complete_upload(upload.id, sha256_bytes(bytes)), sha256_bytes(bytes));
  EXPECT_EQ(testing::read_file(store_->blob_path(sha256_bytes(bytes))), bytes);
}

TEST_P(UploadTest, DeleteAndUnknownIds) {
  const proto::Upload upload = store_->create_upload({"m", 3});
  store_->delete_upload(upload.id);
  EXPECT_FALSE(fs::exists(part_file(upload.id)));
  try {
    store_->delete_upload(upload.id);
    FAIL() << "expected NotFound";
  } catch (const NotFound& error) {
    EXPECT_NE(std::string(error.what()).find(upload.id), std::string::npos);
  }
  EXPECT_THROW(append("u_0123456789abcdef", 0, "x"), NotFound);
  EXPECT_THROW(store_->complete_upload(upload.id, "not-a-hash"), Invalid);
  EXPECT_THROW(store_->create_upload({"m", -1}), Invalid);
}

KEEL_STORE_TEST_SUITE(UploadTest);

}  // namespace
}  // namespace keel::storage
