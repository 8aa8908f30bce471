#pragma once
// The MCAP container (https://mcap.dev/spec, major version 0) as far as recordings use it: a
// writer of chunked, zstd-compressed, indexed files with a summary, and a linear reader that
// checks every record, stops cleanly where a file was cut off, and checks the file's end (the
// data section's CRC, the summary, the footer and the closing magic).

#include <cstdint>
#include <istream>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace arbiter::mcap {

inline constexpr std::string_view kMagic{"\x89MCAP0\r\n", 8};

/// Record opcodes.
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

/// zlib's CRC-32 of `bytes`, continuing `running`: every CRC in a file is this one.
std::uint32_t crc(std::uint32_t running, std::string_view bytes);

/// Writes one MCAP file. Not thread-safe: one thread at a time owns it.
///
/// Every record goes to the file at once (a chunk when it is closed), with no buffer of its own
/// in between, so that after a failed write the file ends where the failure left it: whole
/// records up to there, then part of one at most, which a reader takes for a file cut off. After
/// a failed write nothing more is written.
class Writer {
 public:
  /// Writes to the open file descriptor `fd` (not owned), from its current offset.
  explicit Writer(int fd, std::size_t chunk_size = 256 * 1024);
  /// The magic and the header record: first of all.
  void header(std::string_view profile, std::string_view library);
  std::uint16_t schema(std::string_view name, std::string_view encoding, std::string_view data);
  std::uint16_t channel(std::uint16_t schema, std::string_view topic, std::string_view encoding);
  /// A message into the open chunk. The owner closes the chunk once chunk_full(), between
  /// messages that belong together: a file cut off after a chunk then holds all of them or none.
  /// `publish_time` is when it was published; the log time, by which readers order and seek, is
  /// the time it is about.
  void message(std::uint16_t channel, std::uint64_t log_time, std::string_view data) {
    message(channel, log_time, log_time, data);
  }
  void message(std::uint16_t channel, std::uint64_t log_time, std::uint64_t publish_time,
               std::string_view data);
  /// A metadata record (outside chunks, so the open chunk is closed first).
  void metadata(std::string_view name, const std::vector<std::pair<std::string, std::string>>& map);
  /// Writes the open chunk (if a message is in it) and its message indexes.
  void close_chunk();
  bool chunk_open() const { return !chunk_.empty(); }
  bool chunk_full() const { return chunk_.size() >= chunk_size_; }
  /// Closes the open chunk and writes the data end, the summary and the footer.
  void finish();
  /// False once a write to the file failed; error() is then its errno.
  bool ok() const { return error_ == 0; }
  int error() const { return error_; }

 private:
  void write(std::string_view bytes);

  int fd_;
  std::size_t chunk_size_;
  int error_ = 0;
  std::uint64_t offset_ = 0;
  std::uint32_t data_crc_ = 0;
  std::string schemas_;  // the schema and channel records again, for the summary
  std::string channels_;
  std::uint16_t schema_count_ = 0;
  std::uint16_t channel_count_ = 0;
  std::map<std::uint16_t, std::uint64_t> counts_;
  std::map<std::uint16_t, std::uint32_t> sequence_;
  std::uint64_t message_count_ = 0;
  std::uint64_t first_time_ = 0;
  std::uint64_t last_time_ = 0;
  std::string chunk_;  // uncompressed records of the open chunk
  std::uint64_t chunk_start_ = 0;
  std::uint64_t chunk_end_ = 0;
  std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> index_;
  std::string chunk_indexes_;
  std::uint32_t chunk_count_ = 0;
  std::string metadata_indexes_;
  std::uint32_t metadata_count_ = 0;
  std::string compressed_;
};

/// A record of the data section, chunks opened: what a recording reader needs.
struct Record {
  enum class Kind { kMessage, kMetadata };
  Kind kind = Kind::kMessage;
  std::string topic;  ///< kMessage: its channel's topic
  std::uint64_t log_time = 0;
  std::string data;  ///< kMessage: the message
  std::string name;  ///< kMetadata
  std::vector<std::pair<std::string, std::string>> metadata;
  std::uint64_t offset = 0;  ///< the byte of the file where the record (or its chunk) starts
};

/// Reads the records of a file in file order, one chunk at a time: what it holds at once is one
/// record and one chunk's messages, however long the file. Part of the tools library
/// (mcap_reader.cpp): a robot writes recordings, it does not read them.
class Reader {
 public:
  /// Reads `in`, which must outlive the reader.
  explicit Reader(std::istream& in);
  /// The next message or metadata record; false at the end, on an error (error() non-empty,
  /// "at byte N: ...") or where the file was cut off (truncated()).
  bool next(Record& record);
  const std::string& error() const { return error_; }
  bool truncated() const { return truncated_; }
  /// Where the last whole chunk (or record) ended, for a truncation message.
  std::uint64_t good_until() const { return good_until_; }
  /// Once next() has returned false after a whole data section: what is wrong past it (the
  /// data section's CRC, the summary, the footer, the closing magic), as a sentence for a
  /// warning; empty when the end is whole. The records read are whole either way.
  const std::string& damaged_end() const { return damaged_end_; }

 private:
  bool fail(std::uint64_t at, std::string message);
  bool read_chunk(std::uint64_t start, std::string_view content);
  bool inner(std::string_view records, std::uint64_t chunk_start);
  /// Reads `size` more bytes of the file into `out` (replacing it); false where the file ends.
  bool read(std::string& out, std::uint64_t size);
  /// After the data end record: the summary, the footer and the closing magic.
  void check_end();
  void damaged(std::uint64_t at, const std::string& what);

  std::istream* in_;
  std::uint64_t pos_ = 0;
  std::uint32_t data_crc_ = 0;  // of every byte before the data end record
  std::string head_;
  std::string content_;
  std::string plain_;  // the chunk being read, decompressed
  bool started_ = false;
  bool done_ = false;
  bool truncated_ = false;
  std::string error_;
  std::string damaged_end_;
  std::uint64_t good_until_ = 0;
  std::map<std::uint16_t, std::string> topics_;
  std::map<std::uint16_t, bool> schemas_;
  std::vector<Record> pending_;  // the messages of the chunk being read
  std::size_t pending_next_ = 0;
};

/// The one message for a recording cut off before its trace header, whichever tool reads it.
std::string cut_before_header(std::uint64_t whole_until);

}  // namespace arbiter::mcap
