#include "tests/sim/mcap_writer.h"

#include <lz4frame.h>
#include <zstd.h>

#include <cstring>
#include <stdexcept>

#include "worker/io/bag/crc32.h"

namespace keel::sim {

namespace {

constexpr uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};

// Little-endian record building (mcap.dev/spec "Serialization").
class Record {
 public:
  explicit Record(uint8_t opcode) : bytes_{opcode, 0, 0, 0, 0, 0, 0, 0, 0} {}
  Record& u8(uint8_t v) { return put(v); }
  Record& u16(uint16_t v) { return put(v); }
  Record& u32(uint32_t v) { return put(v); }
  Record& u64(uint64_t v) { return put(v); }
  Record& string(const std::string& s) {
    u32(static_cast<uint32_t>(s.size()));
    bytes_.insert(bytes_.end(), s.begin(), s.end());
    return *this;
  }
  Record& raw(const uint8_t* data, size_t size) {
    bytes_.insert(bytes_.end(), data, data + size);
    return *this;
  }
  // The content length goes into bytes 1..8.
  std::vector<uint8_t> done() {
    const uint64_t length = bytes_.size() - 9;
    std::memcpy(bytes_.data() + 1, &length, 8);
    return std::move(bytes_);
  }

 private:
  template <typename T>
  Record& put(T v) {
    const size_t at = bytes_.size();
    bytes_.resize(at + sizeof(T));
    std::memcpy(bytes_.data() + at, &v, sizeof(T));
    return *this;
  }
  std::vector<uint8_t> bytes_;
};

std::vector<uint8_t> compress(const std::string& method, const std::vector<uint8_t>& in) {
  std::vector<uint8_t> out;
  if (method == "zstd") {
    out.resize(ZSTD_compressBound(in.size()));
    const size_t n = ZSTD_compress(out.data(), out.size(), in.data(), in.size(), 3);
    if (ZSTD_isError(n)) throw std::runtime_error(std::string("zstd: ") + ZSTD_getErrorName(n));
    out.resize(n);
  } else if (method == "lz4") {
    LZ4F_preferences_t preferences{};
    preferences.frameInfo.contentSize = in.size();
    out.resize(LZ4F_compressFrameBound(in.size(), &preferences));
    const size_t n = LZ4F_compressFrame(out.data(), out.size(), in.data(), in.size(), &preferences);
    if (LZ4F_isError(n)) throw std::runtime_error(std::string("lz4: ") + LZ4F_getErrorName(n));
    out.resize(n);
  } else {
    out = in;
  }
  return out;
}

}  // namespace

McapWriter::McapWriter(const std::string& path, McapWriterOptions options)
    : path_(path), options_(std::move(options)) {
  if (options_.compression != "zstd" && options_.compression != "lz4" &&
      !options_.compression.empty())
    throw std::invalid_argument("MCAP compression '" + options_.compression +
                                "': expected zstd, lz4 or none");
  file_ = std::fopen(path.c_str(), "wb");
  if (!file_) throw std::runtime_error("cannot write " + path);
  emit(std::vector<uint8_t>(kMagic, kMagic + 8));
  emit(Record(0x01).string("ros2").string("keel-sim").done());
}

McapWriter::~McapWriter() {
  try {
    close();
  } catch (...) {
  }
}

void McapWriter::emit(const std::vector<uint8_t>& bytes) {
  if (std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size())
    throw std::runtime_error("cannot write " + path_);
  data_crc_ = io::crc32(bytes.data(), bytes.size(), data_crc_);
  offset_ += bytes.size();
}

uint16_t McapWriter::add_schema(const std::string& name, const std::string& encoding,
                                const std::string& data) {
  const auto id = static_cast<uint16_t>(schema_records_.size() + 1);  // 0 is "no schema"
  Record r(0x03);
  r.u16(id).string(name).string(encoding).string(data);  // data: uint32-prefixed bytes
  schema_records_.push_back(r.done());
  // Into the open chunk, before any channel that refers to it.
  chunk_.insert(chunk_.end(), schema_records_.back().begin(), schema_records_.back().end());
  return id;
}

uint16_t McapWriter::add_channel(const std::string& topic, uint16_t schema_id,
                                 const std::string& message_encoding) {
  const auto id = static_cast<uint16_t>(channel_records_.size() + 1);
  Record r(0x04);
  r.u16(id).u16(schema_id).string(topic).string(message_encoding).u32(0);  // no metadata
  channel_records_.push_back(r.done());
  chunk_.insert(chunk_.end(), channel_records_.back().begin(), channel_records_.back().end());
  channel_counts_[id] = 0;
  sequence_.push_back(0);
  return id;
}

