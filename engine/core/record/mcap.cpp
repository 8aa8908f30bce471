#include <fmt/format.h>
#include <unistd.h>
#include <zlib.h>
#include <zstd.h>

#include <cerrno>
#include <cstring>

#include "core/record/mcap.hpp"

namespace arbiter::mcap {

std::uint32_t crc(std::uint32_t running, std::string_view bytes) {
  return static_cast<std::uint32_t>(crc32(running, reinterpret_cast<const Bytef*>(bytes.data()),
                                          static_cast<uInt>(bytes.size())));
}

namespace {

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

}  // namespace

Writer::Writer(int fd, std::size_t chunk_size) : fd_(fd), chunk_size_(chunk_size) {}

void Writer::write(std::string_view bytes) {
  while (error_ == 0 && !bytes.empty()) {
    const auto written = ::write(fd_, bytes.data(), bytes.size());
    if (written < 0) {
      if (errno != EINTR) error_ = errno;
      continue;
    }
    // A short write stops at a limit (a file size limit, a full disk): the next one says which.
    offset_ += static_cast<std::uint64_t>(written);
    data_crc_ = crc(data_crc_, bytes.substr(0, static_cast<std::size_t>(written)));
    bytes.remove_prefix(static_cast<std::size_t>(written));
  }
}

void Writer::header(std::string_view profile, std::string_view library) {
  write(kMagic);
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

void Writer::message(std::uint16_t channel, std::uint64_t log_time, std::uint64_t publish_time,
                     std::string_view data) {
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
  put<std::uint64_t>(chunk_, publish_time);
  chunk_ += data;
}

void Writer::close_chunk() {
  if (chunk_.empty()) return;
  compressed_.resize(ZSTD_compressBound(chunk_.size()));
  const std::size_t size =
      ZSTD_compress(compressed_.data(), compressed_.size(), chunk_.data(), chunk_.size(), 3);
  if (ZSTD_isError(size)) {
    // Only for want of memory: the chunk is lost, as a write of it that failed would lose it.
    if (error_ == 0) error_ = ENOMEM;
    chunk_.clear();
    index_.clear();
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
}

void Writer::metadata(std::string_view name,
                      const std::vector<std::pair<std::string, std::string>>& map) {
  close_chunk();
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
}

void Writer::finish() {
  close_chunk();
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
}

}  // namespace arbiter::mcap
