#include "arbiter/diagnostics.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>

#include "core/document/utf8.hpp"

namespace arbiter {

Diagnostic& Diagnostics::error(const SourceLocation& where, std::string code, std::string message) {
  ++error_count_;
  return items_.emplace_back(
      Diagnostic{where, Severity::kError, std::move(code), std::move(message), {}});
}

Diagnostic& Diagnostics::warning(const SourceLocation& where, std::string code,
                                 std::string message) {
  return items_.emplace_back(
      Diagnostic{where, Severity::kWarning, std::move(code), std::move(message), {}});
}

void Diagnostics::append(const Diagnostics& other) {
  items_.insert(items_.end(), other.items_.begin(), other.items_.end());
  error_count_ += other.error_count_;
}

void Diagnostics::promote_warnings() {
  for (auto& item : items_) item.severity = Severity::kError;
  error_count_ = items_.size();
}

void Diagnostics::sort() {
  std::stable_sort(items_.begin(), items_.end(), [](const Diagnostic& a, const Diagnostic& b) {
    const auto& x = a.location;
    const auto& y = b.location;
    return std::tie(x.file, x.line, x.column) < std::tie(y.file, y.line, y.column);
  });
}

std::string printable(std::string_view text, bool lines) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size();) {
    const auto c = detail::utf8_char(text, i);
    if (c.length == 0) {
      out += fmt::format("\\x{:02x}", static_cast<unsigned char>(text[i]));
      ++i;
      continue;
    }
    if ((c.code < 0x20 && c.code != '\t' && !(lines && c.code == '\n')) || c.code == 0x7F) {
      out += fmt::format("\\x{:02x}", c.code);
    } else if (c.code >= 0x80 && c.code <= 0x9F) {
      out += fmt::format("\\u{:04x}", c.code);
    } else {
      out.append(text, i, c.length);
    }
    i += c.length;
  }
  return out;
}

std::string to_string(const SourceLocation& where) {
  if (where.line <= 0) return where.file;
  return fmt::format("{}:{}:{}", where.file, where.line, where.column);
}

namespace {

const char* severity_name(Severity severity) {
  return severity == Severity::kError ? "error" : "warning";
}

// ANSI escapes, as gcc and rustc colour their messages.
constexpr const char* kBold = "\x1b[1m";
constexpr const char* kRed = "\x1b[1;31m";
constexpr const char* kMagenta = "\x1b[1;35m";
constexpr const char* kCyan = "\x1b[1;36m";
constexpr const char* kBlue = "\x1b[1;34m";
constexpr const char* kGreen = "\x1b[1;32m";
constexpr const char* kReset = "\x1b[0m";

struct Paint {
  bool on;
  std::string operator()(const char* colour, std::string_view text) const {
    if (!on) return std::string(text);
    return fmt::format("{}{}{}", colour, text, kReset);
  }
};

// Config files are bounded by the load limits; a file larger than this was refused at load and
// gets no source line.
constexpr std::uintmax_t kMaxSourceBytes = 64u << 20;
// A longer line is shown as a window around the column.
constexpr std::size_t kMaxShownBytes = 160;

/// The lines of the files diagnostics point into, each file read once per format() call.
class SourceLines {
 public:
  /// The line (1-based) of `file`, without its line break; nullopt when unreadable.
  std::optional<std::string_view> line(const std::string& file, int number) {
    auto found = files_.find(file);
    if (found == files_.end()) found = files_.emplace(file, read(file)).first;
    const auto& lines = found->second;
    if (number <= 0 || static_cast<std::size_t>(number) > lines.size()) return std::nullopt;
    return std::string_view(lines[static_cast<std::size_t>(number) - 1]);
  }

 private:
  static std::vector<std::string> read(const std::string& file) {
    // Only regular files of a plausible size: a FIFO would block, /proc files claim size 0.
    std::error_code error;
    if (!std::filesystem::is_regular_file(file, error)) return {};
    const auto size = std::filesystem::file_size(file, error);
    if (error || size == 0 || size > kMaxSourceBytes) return {};
    std::ifstream in(file, std::ios::binary);
    std::vector<std::string> lines;
    for (std::string text; std::getline(in, text);) {
      if (!text.empty() && text.back() == '\r') text.pop_back();
      lines.push_back(std::move(text));
    }
    return lines;
  }

