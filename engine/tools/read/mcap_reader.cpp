// The MCAP reader: tools read recordings back (replay, view, explain); a robot only writes them.

#include <fmt/format.h>
#include <zstd.h>

#include <algorithm>
#include <cstring>

#include "core/record/mcap.hpp"

namespace arbiter::mcap {

namespace {

// Chunks larger than this when uncompressed are refused: no recording writes one, and a hostile
// file must not make the reader allocate what it claims.
constexpr std::uint64_t kMaxChunk = 256u << 20;
// A chunk record holds a compressed chunk, which zstd may make a little larger than the chunk.
constexpr std::uint64_t kMaxRecord = kMaxChunk + (1u << 20);
// Read in pieces of this size, so that a record claiming more than the file holds costs no more
// memory than the file has bytes.
constexpr std::uint64_t kPiece = 1u << 20;

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

Reader::Reader(std::istream& in) : in_(&in) {}

std::string cut_before_header(std::uint64_t whole_until) {
  return fmt::format(
      "the recording was cut off while it was written, before its trace header: it holds no "
      "step (it is whole up to byte {})",
      whole_until);
}

bool Reader::read(std::string& out, std::uint64_t size) {
  out.clear();
  while (out.size() < size) {
    const auto had = out.size();
    const auto piece = std::min<std::uint64_t>(size - had, kPiece);
    out.resize(had + piece);
    in_->read(&out[had], static_cast<std::streamsize>(piece));
    const auto got = static_cast<std::size_t>(in_->gcount());
    out.resize(had + got);
    pos_ += got;
    // A read error is no end of the file: told as an error, not as a recording cut off.
    if (in_->bad()) return fail(pos_, "cannot read the recording");
    if (got < piece) return false;
  }
  return true;
}

void Reader::damaged(std::uint64_t at, const std::string& what) {
  if (!damaged_end_.empty()) return;
  damaged_end_ = fmt::format(
      "the end of the recording is not whole: at byte {}: {}; its steps are read in order, but "
      "tools that read a recording's summary first (Foxglove, @mcap/core's indexed reader) may "
      "refuse it",
      at, what);
}

void Reader::check_end() {
  const std::uint64_t summary_start = pos_;
  bool summary = false;
  std::uint64_t offsets_start = 0;
  std::uint32_t summary_crc = 0;
  while (true) {
    const std::uint64_t start = pos_;
    if (!read(head_, 9)) {
      return damaged(start, "the file ends in its summary, before its footer");
    }
    Cursor head{head_};
    const auto op = head.get<std::uint8_t>();
    const auto length = head.get<std::uint64_t>();
    if (op == kFooter) {
      if (length != 20) {
        return damaged(start, fmt::format("the footer record holds {} bytes, not 20", length));
      }
      if (!read(content_, length)) return damaged(start, "the footer is cut short");
      Cursor footer{content_};
      const auto footer_summary = footer.get<std::uint64_t>();
      const auto footer_offsets = footer.get<std::uint64_t>();
      const auto footer_crc = footer.get<std::uint32_t>();
      summary_crc = crc(crc(summary_crc, head_), std::string_view(content_).substr(0, 16));
      if (footer_summary != (summary ? summary_start : 0)) {
        return damaged(start, fmt::format("the footer puts the summary at byte {}; it is at "
                                          "byte {}",
                                          footer_summary, summary ? summary_start : 0));
      }
      if (footer_offsets != offsets_start) {
        return damaged(start, fmt::format("the footer puts the summary offsets at byte {}; they "
                                          "are at byte {}",
                                          footer_offsets, offsets_start));
      }
      if (footer_crc != 0 && footer_crc != summary_crc) {
        return damaged(start, "the footer's summary CRC does not match the summary");
      }
      const std::uint64_t end = pos_;
      if (!read(head_, kMagic.size()) || head_ != kMagic) {
        return damaged(end, "the file does not end with MCAP's magic bytes after its footer");
      }
      return;
    }
    if (length > kMaxRecord) {
      return damaged(start, fmt::format("a summary record claims {} bytes", length));
    }
    if (!read(content_, length)) {
      return damaged(start, "the file ends in its summary, before its footer");
    }
    summary_crc = crc(crc(summary_crc, head_), content_);
    if (op == kSummaryOffset) {
      if (offsets_start == 0) offsets_start = start;
    } else if (offsets_start == 0) {
      summary = true;
    }
  }
}

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
  std::string& plain = plain_;
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
    plain.assign(records);
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
      started_ = true;
      if (!read(head_, kMagic.size())) {
        if (!head_.empty() && kMagic.substr(0, head_.size()) == head_) {
          truncated_ = done_ = true;
          return false;
        }
        return fail(0, "not an MCAP file (it does not start with MCAP's magic bytes)");
      }
      if (head_ != kMagic) {
        return fail(0, "not an MCAP file (it does not start with MCAP's magic bytes)");
      }
      data_crc_ = crc(0, head_);
      good_until_ = pos_;
    }
    const std::uint64_t start = pos_;
    if (!read(head_, 9)) {
      truncated_ = done_ = true;
      return false;
    }
    Cursor head{head_};
    const auto op = head.get<std::uint8_t>();
    const auto length = head.get<std::uint64_t>();
    if (length > kMaxRecord) {
      return fail(start,
                  fmt::format("a record claims {} bytes; at most {} are read", length, kMaxRecord));
    }
    if (!read(content_, length)) {
      truncated_ = done_ = true;
      return false;
    }
    if (start == kMagic.size() && op != kHeader) {
      return fail(start, "the first record is not a header record (opcode 0x01)");
    }
    if (op != kDataEnd) data_crc_ = crc(crc(data_crc_, head_), content_);
    const std::string_view content = content_;
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
        if (!inner(head_ + content_, start)) return false;
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
      case kDataEnd: {
        done_ = true;
        const auto data_crc = c.get<std::uint32_t>();  // 0: not computed
        if (!c.ok) {
          damaged(start, "the data end record is cut short");
        } else if (data_crc != 0 && data_crc != data_crc_) {
          damaged(start, "the data end record's CRC does not match the data section");
        }
        check_end();
        break;
      }
      case kFooter:
        done_ = true;
        damaged(start, "the data section has no data end record");
        break;
      default:
        break;  // indexes and records this reader does not need (the spec: skip unknown ones)
    }
    if (!done_) good_until_ = pos_;
  }
}

}  // namespace arbiter::mcap
