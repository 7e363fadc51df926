#include "worker/io/bag/mcap_reader.h"

#include <lz4frame.h>
#include <zstd.h>

#include <cstring>

#include "worker/io/bag/bag_format_error.h"
#include "worker/io/bag/crc32.h"

namespace keel::io {

namespace {

constexpr uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
constexpr uint64_t kRecordHeaderBytes = 9;  // opcode (1) + content length (8)
constexpr uint64_t kFooterContentBytes = 20;
constexpr uint64_t kFooterRecordBytes = kRecordHeaderBytes + kFooterContentBytes;

enum Opcode : uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kChunkIndex = 0x08,
  kStatistics = 0x0B,
  kDataEnd = 0x0F,
};

std::string record_name(uint8_t opcode) {
  static const char* names[] = {"",           "Header",           "Footer",
                                "Schema",     "Channel",          "Message",
                                "Chunk",      "Message Index",    "Chunk Index",
                                "Attachment", "Attachment Index", "Statistics",
                                "Metadata",   "Metadata Index",   "Summary Offset",
                                "Data End"};
  if (opcode >= 1 && opcode <= 0x0F) return names[opcode];
  return "opcode " + std::to_string(opcode);
}

std::string at(uint8_t opcode, uint64_t offset) {
  return record_name(opcode) + " record at byte " + std::to_string(offset);
}

uint64_t load_u64(const uint8_t* p) {
  uint64_t v;
  std::memcpy(&v, p, 8);
  return v;
}

// Fields of one record's content, each read checked against the content's length.
class Fields {
 public:
  Fields(const uint8_t* data, uint64_t size, std::string what)
      : data_(data), size_(size), what_(std::move(what)) {}
  uint16_t u16(const char* field) { return load<uint16_t>(field); }
  uint32_t u32(const char* field) { return load<uint32_t>(field); }
  uint64_t u64(const char* field) { return load<uint64_t>(field); }
  std::string string(const char* field) {
    const uint32_t n = u32(field);
    need(n, field);
    std::string s(reinterpret_cast<const char*>(data_ + position_), n);
    position_ += n;
    return s;
  }
  // A uint32 byte-length-prefixed map or byte array: returns its bytes' offset and length.
  std::pair<uint64_t, uint32_t> block32(const char* field) {
    const uint32_t n = u32(field);
    need(n, field);
    const uint64_t begin = position_;
    position_ += n;
    return {begin, n};
  }
  const uint8_t* data() const { return data_; }
  uint64_t position() const { return position_; }
  uint64_t left() const { return size_ - position_; }

 private:
  template <typename T>
  T load(const char* field) {
    need(sizeof(T), field);
    T v;
    std::memcpy(&v, data_ + position_, sizeof(T));
    position_ += sizeof(T);
    return v;
  }
  void need(uint64_t n, const char* field) const {
    if (n > size_ - position_)
      throw BagFormatError(what_ + ": field '" + field + "' of " + std::to_string(n) +
                           " bytes runs past the record's " + std::to_string(size_) + " bytes");
  }

  const uint8_t* data_;
  uint64_t size_;
  std::string what_;
  uint64_t position_ = 0;
};

std::string hex32(uint32_t v) {
  char buffer[16];
  std::snprintf(buffer, sizeof(buffer), "0x%08x", v);
  return buffer;
}

}  // namespace

