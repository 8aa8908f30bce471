// The MCAP reader: tools read recordings back (replay, view, explain); a robot only writes them.

#include <fmt/format.h>
#include <zstd.h>

#include <cstring>

#include "mcap.hpp"

namespace arbiter::mcap {

namespace {

// Chunks larger than this when uncompressed are refused: no recording writes one, and a hostile
// file must not make the reader allocate what it claims.
constexpr std::uint64_t kMaxChunk = 256u << 20;

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
