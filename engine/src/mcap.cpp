#include "mcap.hpp"

#include <fmt/format.h>
#include <zlib.h>
#include <zstd.h>

#include <cstdio>
#include <cstring>

namespace arbiter::mcap {

namespace {

enum Op : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

// Chunks larger than this when uncompressed are refused: no recording writes one, and a hostile
// file must not make the reader allocate what it claims.
constexpr std::uint64_t kMaxChunk = 256u << 20;

template <typename T>
void put(std::string& out, T value) {
  for (std::size_t i = 0; i < sizeof(T); ++i) {
    out += static_cast<char>(static_cast<std::uint64_t>(value) >> (8 * i) & 0xff);
  }
}

void put_string(std::string& out, std::string_view text) {
  put<std::uint32_t>(out, static_cast<std::uint32_t>(text.size()));
  out += text;
}

void put_record(std::string& out, Op op, std::string_view content) {
  put<std::uint8_t>(out, op);
  put<std::uint64_t>(out, content.size());
  out += content;
}

std::uint32_t crc(std::uint32_t running, std::string_view bytes) {
  return static_cast<std::uint32_t>(crc32(running, reinterpret_cast<const Bytef*>(bytes.data()),
                                          static_cast<uInt>(bytes.size())));
}

/// Reads little-endian fields from a record's content, failing (not throwing) past its end.
struct Cursor {
  std::string_view bytes;
  std::size_t at = 0;
  bool ok = true;