McapReader::McapReader(std::shared_ptr<const ByteSource> bytes, McapReadOptions options)
    : bytes_(std::move(bytes)), options_(options) {
  const uint64_t size = bytes_->size();
  uint8_t head[8] = {};
  bytes_->read(0, std::min<uint64_t>(8, size), head);
  if (size < 8 || std::memcmp(head, kMagic, 8) != 0) {
    std::string seen;
    for (uint64_t i = 0; i < std::min<uint64_t>(8, size); ++i) {
      char b[4];
      std::snprintf(b, sizeof(b), "%02x ", head[i]);
      seen += b;
    }
    throw BagFormatError("not an MCAP file: it starts with " +
                         (seen.empty() ? std::string("nothing (empty file) ") : seen) +
                         "instead of the MCAP magic 89 4d 43 41 50 30 0d 0a");
  }
  // The Header record comes first.
  if (size < 8 + kRecordHeaderBytes)
    throw BagFormatError("truncated MCAP: the file ends inside its Header record");
  uint8_t header[kRecordHeaderBytes];
  bytes_->read(8, kRecordHeaderBytes, header);
  const uint64_t header_length = load_u64(header + 1);
  if (header[0] != kHeader)
    throw BagFormatError("malformed MCAP: the first record (byte 8) is " + record_name(header[0]) +
                         ", not Header");
  if (header_length > size - 8 - kRecordHeaderBytes || header_length > options_.max_record_bytes)
    throw BagFormatError("truncated MCAP: the Header record at byte 8 declares " +
                         std::to_string(header_length) + " bytes; the file has " +
                         std::to_string(size) + " bytes");
  std::vector<uint8_t> content(header_length);
  bytes_->read(8 + kRecordHeaderBytes, header_length, content.data());
  Fields fields(content.data(), header_length, at(kHeader, 8));
  profile_ = fields.string("profile");
  data_start_ = 8 + kRecordHeaderBytes + header_length;
  data_end_ = size;

  read_footer_and_summary();
  if (!has_summary_ || !has_message_counts_) {
    // Without a summary, or one without message counts: one pass over the data section.
    for (auto& [id, channel] : channels_) channel.messages = 0;
    scan_data_section();
  }
  resolve_schema_names();
}

void McapReader::read_footer_and_summary() {
  const uint64_t size = bytes_->size();
  if (size < data_start_ + kFooterRecordBytes + 8) return;
  uint8_t tail[kFooterRecordBytes + 8];
  const uint64_t footer_offset = size - sizeof(tail);
  bytes_->read(footer_offset, sizeof(tail), tail);
  if (std::memcmp(tail + kFooterRecordBytes, kMagic, 8) != 0) return;  // cut short: no footer
  if (tail[0] != kFooter || load_u64(tail + 1) != kFooterContentBytes)
    throw BagFormatError("malformed MCAP: no Footer record before the trailing magic (byte " +
                         std::to_string(footer_offset) + ")");
  complete_ = true;
  data_end_ = footer_offset;
  const uint64_t summary_start = load_u64(tail + 9);
  uint32_t summary_crc;
  std::memcpy(&summary_crc, tail + 25, 4);
  if (summary_start == 0) return;
  if (summary_start < data_start_ || summary_start > footer_offset)
    throw BagFormatError("malformed MCAP: the Footer's summary_start " +
                         std::to_string(summary_start) + " lies outside the data after the Header");
  const uint64_t summary_bytes = footer_offset - summary_start;
  if (summary_bytes > options_.max_record_bytes)
    throw BagFormatError("MCAP summary of " + std::to_string(summary_bytes) +
                         " bytes exceeds the reader's limit of " +
                         std::to_string(options_.max_record_bytes));
  std::vector<uint8_t> summary(summary_bytes);
  bytes_->read(summary_start, summary_bytes, summary.data());
  if (summary_crc != 0) {
    // Summary and summary offset sections, then the footer through summary_offset_start.
    uint32_t crc = io::crc32(summary.data(), summary.size());
    crc = io::crc32(tail, 1 + 8 + 8 + 8, crc);
    if (crc != summary_crc)
      throw BagFormatError("MCAP summary CRC mismatch: the Footer stores " + hex32(summary_crc) +
                           ", the summary at bytes " + std::to_string(summary_start) + ".." +
                           std::to_string(footer_offset) + " gives " + hex32(crc));
  }
  data_end_ = summary_start;
  has_summary_ = true;
  parse_summary(summary, summary_start);
}

