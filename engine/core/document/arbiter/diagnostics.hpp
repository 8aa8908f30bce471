#pragma once
// Load-time problems are diagnostics, collected in one pass and reported together.

#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace arbiter {

/// A place in a config file. Lines and columns are 1-based; 0 means "unknown" (e.g. a whole file).
struct SourceLocation {
  std::string file;
  int line = 0;
  int column = 0;
  /// How many characters the place spans, for the underline; 0: the token at the column (a
  /// name, a scalar, a flow collection).
  int length = 0;

  /// The location `offset` characters further along the same line.
  SourceLocation shifted(int offset) const { return {file, line, column + offset}; }
};

/// "file:line:column", or "file" when the line is unknown: the one way a location is written.
std::string to_string(const SourceLocation& where);

enum class Severity { kError, kWarning };

/// A line under a diagnostic: a suggestion, or a place that bears on it ("first declared at
/// ..."). The text is what is printed and names the place itself; `location` is that place for
/// tools that link to it (the language server's related information, `--format json`).
struct Note {
  std::string text;
  std::optional<SourceLocation> location;

  // Implicit: most notes are text only.
  Note(std::string text) : text(std::move(text)) {}
  Note(const char* text) : text(text) {}
  Note(std::string text, SourceLocation where)
      : text(std::move(text)), location(std::move(where)) {}
};

struct Diagnostic {
  SourceLocation location;
  Severity severity = Severity::kError;
  std::string code;  ///< stable, kebab-case; listed in docs/diagnostics.md
  std::string message;
  std::vector<Note> notes;

  /// For a name that names nothing: the note offering the closest of `known` and listing them
  /// (suggest(name, known, label)), or `none_known` when `known` is empty (then no note if that
  /// is empty too). Every "unknown X" report writes its note this way.
  Diagnostic& unknown_name(std::string_view name, const std::vector<std::string>& known,
                           std::string_view none_known = {}, std::string_view label = "known");
};

/// The sink every pipeline stage reports into. Stages keep going after an error so that one run
/// shows every problem; the caller stops before the next stage when has_errors().
class Diagnostics {
 public:
  Diagnostic& error(const SourceLocation& where, std::string code, std::string message);
  Diagnostic& warning(const SourceLocation& where, std::string code, std::string message);

  bool has_errors() const { return error_count_ > 0; }
  std::size_t error_count() const { return error_count_; }
  std::size_t warning_count() const { return items_.size() - error_count_; }
  const std::vector<Diagnostic>& items() const { return items_; }
  /// An earlier report, to add notes to (one mistake, one error: what follows from it are notes).
  Diagnostic& at(std::size_t index) { return items_.at(index); }
  bool empty() const { return items_.empty(); }

  /// Adds every report of `other`, after these, as it was made.
  void append(const Diagnostics& other);

  /// Turns every warning into an error (`--strict`).
  void promote_warnings();

  /// Sorted by file, line and column, keeping the order of reports at the same place.
  void sort();

 private:
  std::vector<Diagnostic> items_;
  std::size_t error_count_ = 0;
};

/// How format() renders diagnostics. The default is the compact form (one line per diagnostic
/// and per note) that tests and the exception text use; people get `readable()`.
struct FormatOptions {
  bool codes = false;   ///< `error[unknown-key]:` instead of `error:`
  bool source = false;  ///< under each diagnostic, its source line with the place underlined
  bool color = false;   ///< ANSI colours (a terminal)

  /// Codes and source lines: what the CLI prints.
  static FormatOptions readable(bool color = false) { return {true, true, color}; }
};

/// `file:line:col: error: message` followed by one `file:line:col: note: ...` line per note.
/// With `options.source`, the line the location points into is read from its file (relative
/// names are resolved against the working directory, as when loading) and shown under the
/// message, numbered, with the token at the column (or the location's `length` characters)
/// underlined (`^~~~`); a file that cannot be read again simply gets no source line.
std::string format(const Diagnostic& diagnostic, const FormatOptions& options = {});
std::string format(const Diagnostics& diagnostics, const FormatOptions& options = {});
/// The same for a diagnostic about a text that is no file (a command-line argument, whose
/// location names the option, line 1): `source` is that text, shown as a file's line would be.
std::string format(const Diagnostic& diagnostic, std::string_view source,
                   const FormatOptions& options);

/// `text` made safe to print on a terminal, for every message that quotes input (format() does
/// this to what it prints): a control character (U+0000 to U+001F but the tab, U+007F) is written
/// `\x1b`, a C1 control (U+0080 to U+009F) `\u009b`, and each byte that is not part of valid UTF-8
/// `\xff`; everything else, valid UTF-8 such as "é" included, is kept. With `lines`, line feeds
/// are kept too (a text of several lines); otherwise they are `\x0a`, so that quoted input cannot
/// start a line of its own.
std::string printable(std::string_view text, bool lines = false);

/// A JSON array of {file, line, column, severity, code, message, notes, note_locations}: `notes`
/// holds each note's text, `note_locations` one entry per note, {file, line, column} or null.
std::string format_json(const Diagnostics& diagnostics);

/// "did you mean 'x'? known: a, b, c" for a misspelt name, or "known: ..." when nothing is close
/// (`label` replaces "known", e.g. "allowed"). Empty when `known` is empty. A name differing only
/// in case, a prefix of at least 3 characters, or one within a third of its length in edits
/// (a swap of neighbours counts as one) is close.
std::string suggest(std::string_view wrong, const std::vector<std::string>& known,
                    std::string_view label = "known");

/// The name suggest() would offer for `wrong`, if any is close.
std::optional<std::string> closest(std::string_view wrong, const std::vector<std::string>& known);

/// Thrown by the convenience API (load_program) when any stage reported an error.
class ConfigError : public std::runtime_error {
 public:
  explicit ConfigError(Diagnostics diagnostics);
  const Diagnostics& diagnostics() const { return diagnostics_; }

 private:
  Diagnostics diagnostics_;
};

}  // namespace arbiter
