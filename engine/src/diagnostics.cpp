#include "arbiter/diagnostics.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <nlohmann/json.hpp>
#include <optional>

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

namespace {

std::string format_location(const SourceLocation& where) {
  if (where.line <= 0) return where.file;
  return fmt::format("{}:{}:{}", where.file, where.line, where.column);
}

const char* severity_name(Severity severity) {
  return severity == Severity::kError ? "error" : "warning";
}

}  // namespace

std::string format(const Diagnostic& diagnostic) {
  const std::string where = format_location(diagnostic.location);
  std::string out =
      fmt::format("{}: {}: {}\n", where, severity_name(diagnostic.severity), diagnostic.message);
  for (const auto& note : diagnostic.notes) out += fmt::format("{}: note: {}\n", where, note);
  return out;
}

std::string format(const Diagnostics& diagnostics) {
  std::string out;
  for (const auto& item : diagnostics.items()) out += format(item);
  return out;
}

std::string format_json(const Diagnostics& diagnostics) {
  auto array = nlohmann::ordered_json::array();
  for (const auto& item : diagnostics.items()) {
    array.push_back({{"file", item.location.file},
                     {"line", item.location.line},
                     {"column", item.location.column},
                     {"severity", severity_name(item.severity)},
                     {"code", item.code},
                     {"message", item.message},
                     {"notes", item.notes}});
  }
  return array.dump(2) + "\n";
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
  for (std::size_t i = 0; i < sorted.size() && i < kMaxListed; ++i) {
    if (i > 0) list += ", ";
    list += sorted[i];
  }
  if (total > kMaxListed) {
    list += fmt::format(", ... ({} more)", total - std::min(kMaxListed, sorted.size()));
  }
  if (const auto best = closest(wrong, known)) {
    return fmt::format("did you mean '{}'? {}: {}", *best, label, list);
  }
  return fmt::format("{}: {}", label, list);
}

ConfigError::ConfigError(Diagnostics diagnostics)
    : std::runtime_error(format(diagnostics)), diagnostics_(std::move(diagnostics)) {}

}  // namespace arbiter