void McapReader::parse_summary(const std::vector<uint8_t>& summary, uint64_t summary_start) {
  uint64_t p = 0;
  while (p < summary.size()) {
    const uint64_t offset = summary_start + p;
    if (summary.size() - p < kRecordHeaderBytes)
      throw BagFormatError("malformed MCAP summary: a record header at byte " +
                           std::to_string(offset) + " is cut off");
    const uint8_t opcode = summary[p];
    const uint64_t length = load_u64(&summary[p + 1]);
    if (length > summary.size() - p - kRecordHeaderBytes)
      throw BagFormatError("malformed MCAP summary: the " + at(opcode, offset) + " declares " +
                           std::to_string(length) + " bytes past the summary's end");
    const uint8_t* content = &summary[p + kRecordHeaderBytes];
    if (opcode == kSchema) {
      add_schema(content, length, offset);
    } else if (opcode == kChannel) {
      add_channel(content, length, offset);
    } else if (opcode == kChunkIndex) {
      Fields f(content, length, at(opcode, offset));
      f.u64("message_start_time");
      f.u64("message_end_time");
      const uint64_t chunk_offset = f.u64("chunk_start_offset");
      f.u64("chunk_length");
      const auto [map_begin, map_bytes] = f.block32("message_index_offsets");
      if (map_bytes % 10 != 0)
        throw BagFormatError(at(opcode, offset) + ": message_index_offsets of " +
                             std::to_string(map_bytes) + " bytes is not a whole number of " +
                             "(uint16, uint64) entries");
      std::vector<uint16_t> ids;
      for (uint64_t e = 0; e < map_bytes; e += 10) {
        uint16_t id;
        std::memcpy(&id, content + map_begin + e, 2);
        ids.push_back(id);
      }
      // An empty map means "not indexed": such a chunk is always read.
      if (!ids.empty()) chunk_channels_[chunk_offset] = std::move(ids);
    } else if (opcode == kStatistics) {
      Fields f(content, length, at(opcode, offset));
      f.u64("message_count");
      f.u16("schema_count");
      f.u32("channel_count");
      f.u32("attachment_count");
      f.u32("metadata_count");
      f.u32("chunk_count");
      f.u64("message_start_time");
      f.u64("message_end_time");
      const auto [map_begin, map_bytes] = f.block32("channel_message_counts");
      if (map_bytes % 10 != 0)
        throw BagFormatError(at(opcode, offset) + ": channel_message_counts of " +
                             std::to_string(map_bytes) + " bytes is not a whole number of " +
                             "(uint16, uint64) entries");
      has_message_counts_ = map_bytes > 0 && !channels_.empty();
      for (uint64_t e = 0; e < map_bytes; e += 10) {
        uint16_t id;
        std::memcpy(&id, content + map_begin + e, 2);
        const uint64_t count = load_u64(content + map_begin + e + 2);
        auto it = channels_.find(id);
        if (it != channels_.end()) it->second.messages = count;
      }
    }
    p += kRecordHeaderBytes + length;
  }
}

void McapReader::add_schema(const uint8_t* content, uint64_t size, uint64_t offset) {
  Fields f(content, size, at(kSchema, offset));
  const uint16_t id = f.u16("id");
  std::string name = f.string("name");
  f.string("encoding");
  f.block32("data");
  if (id != 0) schemas_[id] = std::move(name);  // id 0 is invalid and ignored (spec)
}

void McapReader::add_channel(const uint8_t* content, uint64_t size, uint64_t offset) {
  Fields f(content, size, at(kChannel, offset));
  McapChannel channel;
  channel.id = f.u16("id");
  channel.schema_id = f.u16("schema_id");
  channel.topic = f.string("topic");
  channel.message_encoding = f.string("message_encoding");
  f.block32("metadata");
  // Repeated definitions (data section and summary) must agree (spec: "must be identical").
  auto [it, inserted] = channels_.emplace(channel.id, channel);
  if (!inserted && (it->second.topic != channel.topic || it->second.schema_id != channel.schema_id))
    throw BagFormatError(at(kChannel, offset) + ": channel " + std::to_string(channel.id) +
                         " redefined as '" + channel.topic + "' (first defined as '" +
                         it->second.topic + "')");
}