  template <typename T>
  T get() {
    if (!ok || bytes.size() - at < sizeof(T)) {
      ok = false;
      return T{};
    }
    std::uint64_t value = 0;
    for (std::size_t i = 0; i < sizeof(T); ++i) {
      value |= static_cast<std::uint64_t>(static_cast<unsigned char>(bytes[at + i])) << (8 * i);
    }
    at += sizeof(T);
    return static_cast<T>(value);
  }
  std::string_view take(std::uint64_t size) {
    if (!ok || bytes.size() - at < size) {
      ok = false;
      return {};
    }
    const auto out = bytes.substr(at, size);
    at += size;
    return out;
  }
  std::string_view string() { return take(get<std::uint32_t>()); }
  std::string_view rest() { return take(bytes.size() - at); }
};

}  // namespace

Writer::Writer(std::FILE* file, std::size_t chunk_size) : file_(file), chunk_size_(chunk_size) {
  write(kMagic);
}

void Writer::write(std::string_view bytes) {
  if (ok_ && std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size()) ok_ = false;
  offset_ += bytes.size();
  data_crc_ = crc(data_crc_, bytes);
}

void Writer::header(std::string_view profile, std::string_view library) {
  std::string content;
  put_string(content, profile);
  put_string(content, library);
  std::string record;
  put_record(record, kHeader, content);
  write(record);
}

std::uint16_t Writer::schema(std::string_view name, std::string_view encoding,
                             std::string_view data) {
  const auto id = ++schema_count_;  // 0 means "no schema"
  std::string content;
  put<std::uint16_t>(content, id);
  put_string(content, name);
  put_string(content, encoding);
  put_string(content, data);
  std::string record;
  put_record(record, kSchema, content);
  write(record);
  schemas_ += record;
  return id;
}

std::uint16_t Writer::channel(std::uint16_t schema, std::string_view topic,
                              std::string_view encoding) {
  const auto id = channel_count_++;
  std::string content;
  put<std::uint16_t>(content, id);
  put<std::uint16_t>(content, schema);
  put_string(content, topic);
  put_string(content, encoding);
  put<std::uint32_t>(content, 0);  // no channel metadata
  std::string record;
  put_record(record, kChannel, content);
  write(record);
  channels_ += record;
  counts_[id] = 0;
  return id;
}

void Writer::message(std::uint16_t channel, std::uint64_t log_time, std::string_view data) {
  if (chunk_.empty()) {
    chunk_start_ = log_time;
    chunk_end_ = log_time;
  }
  chunk_start_ = std::min(chunk_start_, log_time);
  chunk_end_ = std::max(chunk_end_, log_time);
  if (message_count_ == 0) first_time_ = log_time;
  first_time_ = std::min(first_time_, log_time);
  last_time_ = std::max(last_time_, log_time);
  ++message_count_;
  ++counts_[channel];
  index_[channel].emplace_back(log_time, chunk_.size());
  put<std::uint8_t>(chunk_, kMessage);
  put<std::uint64_t>(chunk_, 2 + 4 + 8 + 8 + data.size());
  put<std::uint16_t>(chunk_, channel);
  put<std::uint32_t>(chunk_, sequence_[channel]++);
  put<std::uint64_t>(chunk_, log_time);
  put<std::uint64_t>(chunk_, log_time);
  chunk_ += data;
  if (chunk_.size() >= chunk_size_) flush_chunk();
}

void Writer::flush_chunk() {
  if (chunk_.empty()) return;
  compressed_.resize(ZSTD_compressBound(chunk_.size()));
  const std::size_t size =
      ZSTD_compress(compressed_.data(), compressed_.size(), chunk_.data(), chunk_.size(), 3);
  if (ZSTD_isError(size)) {
    ok_ = false;
    chunk_.clear();
    return;
  }
  std::string content;
  put<std::uint64_t>(content, chunk_start_);
  put<std::uint64_t>(content, chunk_end_);
  put<std::uint64_t>(content, chunk_.size());
  put<std::uint32_t>(content, crc(0, chunk_));
  put_string(content, "zstd");
  put<std::uint64_t>(content, size);
  content.append(compressed_.data(), size);
  std::string record;
  put_record(record, kChunk, content);
  const std::uint64_t chunk_offset = offset_;
  write(record);

  std::string offsets;
  std::string indexes;
  for (const auto& [channel, entries] : index_) {
    put<std::uint16_t>(offsets, channel);
    put<std::uint64_t>(offsets, offset_ + indexes.size());
    std::string index;
    put<std::uint16_t>(index, channel);
    put<std::uint32_t>(index, static_cast<std::uint32_t>(entries.size() * 16));
    for (const auto& [time, at] : entries) {
      put<std::uint64_t>(index, time);
      put<std::uint64_t>(index, at);
    }
    put_record(indexes, kMessageIndex, index);
  }
  write(indexes);

  std::string chunk_index;
  put<std::uint64_t>(chunk_index, chunk_start_);
  put<std::uint64_t>(chunk_index, chunk_end_);
  put<std::uint64_t>(chunk_index, chunk_offset);
  put<std::uint64_t>(chunk_index, record.size());
  put<std::uint32_t>(chunk_index, static_cast<std::uint32_t>(offsets.size()));
  chunk_index += offsets;
  put<std::uint64_t>(chunk_index, indexes.size());
  put_string(chunk_index, "zstd");
  put<std::uint64_t>(chunk_index, size);
  put<std::uint64_t>(chunk_index, chunk_.size());
  put_record(chunk_indexes_, kChunkIndex, chunk_index);
  ++chunk_count_;
  chunk_.clear();
  index_.clear();
  std::fflush(file_);
}

void Writer::metadata(std::string_view name,
                      const std::vector<std::pair<std::string, std::string>>& map) {
  flush_chunk();
  std::string entries;
  for (const auto& [key, value] : map) {
    put_string(entries, key);
    put_string(entries, value);
  }
  std::string content;
  put_string(content, name);
  put_string(content, entries);
  std::string record;
  put_record(record, kMetadata, content);
  std::string index;
  put<std::uint64_t>(index, offset_);
  put<std::uint64_t>(index, record.size());
  put_string(index, name);
  put_record(metadata_indexes_, kMetadataIndex, index);
  ++metadata_count_;
  write(record);
  std::fflush(file_);
}

void Writer::finish() {
  flush_chunk();
  std::string data_end;
  put<std::uint32_t>(data_end, data_crc_);
  std::string record;
  put_record(record, kDataEnd, data_end);
  write(record);

  const std::uint64_t summary_start = offset_;
  std::string summary;
  std::string offsets;
  const auto group = [&](Op op, const std::string& records) {
    if (records.empty()) return;
    std::string content;
    put<std::uint8_t>(content, op);
    put<std::uint64_t>(content, summary_start + summary.size());
    put<std::uint64_t>(content, records.size());
    put_record(offsets, kSummaryOffset, content);
    summary += records;
  };
  group(kSchema, schemas_);
  group(kChannel, channels_);
  std::string statistics;
  put<std::uint64_t>(statistics, message_count_);
  put<std::uint16_t>(statistics, schema_count_);
  put<std::uint32_t>(statistics, channel_count_);
  put<std::uint32_t>(statistics, 0);  // attachments
  put<std::uint32_t>(statistics, metadata_count_);
  put<std::uint32_t>(statistics, chunk_count_);
  put<std::uint64_t>(statistics, first_time_);
  put<std::uint64_t>(statistics, last_time_);
  put<std::uint32_t>(statistics, static_cast<std::uint32_t>(counts_.size() * 10));
  for (const auto& [channel, count] : counts_) {
    put<std::uint16_t>(statistics, channel);
    put<std::uint64_t>(statistics, count);
  }
  std::string statistics_record;
  put_record(statistics_record, kStatistics, statistics);
  group(kStatistics, statistics_record);
  group(kChunkIndex, chunk_indexes_);
  group(kMetadataIndex, metadata_indexes_);

  const std::uint64_t offsets_start = summary_start + summary.size();
  std::string footer;
  put<std::uint8_t>(footer, kFooter);
  put<std::uint64_t>(footer, 8 + 8 + 4);
  put<std::uint64_t>(footer, summary_start);
  put<std::uint64_t>(footer, offsets_start);
  const std::uint32_t summary_crc = crc(crc(crc(0, summary), offsets), footer);
  put<std::uint32_t>(footer, summary_crc);
  write(summary);
  write(offsets);
  write(footer);
  write(kMagic);
  std::fflush(file_);
}

Reader::Reader(std::string bytes) : bytes_(std::move(bytes)) {}

bool Reader::fail(std::uint64_t at, std::string message) {
  if (error_.empty()) error_ = fmt::format("at byte {}: {}", at, message);
  return false;
}

bool Reader::inner(std::string_view records, std::uint64_t chunk_start) {
  Cursor in{records};
  while (in.ok && in.at < records.size()) {
    const auto op = in.get<std::uint8_t>();
    const auto length = in.get<std::uint64_t>();
    const auto content = in.take(length);
    if (!in.ok) return fail(chunk_start, "a record in the chunk runs past the chunk's end");
    Cursor c{content};
    if (op == kSchema) {
      const auto id = c.get<std::uint16_t>();
      c.string();
      c.string();
      c.string();
      if (!c.ok) return fail(chunk_start, "a schema record in the chunk is cut short");
      schemas_[id] = true;
    } else if (op == kChannel) {
      const auto id = c.get<std::uint16_t>();
      c.get<std::uint16_t>();
      topics_[id] = std::string(c.string());
      if (!c.ok) return fail(chunk_start, "a channel record in the chunk is cut short");
    } else if (op == kMessage) {
      Record record;
      const auto channel = c.get<std::uint16_t>();
      c.get<std::uint32_t>();
      record.log_time = c.get<std::uint64_t>();
      c.get<std::uint64_t>();
      record.data = std::string(c.rest());
      if (!c.ok) return fail(chunk_start, "a message record in the chunk is cut short");
      const auto topic = topics_.find(channel);
      if (topic == topics_.end()) {
        return fail(chunk_start, fmt::format("a message on channel {}, which no channel record "
                                             "declares",
                                             channel));
      }
      record.topic = topic->second;
      record.offset = chunk_start;
      pending_.push_back(std::move(record));
    } else {
      return fail(chunk_start, fmt::format("a chunk holds a record of opcode 0x{:02x}; chunks hold "
                                           "schemas, channels and messages",
                                           op));
    }
  }
  return true;
}

bool Reader::read_chunk(std::uint64_t start, std::string_view content) {
  Cursor c{content};
  c.get<std::uint64_t>();
  c.get<std::uint64_t>();
  const auto size = c.get<std::uint64_t>();
  const auto expected_crc = c.get<std::uint32_t>();
  const auto compression = c.string();
  const auto records = c.take(c.get<std::uint64_t>());
  if (!c.ok) return fail(start, "the chunk record is cut short");
  if (size > kMaxChunk) {
    return fail(start, fmt::format("the chunk claims {} bytes uncompressed; at most {} are read",
                                   size, kMaxChunk));
  }
  std::string plain;
  if (compression == "zstd") {
    plain.resize(size);
    const auto got = ZSTD_decompress(plain.data(), plain.size(), records.data(), records.size());
    if (ZSTD_isError(got)) {
      return fail(start, fmt::format("the chunk does not decompress: {}", ZSTD_getErrorName(got)));
    }
    if (got != size) {
      return fail(start, fmt::format("the chunk decompresses to {} bytes, not the {} it claims",
                                     got, size));
    }
  } else if (compression.empty()) {
    if (records.size() != size) {
      return fail(start, fmt::format("the chunk holds {} bytes, not the {} it claims",
                                     records.size(), size));
    }
    plain = std::string(records);
  } else {
    return fail(start, fmt::format("the chunk is compressed with '{}'; this reader knows zstd "
                                   "and none",
                                   compression));
  }
  if (expected_crc != 0 && crc(0, plain) != expected_crc) {
    return fail(start, "the chunk's CRC does not match its content");
  }
  return inner(plain, start);
}

bool Reader::next(Record& record) {
  if (!error_.empty()) return false;
  while (true) {
    if (pending_next_ < pending_.size()) {
      record = std::move(pending_[pending_next_++]);
      return true;
    }
    pending_.clear();
    pending_next_ = 0;
    if (done_) return false;
    if (!started_) {
      if (bytes_.size() < kMagic.size()) {
        if (kMagic.substr(0, bytes_.size()) == bytes_ && !bytes_.empty()) {
          truncated_ = done_ = true;
          return false;
        }
        return fail(0, "not an MCAP file (it does not start with MCAP's magic bytes)");
      }
      if (std::string_view(bytes_).substr(0, kMagic.size()) != kMagic) {
        return fail(0, "not an MCAP file (it does not start with MCAP's magic bytes)");
      }
      pos_ = kMagic.size();
      good_until_ = pos_;
      started_ = true;
    }
    const std::size_t start = pos_;
    if (bytes_.size() - pos_ < 9) {
      truncated_ = done_ = true;
      return false;
    }
    Cursor head{std::string_view(bytes_).substr(pos_, 9)};
    const auto op = head.get<std::uint8_t>();
    const auto length = head.get<std::uint64_t>();
    if (length > bytes_.size() - pos_ - 9) {
      truncated_ = done_ = true;
      return false;
    }
    const std::string_view content = std::string_view(bytes_).substr(pos_ + 9, length);
    pos_ += 9 + length;
    if (start == kMagic.size() && op != kHeader) {
      return fail(start, "the first record is not a header record (opcode 0x01)");
    }
    Cursor c{content};
    switch (op) {
      case kSchema: {
        const auto id = c.get<std::uint16_t>();
        c.string();
        c.string();
        c.string();
        if (!c.ok) return fail(start, "the schema record is cut short");
        schemas_[id] = true;
        break;
      }
      case kChannel: {
        const auto id = c.get<std::uint16_t>();
        c.get<std::uint16_t>();
        topics_[id] = std::string(c.string());
        if (!c.ok) return fail(start, "the channel record is cut short");
        break;
      }
      case kMessage:
        if (!inner(std::string_view(bytes_).substr(start, 9 + length), start)) return false;
        break;
      case kChunk:
        if (!read_chunk(start, content)) return false;
        break;
      case kMetadata: {
        record = Record();
        record.kind = Record::Kind::kMetadata;
        record.offset = start;
        record.name = std::string(c.string());
        Cursor map{c.take(c.get<std::uint32_t>())};
        if (!c.ok) return fail(start, "the metadata record is cut short");
        while (map.ok && map.at < map.bytes.size()) {
          auto key = std::string(map.string());
          auto value = std::string(map.string());
          record.metadata.emplace_back(std::move(key), std::move(value));
        }
        if (!map.ok) return fail(start, "the metadata record's map is cut short");
        good_until_ = pos_;
        return true;
      }
      case kDataEnd:
      case kFooter:
        done_ = true;
        break;
      default:
        break;  // indexes and records this reader does not need (the spec: skip unknown ones)
    }
    good_until_ = pos_;
  }
}

}  // namespace arbiter::mcap
