// Where config texts come from: the disk, an editor's overlay, and the set of files one load read.

#include <fmt/format.h>

#include <cerrno>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <system_error>

#include "arbiter/document.hpp"

namespace arbiter {

namespace {

// Why the last system call failed, as ": Permission denied", or "" when errno says nothing.
std::string reason() {
  return errno == 0 ? std::string() : ": " + std::generic_category().message(errno);
}

}  // namespace

std::optional<std::string> FileSource::read(const std::string& path, Diagnostics& diagnostics,
                                            const ReadLimits& limits) const {
  namespace fs = std::filesystem;
  std::error_code error;
  const auto status = fs::status(path, error);
  if (status.type() == fs::file_type::not_found) {
    std::error_code link_error;
    if (fs::is_symlink(fs::symlink_status(path, link_error))) {
      diagnostics.error({path, 0, 0}, "file-not-found",
                        "is a symbolic link to a file that does not exist");
    } else {
      diagnostics.error({path, 0, 0}, "file-not-found",
                        "cannot open: " + std::generic_category().message(ENOENT));
    }
    return std::nullopt;
  }
  // The path exists but cannot be looked at: a symbolic link loop, a directory on the way that
  // cannot be searched.
  if (error) {
    diagnostics.error({path, 0, 0}, "unreadable-file",
                      fmt::format("cannot be read: {}", error.message()));
    return std::nullopt;
  }
  if (fs::is_directory(status)) {
    diagnostics.error({path, 0, 0}, "not-a-file", "is a directory, not a config file");
    return std::nullopt;
  }
  // Reading a FIFO or a device could block for ever or never end (/dev/zero).
  if (!fs::is_regular_file(status)) {
    diagnostics.error({path, 0, 0}, "not-a-file",
                      "is not a regular file (a FIFO, socket or device), not a config file");
    return std::nullopt;
  }
  const auto size = fs::file_size(path, error);
  if (!error && size > limits.max_file_bytes) {
    diagnostics.error(
        {path, 0, 0}, "file-too-large",
        fmt::format("the file has {} bytes; the limit is {}", size, limits.max_file_bytes));
    return std::nullopt;
  }
  errno = 0;
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    diagnostics.error({path, 0, 0}, "unreadable-file", "cannot be opened for reading" + reason());
    return std::nullopt;
  }
  std::string text;
  char buffer[1 << 16];
  while (in.read(buffer, sizeof buffer) || in.gcount() > 0) {
    text.append(buffer, static_cast<std::size_t>(in.gcount()));
    if (text.size() > limits.max_file_bytes) {
      diagnostics.error(
          {path, 0, 0}, "file-too-large",
          fmt::format("the file exceeds the limit of {} bytes", limits.max_file_bytes));
      return std::nullopt;
    }
  }
  if (in.bad()) {
    diagnostics.error({path, 0, 0}, "unreadable-file", "read error" + reason());
    return std::nullopt;
  }
  return text;
}

const FileSource& disk() {
  static const FileSource instance;
  return instance;
}

namespace {

std::string normal(const std::string& path) {
  return std::filesystem::path(path).lexically_normal().string();
}

}  // namespace

void Overlay::set(const std::string& path, std::string text) {
  texts_[normal(path)] = std::move(text);
}

void Overlay::erase(const std::string& path) {
  texts_.erase(normal(path));
}

const std::string* Overlay::find(const std::string& path) const {
  const auto found = texts_.find(normal(path));
  return found == texts_.end() ? nullptr : &found->second;
}

std::optional<std::string> Overlay::read(const std::string& path, Diagnostics& diagnostics,
                                         const ReadLimits& limits) const {
  const std::string* text = find(path);
  if (!text) return FileSource::read(path, diagnostics, limits);
  if (text->size() > limits.max_file_bytes) {
    diagnostics.error(
        {path, 0, 0}, "file-too-large",
        fmt::format("the file has {} bytes; the limit is {}", text->size(), limits.max_file_bytes));
    return std::nullopt;
  }
  return *text;
}

const Node* SourceFiles::read(const std::string& path, Diagnostics& diagnostics) {
  if (const SourceFile* file = find(path)) return file->root ? &*file->root : nullptr;
  auto text = source_->read(path, diagnostics, limits_);
  if (!text) return nullptr;
  auto file = std::make_unique<SourceFile>();
  file->path = path;
  file->text = std::move(*text);
  file->root = parse_document(file->text, path, format_of(path), diagnostics, limits_);
  files_.push_back(std::move(file));
  return files_.back()->root ? &*files_.back()->root : nullptr;
}

const SourceFile* SourceFiles::find(const std::string& path) const {
  for (const auto& file : files_) {
    if (file->path == path) return file.get();
  }
  return nullptr;
}

std::optional<Node> read_document(const std::string& path, Diagnostics& diagnostics,
                                  const ReadLimits& limits) {
  auto text = disk().read(path, diagnostics, limits);
  if (!text) return std::nullopt;
  return parse_document(*text, path, format_of(path), diagnostics, limits);
}

}  // namespace arbiter