void McapReader::resolve_schema_names() {
  for (auto& [id, channel] : channels_) {
    const auto it = schemas_.find(channel.schema_id);
    channel.schema_name = it == schemas_.end() ? "" : it->second;
  }
}

void McapReader::scan_data_section() {
  Cursor cursor(this, {}, /*scanning=*/true);
  McapMessage message;
  // A file cut short (or damaged) still opens with what precedes the damage; cursors over
  // the topics fail at the damage, naming their message.
  try {
    while (cursor.next(message)) {
    }
  } catch (const BagFormatError&) {
  }
}

McapReader::Cursor McapReader::messages(std::set<uint16_t> channel_ids) const {
  return Cursor(const_cast<McapReader*>(this), std::move(channel_ids), /*scanning=*/false);
}

McapReader::Cursor::Cursor(McapReader* reader, std::set<uint16_t> wanted, bool scanning)
    : reader_(reader),
      wanted_(std::move(wanted)),
      scanning_(scanning),
      position_(reader->data_start_) {}

bool McapReader::Cursor::wants(uint16_t channel) const {
  return wanted_.empty() || wanted_.count(channel) > 0;
}

bool McapReader::Cursor::chunk_has_wanted(uint64_t offset) const {
  if (scanning_ || wanted_.empty()) return true;
  const auto it = reader_->chunk_channels_.find(offset);
  if (it == reader_->chunk_channels_.end()) return true;
  for (const uint16_t id : it->second)
    if (wanted_.count(id)) return true;
  return false;
}

bool McapReader::Cursor::next(McapMessage& message) {
  while (!done_) {
    if (in_chunk_) {
      if (next_in_chunk(message)) return true;
      in_chunk_ = false;
    }
    const uint64_t end = reader_->data_end_;
    if (position_ >= end) {
      done_ = true;
      if (!reader_->complete_)
        throw BagFormatError("truncated MCAP: the data ends at byte " + std::to_string(end) +
                             " without a Data End record, Footer and closing magic (the "
                             "recording did not finish?)");
      return false;
    }
    record_offset_ = position_;
    if (end - position_ < kRecordHeaderBytes)
      throw BagFormatError("truncated MCAP: a record header at byte " + std::to_string(position_) +
                           " is cut off at byte " + std::to_string(end));
    uint8_t header[kRecordHeaderBytes];
    reader_->bytes_->read(position_, kRecordHeaderBytes, header);
    const uint8_t opcode = header[0];
    const uint64_t length = load_u64(header + 1);
    const uint64_t content_offset = position_ + kRecordHeaderBytes;
    if (length > end - content_offset)
      throw BagFormatError("truncated MCAP: the " + at(opcode, position_) + " declares " +
                           std::to_string(length) + " bytes; " +
                           std::to_string(end - content_offset) + " remain before byte " +
                           std::to_string(end));
    position_ = content_offset + length;
    switch (opcode) {
      case kDataEnd:
      case kFooter:
        done_ = true;
        return false;
      case kChunk:
        if (chunk_has_wanted(record_offset_)) {
          load_chunk(content_offset, length);
          in_chunk_ = true;
        }
        break;
      case kSchema:
      case kChannel:
      case kMessage: {
        if (!scanning_ && opcode != kMessage) break;
        if (opcode == kMessage && length >= 2) {
          // The channel decides whether the (maybe large) message is read at all.
          uint16_t channel_id;
          reader_->bytes_->read(content_offset, 2, reinterpret_cast<uint8_t*>(&channel_id));
          if (!wants(channel_id)) break;
        }
        if (length > reader_->options_.max_record_bytes)
          throw BagFormatError(at(opcode, record_offset_) + " of " + std::to_string(length) +
                               " bytes exceeds the reader's limit");
        // A lone record: served from `chunk_` like a one-record chunk.
        chunk_.resize(kRecordHeaderBytes + length);
        std::memcpy(chunk_.data(), header, kRecordHeaderBytes);
        reader_->bytes_->read(content_offset, length, chunk_.data() + kRecordHeaderBytes);
        chunk_position_ = 0;
        in_chunk_ = true;
        break;
      }
      default:
        break;  // Message Index, Attachment, Metadata, private records: not needed here
    }
  }
  return false;
}