  std::map<std::string, std::vector<std::string>> files_;
};

bool is_continuation_byte(char c) {
  return (static_cast<unsigned char>(c) & 0xC0) == 0x80;
}

/// The bytes of the character at `i`: a byte that is not valid UTF-8 is a character of its own,
/// as printable() shows it.
std::size_t character_bytes(std::string_view line, std::size_t i) {
  return std::max<std::size_t>(1, detail::utf8_char(line, i).length);
}

/// The byte offset of the 1-based character column `column` in `line` (columns count
/// characters, as the Document's locations do); the line's size when past its end.
std::size_t byte_of_column(std::string_view line, int column) {
  int seen = 1;
  for (std::size_t i = 0; i < line.size(); i += character_bytes(line, i)) {
    if (seen == column) return i;
    ++seen;
  }
  return line.size();
}

/// The length in bytes of the YAML token that starts at `start`: a quoted scalar to its closing
/// quote, a flow collection to its closing bracket, a plain scalar up to what ends it (`: `,
/// `,`, a closing bracket, ` #`, the line's end), a name in an inhibition up to its arrow. At
/// least 1.
std::size_t token_bytes(std::string_view line, std::size_t start) {
  if (start >= line.size()) return 1;
  const char first = line[start];
  std::size_t end = start + 1;
  if (first == '"' || first == '\'') {
    while (end < line.size() && line[end] != first)
      end += line[end] == '\\' && first == '"' ? 2 : 1;
    return std::min(end + 1, line.size()) - start;
  }
  if (first == '{' || first == '[') {
    const char close = first == '{' ? '}' : ']';
    int depth = 1;
    for (; end < line.size() && depth > 0; ++end) {
      if (line[end] == first) ++depth;
      if (line[end] == close) --depth;
    }
    return end - start;
  }
  while (end < line.size()) {
    const char c = line[end];
    const bool followed_by_space = end + 1 == line.size() || line[end + 1] == ' ';
    const bool arrow =
        c == ' ' && (line.compare(end + 1, 2, "=>") == 0 || line.compare(end + 1, 2, "->") == 0);
    if (c == ',' || c == ']' || c == '}' || c == '"' || (c == ':' && followed_by_space) ||
        (c == '#' && line[end - 1] == ' ') || arrow) {
      break;
    }
    ++end;
  }
  while (end > start + 1 && line[end - 1] == ' ') --end;
  return end - start;
}

/// The bytes that `count` characters from `start` take, up to the line's end; at least 1.
std::size_t bytes_of_characters(std::string_view line, std::size_t start, int count) {
  std::size_t end = start;
  for (int seen = 0; end < line.size() && seen < count; ++seen) end += character_bytes(line, end);
  return std::max<std::size_t>(1, std::min(end, line.size()) - std::min(start, end));
}

/// Characters, not bytes: what the underline spans on screen.
std::size_t characters(std::string_view text) {
  std::size_t count = 0;
  for (const char c : text) count += is_continuation_byte(c) ? 0 : 1;
  return count;
}

/// `  12 | source line` and `     |   ^~~~` under it.
std::string source_excerpt(std::string_view line, const SourceLocation& where, Paint paint) {
  std::size_t start = byte_of_column(line, where.column);
  std::size_t length =
      where.length > 0 ? bytes_of_characters(line, start, where.length) : token_bytes(line, start);
  // A long line is cut to a window around the place, marked with "...".
  std::string_view shown = line;
  std::string before, after;
  if (line.size() > kMaxShownBytes) {
    std::size_t from = start > kMaxShownBytes / 4 ? start - kMaxShownBytes / 4 : 0;
    while (from > 0 && is_continuation_byte(line[from])) --from;
    std::size_t to = std::min(line.size(), from + kMaxShownBytes);
    while (to < line.size() && is_continuation_byte(line[to])) ++to;
    shown = line.substr(from, to - from);
    if (from > 0) before = "...";
    if (to < line.size()) after = "...";
    start -= from;
    length =
        std::min(length, std::max<std::size_t>(1, shown.size() - std::min(start, shown.size())));
  }
  // Escaped in three parts, so that the underline spans the escapes of what it marks.
  start = std::min(start, shown.size());
  const std::size_t end = start + std::min(length, shown.size() - start);
  const std::string lead = printable(shown.substr(0, start));
  const std::string marked = printable(shown.substr(start, end - start));
  // The underline keeps the line's tabs so that it lines up wherever the terminal's tab stops are.
  std::string pad = before.empty() ? "" : "   ";
  for (const char c : lead) {
    if (is_continuation_byte(c)) continue;
    pad += c == '\t' ? '\t' : ' ';
  }
  const std::size_t width = std::max<std::size_t>(1, characters(marked));
  const std::string number = std::to_string(where.line);
  const std::string gutter(number.size(), ' ');
  return fmt::format("{} {} {}{}{}{}{}\n{} {} {}{}\n", paint(kBlue, number), paint(kBlue, "|"),
                     before, lead, marked, printable(shown.substr(end)), after, gutter,
                     paint(kBlue, "|"), pad, paint(kGreen, "^" + std::string(width - 1, '~')));
}

std::string format_one(const Diagnostic& diagnostic, const FormatOptions& options,
                       SourceLines* sources, std::string_view given = {}) {
  const Paint paint{options.color};
  // Every part may quote input: a file name, a key, a trace line.
  const std::string where = printable(to_string(diagnostic.location));
  std::string label = severity_name(diagnostic.severity);
  if (options.codes && !diagnostic.code.empty()) label += fmt::format("[{}]", diagnostic.code);
  const char* colour = diagnostic.severity == Severity::kError ? kRed : kMagenta;
  std::string out = fmt::format("{}: {}: {}\n", paint(kBold, where), paint(colour, label),
                                paint(kBold, printable(diagnostic.message)));
  if (options.source && diagnostic.location.line > 0) {
    if (sources == nullptr) {
      out += source_excerpt(given, diagnostic.location, paint);
    } else if (const auto line =
                   sources->line(diagnostic.location.file, diagnostic.location.line)) {
      out += source_excerpt(*line, diagnostic.location, paint);
    }
  }
  for (const auto& note : diagnostic.notes) {
    out += fmt::format("{}: {} {}\n", paint(kBold, where), paint(kCyan, "note:"),
                       printable(note.text));
  }
  return out;
}

}  // namespace