void McapWriter::write(uint16_t channel_id, uint64_t log_time_ns,
                       const std::vector<uint8_t>& data) {
  if (channel_id == 0 || channel_id > sequence_.size())
    throw std::invalid_argument("MCAP write on unknown channel " + std::to_string(channel_id));
  chunk_index_[channel_id].emplace_back(log_time_ns, chunk_.size());
  Record r(0x05);
  r.u16(channel_id).u32(sequence_[channel_id - 1]++).u64(log_time_ns).u64(log_time_ns);
  r.raw(data.data(), data.size());
  const std::vector<uint8_t> record = r.done();
  chunk_.insert(chunk_.end(), record.begin(), record.end());
  chunk_start_ = chunk_has_messages_ ? std::min(chunk_start_, log_time_ns) : log_time_ns;
  chunk_end_ = chunk_has_messages_ ? std::max(chunk_end_, log_time_ns) : log_time_ns;
  start_time_ = message_count_ > 0 ? std::min(start_time_, log_time_ns) : log_time_ns;
  end_time_ = std::max(end_time_, log_time_ns);
  chunk_has_messages_ = true;
  ++channel_counts_[channel_id];
  ++message_count_;
  if (chunk_.size() >= options_.chunk_bytes) flush_chunk();
}

void McapWriter::flush_chunk() {
  if (chunk_.empty()) return;
  const std::vector<uint8_t> records = compress(options_.compression, chunk_);
  ChunkIndex index;
  index.start_time = chunk_has_messages_ ? chunk_start_ : 0;
  index.end_time = chunk_has_messages_ ? chunk_end_ : 0;
  index.offset = offset_;
  index.compressed = records.size();
  index.uncompressed = chunk_.size();
  Record r(0x06);
  r.u64(index.start_time).u64(index.end_time).u64(chunk_.size());
  r.u32(io::crc32(chunk_.data(), chunk_.size())).string(options_.compression);
  r.u64(records.size()).raw(records.data(), records.size());
  const std::vector<uint8_t> chunk_record = r.done();
  emit(chunk_record);
  index.length = chunk_record.size();
  const uint64_t index_start = offset_;
  for (const auto& [channel, entries] : chunk_index_) {
    index.index_offsets[channel] = offset_;
    Record m(0x07);
    m.u16(channel).u32(static_cast<uint32_t>(entries.size() * 16));
    for (const auto& [time, at] : entries) m.u64(time).u64(at);
    emit(m.done());
  }
  index.index_length = offset_ - index_start;
  chunk_indexes_.push_back(index);
  chunk_.clear();
  chunk_index_.clear();
  chunk_has_messages_ = false;
}

void McapWriter::close() {
  if (!file_) return;
  flush_chunk();
  emit(Record(0x0F).u32(data_crc_).done());  // Data End: CRC of everything before it

  // Summary, grouped by opcode; a Summary Offset per group.
  const uint64_t summary_start = offset_;
  uint32_t summary_crc = 0;
  std::vector<std::vector<uint8_t>> offsets;
  auto group = [&](uint8_t opcode, const std::vector<std::vector<uint8_t>>& records) {
    if (records.empty()) return;
    const uint64_t start = offset_;
    for (const auto& record : records) {
      emit(record);
      summary_crc = io::crc32(record.data(), record.size(), summary_crc);
    }
    offsets.push_back(Record(0x0E).u8(opcode).u64(start).u64(offset_ - start).done());
  };
  group(0x03, schema_records_);
  group(0x04, channel_records_);
  Record statistics(0x0B);
  statistics.u64(message_count_)
      .u16(static_cast<uint16_t>(schema_records_.size()))
      .u32(static_cast<uint32_t>(channel_records_.size()))
      .u32(0)
      .u32(0)
      .u32(static_cast<uint32_t>(chunk_indexes_.size()))
      .u64(message_count_ ? start_time_ : 0)
      .u64(message_count_ ? end_time_ : 0)
      .u32(static_cast<uint32_t>(channel_counts_.size() * 10));
  for (const auto& [channel, count] : channel_counts_) statistics.u16(channel).u64(count);
  group(0x0B, {statistics.done()});
  std::vector<std::vector<uint8_t>> chunk_index_records;
  for (const auto& c : chunk_indexes_) {
    Record r(0x08);
    r.u64(c.start_time).u64(c.end_time).u64(c.offset).u64(c.length);
    r.u32(static_cast<uint32_t>(c.index_offsets.size() * 10));
    for (const auto& [channel, at] : c.index_offsets) r.u16(channel).u64(at);
    r.u64(c.index_length).string(options_.compression).u64(c.compressed).u64(c.uncompressed);
    chunk_index_records.push_back(r.done());
  }
  group(0x08, chunk_index_records);
  const uint64_t summary_offset_start = offset_;
  for (const auto& record : offsets) {
    emit(record);
    summary_crc = io::crc32(record.data(), record.size(), summary_crc);
  }
  // Footer: the summary CRC runs through the footer's summary_offset_start field.
  std::vector<uint8_t> footer =
      Record(0x02).u64(summary_start).u64(summary_offset_start).u32(0).done();
  summary_crc = io::crc32(footer.data(), footer.size() - 4, summary_crc);
  std::memcpy(footer.data() + footer.size() - 4, &summary_crc, 4);
  emit(footer);
  emit(std::vector<uint8_t>(kMagic, kMagic + 8));
  const bool ok = std::fclose(file_) == 0;
  file_ = nullptr;
  if (!ok) throw std::runtime_error("cannot write " + path_);
}

}  // namespace keel::sim