void McapReader::Cursor::load_chunk(uint64_t offset, uint64_t length) {
  const std::string what = at(kChunk, record_offset_);
  // Fixed fields and the compression name: small; read them first.
  uint8_t fixed[8 + 8 + 8 + 4 + 4];
  if (length < sizeof(fixed))
    throw BagFormatError(what + ": " + std::to_string(length) + " bytes hold no chunk fields");
  reader_->bytes_->read(offset, sizeof(fixed), fixed);
  Fields f(fixed, sizeof(fixed), what);
  f.u64("message_start_time");
  f.u64("message_end_time");
  const uint64_t uncompressed_size = f.u64("uncompressed_size");
  const uint32_t uncompressed_crc = f.u32("uncompressed_crc");
  const uint32_t compression_bytes = f.u32("compression");
  const uint64_t rest = length - sizeof(fixed);
  if (compression_bytes > 16 || rest < compression_bytes + 8ull)
    throw BagFormatError(what + ": compression name of " + std::to_string(compression_bytes) +
                         " bytes does not fit the record");
  std::string compression(compression_bytes, '\0');
  uint8_t records_size_bytes[8];
  reader_->bytes_->read(offset + sizeof(fixed), compression_bytes,
                        reinterpret_cast<uint8_t*>(compression.data()));
  reader_->bytes_->read(offset + sizeof(fixed) + compression_bytes, 8, records_size_bytes);
  const uint64_t records_size = load_u64(records_size_bytes);
  const uint64_t records_offset = offset + sizeof(fixed) + compression_bytes + 8;
  if (records_size > rest - compression_bytes - 8)
    throw BagFormatError(what + ": records of " + std::to_string(records_size) +
                         " bytes run past the record's " + std::to_string(length) + " bytes");
  const uint64_t limit = reader_->options_.max_record_bytes;
  if (records_size > limit || uncompressed_size > limit)
    throw BagFormatError(what + ": " + std::to_string(uncompressed_size) +
                         " uncompressed bytes exceed the reader's limit of " +
                         std::to_string(limit));

  if (compression.empty()) {
    if (records_size != uncompressed_size)
      throw BagFormatError(what + ": uncompressed chunk holds " + std::to_string(records_size) +
                           " bytes, its uncompressed_size says " +
                           std::to_string(uncompressed_size));
    chunk_.resize(records_size);
    reader_->bytes_->read(records_offset, records_size, chunk_.data());
  } else {
    record_.resize(records_size);
    reader_->bytes_->read(records_offset, records_size, record_.data());
    chunk_.resize(uncompressed_size);
    if (compression == "zstd") {
      if (!zstd_)
        zstd_.reset(ZSTD_createDCtx(), [](void* c) { ZSTD_freeDCtx(static_cast<ZSTD_DCtx*>(c)); });
      const size_t n = ZSTD_decompressDCtx(static_cast<ZSTD_DCtx*>(zstd_.get()), chunk_.data(),
                                           chunk_.size(), record_.data(), record_.size());
      if (ZSTD_isError(n)) throw BagFormatError(what + ": zstd: " + ZSTD_getErrorName(n));
      if (n != uncompressed_size)
        throw BagFormatError(what + ": zstd data gives " + std::to_string(n) +
                             " bytes, uncompressed_size says " + std::to_string(uncompressed_size));
    } else if (compression == "lz4") {
      if (!lz4_) {
        LZ4F_dctx* context = nullptr;
        if (LZ4F_isError(LZ4F_createDecompressionContext(&context, LZ4F_VERSION)))
          throw BagFormatError(what + ": cannot create an lz4 decompression context");
        lz4_.reset(context,
                   [](void* c) { LZ4F_freeDecompressionContext(static_cast<LZ4F_dctx*>(c)); });
      }
      auto* context = static_cast<LZ4F_dctx*>(lz4_.get());
      LZ4F_resetDecompressionContext(context);
      size_t in_done = 0, out_done = 0, hint = 1;
      while (hint != 0) {
        size_t in_size = record_.size() - in_done;
        size_t out_size = chunk_.size() - out_done;
        hint = LZ4F_decompress(context, chunk_.data() + out_done, &out_size,
                               record_.data() + in_done, &in_size, nullptr);
        if (LZ4F_isError(hint)) throw BagFormatError(what + ": lz4: " + LZ4F_getErrorName(hint));
        in_done += in_size;
        out_done += out_size;
        if (hint != 0 && in_size == 0 && out_size == 0)
          throw BagFormatError(what +
                               ": lz4 frame ends early or gives more than uncompressed_size " +
                               std::to_string(uncompressed_size) + " bytes");
      }
      if (out_done != uncompressed_size)
        throw BagFormatError(what + ": lz4 data gives " + std::to_string(out_done) +
                             " bytes, uncompressed_size says " + std::to_string(uncompressed_size));
    } else {
      throw BagFormatError(what + ": unknown compression '" + compression +
                           "' (MCAP knows zstd, lz4 and none)");
    }
  }
  if (uncompressed_crc != 0) {
    const uint32_t crc = io::crc32(chunk_.data(), chunk_.size());
    if (crc != uncompressed_crc)
      throw BagFormatError(what + ": CRC mismatch: the chunk stores " + hex32(uncompressed_crc) +
                           ", its " + std::to_string(chunk_.size()) + " uncompressed bytes give " +
                           hex32(crc) + " (corrupt file)");
  }
  chunk_position_ = 0;
}