std::string format(const Diagnostic& diagnostic, const FormatOptions& options) {
  SourceLines sources;
  return format_one(diagnostic, options, &sources);
}

std::string format(const Diagnostic& diagnostic, std::string_view source,
                   const FormatOptions& options) {
  return format_one(diagnostic, options, nullptr, source);
}

std::string format(const Diagnostics& diagnostics, const FormatOptions& options) {
  SourceLines sources;
  std::string out;
  for (const auto& item : diagnostics.items()) out += format_one(item, options, &sources);
  return out;
}

std::string format_json(const Diagnostics& diagnostics) {
  auto array = nlohmann::ordered_json::array();
  for (const auto& item : diagnostics.items()) {
    auto notes = nlohmann::ordered_json::array();
    auto places = nlohmann::ordered_json::array();
    bool placed = false;
    for (const auto& note : item.notes) {
      notes.push_back(note.text);
      if (note.location) {
        placed = true;
        places.push_back({{"file", note.location->file},
                          {"line", note.location->line},
                          {"column", note.location->column}});
      } else {
        places.push_back(nullptr);
      }
    }
    nlohmann::ordered_json entry = {{"file", item.location.file},
                                    {"line", item.location.line},
                                    {"column", item.location.column},
                                    {"severity", severity_name(item.severity)},
                                    {"code", item.code},
                                    {"message", item.message},
                                    {"notes", std::move(notes)}};
    // Only where a note has a place, so that the common diagnostic stays as it always was.
    if (placed) entry["note_locations"] = std::move(places);
    array.push_back(std::move(entry));
  }
  // JSON escapes control characters itself; a byte that is not UTF-8 (in a file name given on the
  // command line, say) becomes U+FFFD, where dump() would throw.
  return array.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) + "\n";
}

