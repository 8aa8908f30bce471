#pragma once
// engine/core/document: config text (YAML, JSON, includes) in; a Document whose nodes keep their
// file:line:column out, with the Diagnostics that point into it. Every later stage reads these.
//
// Stage 1 of the data path: a config file (YAML or JSON) parsed into one tree type in which every
// node carries its file:line:column. Nothing after read_document sees a yaml-cpp or nlohmann type.

#include <cstddef>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "arbiter/diagnostics.hpp"

namespace arbiter {

/// A place in a config file as the Document keeps it: every node of a file shares one copy of the
/// file's name. Converts to the SourceLocation that diagnostics take.
class NodeLocation {
 public:
  NodeLocation() = default;
  NodeLocation(std::shared_ptr<const std::string> file, int line, int column)
      : file_(std::move(file)), line_(line), column_(column) {}

  const std::string& file() const;
  int line() const { return line_; }
  int column() const { return column_; }

  SourceLocation get() const { return {file(), line_, column_}; }
  // Implicit, so that a key's location is passed to Diagnostics and stored as before.
  operator SourceLocation() const { return get(); }

 private:
  std::shared_ptr<const std::string> file_;
  int line_ = 0;
  int column_ = 0;
};

class Node {
 public:
  enum class Kind { kNull, kScalar, kSequence, kMapping };

  struct Entry;

  Node() = default;
  Node(Kind kind, NodeLocation location) : kind_(kind), location_(std::move(location)) {}

  Kind kind() const { return kind_; }
  SourceLocation location() const { return location_.get(); }
  const NodeLocation& node_location() const { return location_; }
  bool is_null() const { return kind_ == Kind::kNull; }
  bool is_scalar() const { return kind_ == Kind::kScalar; }
  bool is_sequence() const { return kind_ == Kind::kSequence; }
  bool is_mapping() const { return kind_ == Kind::kMapping; }

  /// The scalar's text as written (without quotes).
  const std::string& text() const { return text_; }
  /// Where the character at byte `offset` of text() was written, when the text appears verbatim
  /// on one line of the file (no escapes, no folding); otherwise location().
  SourceLocation text_location(std::size_t offset) const;
  /// True for a quoted YAML scalar and every JSON string: never a number, boolean or null.
  bool quoted() const { return quoted_; }

  const std::vector<Node>& items() const { return items_; }
  const std::vector<Entry>& entries() const { return entries_; }
  /// The value at `key` in a mapping, or nullptr.
  const Node* find(std::string_view key) const;

  /// Typed readings of a scalar under the YAML 1.2 core schema; nullopt when it is not one.
  std::optional<bool> as_bool() const;
  std::optional<long long> as_int() const;
  std::optional<double> as_double() const;  ///< ints count as doubles; may be inf or nan
  /// True for a plain scalar that reads as null (`~`, `null`) or an empty node.
  bool reads_as_null() const;

  /// What the node is, for messages: "a mapping", "a list of 3 items", "the string 'x'",
  /// "the number 2", "the boolean true", "null".
  std::string describe() const;

  // Builders, used by the readers.
  void set_scalar(std::string text, bool quoted);
  /// Records that text() appears verbatim in the file from this 1-based column of the node's line.
  void set_text_column(int column) { text_column_ = column; }
  Node& push_item(Node item);
  Entry& add_entry(std::string key, NodeLocation key_location, Node value);
  std::size_t size() const { return is_mapping() ? entries_.size() : items_.size(); }