bool McapReader::Cursor::next_in_chunk(McapMessage& message) {
  while (chunk_position_ < chunk_.size()) {
    const uint64_t left = chunk_.size() - chunk_position_;
    if (left < kRecordHeaderBytes)
      throw BagFormatError(at(kChunk, record_offset_) + ": a record header at chunk byte " +
                           std::to_string(chunk_position_) + " is cut off");
    const uint8_t opcode = chunk_[chunk_position_];
    const uint64_t length = load_u64(&chunk_[chunk_position_ + 1]);
    if (length > left - kRecordHeaderBytes)
      throw BagFormatError(at(kChunk, record_offset_) + ": its " + record_name(opcode) +
                           " record at chunk byte " + std::to_string(chunk_position_) +
                           " declares " + std::to_string(length) + " bytes past the chunk's end");
    const uint8_t* content = &chunk_[chunk_position_ + kRecordHeaderBytes];
    const uint64_t inner_offset = chunk_position_;
    chunk_position_ += kRecordHeaderBytes + length;
    if (opcode == kSchema && scanning_) {
      reader_->add_schema(content, length, record_offset_ + inner_offset);
    } else if (opcode == kChannel && scanning_) {
      reader_->add_channel(content, length, record_offset_ + inner_offset);
    } else if (opcode == kMessage) {
      if (length < 2 + 4 + 8 + 8)
        throw BagFormatError(at(kMessage, record_offset_) + ": " + std::to_string(length) +
                             " bytes hold no message fields");
      uint16_t channel_id;
      std::memcpy(&channel_id, content, 2);
      if (!wants(channel_id)) continue;
      const auto it = reader_->channels_.find(channel_id);
      if (it == reader_->channels_.end())
        throw BagFormatError(at(kMessage, record_offset_) + ": message on channel " +
                             std::to_string(channel_id) + ", which no Channel record defines");
      if (scanning_) ++it->second.messages;
      message.channel = &it->second;
      std::memcpy(&message.sequence, content + 2, 4);
      message.log_time = load_u64(content + 6);
      message.publish_time = load_u64(content + 14);
      message.data = content + 22;
      message.size = length - 22;
      return true;
    }
  }
  return false;
}

}  // namespace keel::io