namespace {

// Optimal string alignment distance: insertions, deletions, substitutions and transpositions of
// neighbours each cost 1 ("gian" is one edit from "gain"). Three rows, not a full table: names
// in a hostile config can be megabytes long.
std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> before(b.size() + 1), previous(b.size() + 1), current(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) previous[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    current[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      current[j] = std::min({previous[j] + 1, current[j - 1] + 1, previous[j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) {
        current[j] = std::min(current[j], before[j - 2] + 1);
      }
    }
    std::swap(before, previous);
    std::swap(previous, current);
  }
  return previous[b.size()];
}

std::string lower(std::string_view text) {
  std::string out(text);
  for (auto& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

// How plausible `candidate` is as what was meant by `wrong`: lower is better; nullopt when it is
// too far to suggest.
std::optional<std::size_t> closeness(std::string_view wrong, std::string_view candidate) {
  const std::string a = lower(wrong);
  const std::string b = lower(candidate);
  if (a == b) return 0;  // only the case differs
  // One is the other cut short or extended ("rate" for "rate_hz", "activations").
  const std::size_t shorter = std::min(a.size(), b.size());
  if (shorter >= 3 && a.compare(0, shorter, b, 0, shorter) == 0) return 1;
  // Within a third of the name's length in edits, and within half of the part that differs once
  // a shared prefix and suffix are set aside: "gain" is not "in", "test.Feed" not "test.Tuned".
  // The distance is at least the difference in length; very long names are no typos worth an
  // edit distance (quadratic in their length).
  const std::size_t allowed = std::max<std::size_t>(1, wrong.size() / 3);
  constexpr std::size_t kMaxCompared = 128;
  if (std::max(a.size(), b.size()) - shorter > allowed || shorter > kMaxCompared) {
    return std::nullopt;
  }
  const std::size_t distance = edit_distance(a, b);
  if (distance > allowed) return std::nullopt;
  std::size_t prefix = 0;
  while (prefix < shorter && a[prefix] == b[prefix]) ++prefix;
  std::size_t suffix = 0;
  while (suffix < shorter - prefix && a[a.size() - 1 - suffix] == b[b.size() - 1 - suffix]) {
    ++suffix;
  }
  const std::size_t core = std::max(a.size(), b.size()) - prefix - suffix;
  if (distance > std::max<std::size_t>(1, core / 2)) return std::nullopt;
  return 1 + distance;
}

}  // namespace

// Beyond this many names no "did you mean" is looked for: a hostile config with many wrong names
// among many names would otherwise take time quadratic in its size.
constexpr std::size_t kMaxCandidates = 256;

std::optional<std::string> closest(std::string_view wrong, const std::vector<std::string>& known) {
  if (known.size() > kMaxCandidates) return std::nullopt;
  const std::string* best = nullptr;
  std::size_t best_score = 0;
  for (const auto& candidate : known) {
    if (candidate == wrong) continue;
    const auto score = closeness(wrong, candidate);
    // Ties go to the alphabetically first name, whatever the order of `known`.
    if (score &&
        (best == nullptr || *score < best_score || (*score == best_score && candidate < *best))) {
      best = &candidate;
      best_score = *score;
    }
  }
  if (best == nullptr) return std::nullopt;
  return *best;
}

std::string suggest(std::string_view wrong, const std::vector<std::string>& known,
                    std::string_view label) {
  if (known.empty()) return {};
  constexpr std::size_t kMaxListed = 12;
  std::vector<std::string> sorted = known;
  std::size_t total = 0;
  if (known.size() <= kMaxCandidates) {
    std::sort(sorted.begin(), sorted.end());
    sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
    total = sorted.size();
  } else {
    // Only the first few are listed: linear time, and the names are counted as given.
    const auto listed = sorted.begin() + static_cast<std::ptrdiff_t>(4 * kMaxListed);
    std::partial_sort(sorted.begin(), listed, sorted.end());
    sorted.erase(std::unique(sorted.begin(), listed), sorted.end());
    total = known.size();
  }
  std::string list;
  // "(1 more)" would take the place of the name itself.
  const std::size_t listed = total == kMaxListed + 1 ? total : kMaxListed;
  for (std::size_t i = 0; i < sorted.size() && i < listed; ++i) {
    if (i > 0) list += ", ";
    list += sorted[i];
  }
  if (total > listed) {
    list += fmt::format(", ... ({} more)", total - std::min(kMaxListed, sorted.size()));
  }
  if (const auto best = closest(wrong, known)) {
    return fmt::format("did you mean '{}'? {}: {}", *best, label, list);
  }
  return fmt::format("{}: {}", label, list);
}

Diagnostic& Diagnostic::unknown_name(std::string_view name, const std::vector<std::string>& known,
                                     std::string_view none_known, std::string_view label) {
  if (!known.empty()) {
    notes.push_back(suggest(name, known, label));
  } else if (!none_known.empty()) {
    notes.emplace_back(std::string(none_known));
  }
  return *this;
}

ConfigError::ConfigError(Diagnostics diagnostics)
    : std::runtime_error(format(diagnostics)), diagnostics_(std::move(diagnostics)) {}

}  // namespace arbiter