 private:
  Kind kind_ = Kind::kNull;
  bool quoted_ = false;
  int text_column_ = 0;  // 0: the text is not verbatim in the file
  NodeLocation location_;
  std::string text_;
  std::vector<Node> items_;
  std::vector<Entry> entries_;
};

struct Node::Entry {
  std::string key;
  NodeLocation key_location;
  Node value;
};

/// Bounds that keep hostile files from exhausting time or memory.
struct ReadLimits {
  std::size_t max_file_bytes = 16u << 20;
  /// Levels of nested mappings and lists (JSON objects and arrays). The one nesting limit of every
  /// reader: configs, scenario files, traces, recordings and the language server's messages.
  std::size_t max_depth = 200;
  std::size_t max_nodes = 1u << 20;  ///< after alias expansion
};

/// The byte offset of the first `[` or `{` of the JSON `text` that opens a level deeper than
/// `max_depth`, or nullopt. A linear scan that builds nothing, for the readers to call before
/// they build a tree: copying, comparing and printing a JSON tree recurse once per level, so a
/// record nested 100 000 deep would overflow the stack. Text that is not JSON is scanned all the
/// same; its syntax is the parser's business.
std::optional<std::size_t> find_too_deep_json(std::string_view text,
                                              std::size_t max_depth = ReadLimits().max_depth);

enum class DocumentFormat { kYaml, kJson };

/// The format a path's extension names (`.json` is JSON, everything else YAML).
DocumentFormat format_of(std::string_view path);

/// Parses `text` (named `file` in diagnostics). JSON is checked strictly first. Duplicate keys,
/// non-scalar keys, multiple documents, excess depth and alias expansion past the node limit are
/// errors. Returns nullopt after reporting when the text cannot be read; after an error that
/// leaves a usable tree (a duplicate key is dropped, a second document ignored) it returns the
/// tree, so that later stages can report their problems in the same pass. Columns count
/// characters (code points), not bytes.
std::optional<Node> parse_document(std::string_view text, const std::string& file,
                                   DocumentFormat format, Diagnostics& diagnostics,
                                   const ReadLimits& limits = {});

/// Where the pipeline reads a config's text: the disk, unless an editor's unsaved buffers are
/// put in front (Overlay).
class FileSource {
 public:
  virtual ~FileSource() = default;
  /// The text of `path`; nullopt after reporting (at `{path, 0, 0}`) an unreadable path, a
  /// directory or a file over the size limit.
  virtual std::optional<std::string> read(const std::string& path, Diagnostics& diagnostics,
                                          const ReadLimits& limits) const;
};

/// The files on disk.
const FileSource& disk();

/// Texts held in memory, by path, in front of the disk: a path that has a text is never read
/// from disk. Paths are compared after lexical normalisation.
class Overlay : public FileSource {
 public:
  void set(const std::string& path, std::string text);
  void erase(const std::string& path);
  /// The text held for `path`, or nullptr.
  const std::string* find(const std::string& path) const;
  std::optional<std::string> read(const std::string& path, Diagnostics& diagnostics,
                                  const ReadLimits& limits) const override;

 private:
  std::map<std::string, std::string> texts_;
};

/// A file read by the pipeline: its text and, when it could be parsed, its tree.
struct SourceFile {
  std::string path;
  std::string text;
  std::optional<Node> root;
};

/// The files of one load, each read once through a FileSource and kept with its text, in the
/// order they were read (the config first, then its includes).
class SourceFiles {
 public:
  explicit SourceFiles(const FileSource& source = disk(), ReadLimits limits = {})
      : source_(&source), limits_(limits) {}

  /// The tree of `path`, read and parsed on first use; nullptr after reporting when it cannot
  /// be read or parsed (the text, if read, is kept all the same).
  const Node* read(const std::string& path, Diagnostics& diagnostics);

  const std::vector<std::unique_ptr<SourceFile>>& files() const { return files_; }
  /// The file read as `path`, or nullptr.
  const SourceFile* find(const std::string& path) const;
  const ReadLimits& limits() const { return limits_; }

 private:
  const FileSource* source_;
  ReadLimits limits_;
  std::vector<std::unique_ptr<SourceFile>> files_;
};

/// Reads and parses a file; unreadable paths, directories and oversized files are reported.
std::optional<Node> read_document(const std::string& path, Diagnostics& diagnostics,
                                  const ReadLimits& limits = {});

}  // namespace arbiter
