#include "arbiter/breakpoint.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <nlohmann/json.hpp>
#include <typeinfo>

namespace arbiter {

namespace {

/// The parser's place in a condition's text; columns count from 1.
class Cursor {
 public:
  explicit Cursor(std::string_view text) : text_(text) {}

  void skip_blanks() {
    while (at_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[at_]))) ++at_;
  }
  bool done() {
    skip_blanks();
    return at_ >= text_.size();
  }
  int column() const { return static_cast<int>(at_) + 1; }
  char peek() const { return at_ < text_.size() ? text_[at_] : '\0'; }
  bool take(std::string_view token) {
    skip_blanks();
    if (text_.substr(at_, token.size()) != token) return false;
    at_ += token.size();
    return true;
  }
  /// `[A-Za-z_][A-Za-z0-9_]*`, optionally `/` and another: a name as explain takes it.
  std::string_view name() {
    skip_blanks();
    const auto start = at_;
    const auto word = [&] {
      if (at_ >= text_.size() ||
          !(std::isalpha(static_cast<unsigned char>(text_[at_])) != 0 || text_[at_] == '_')) {
        return false;
      }
      while (at_ < text_.size() &&
             (std::isalnum(static_cast<unsigned char>(text_[at_])) != 0 || text_[at_] == '_')) {
        ++at_;
      }
      return true;
    };
    if (!word()) return {};
    if (peek() == '/') {
      ++at_;
      if (!word()) {
        at_ = start;
        return {};
      }
    }
    return text_.substr(start, at_ - start);
  }
  /// A run of characters that may be part of a number.
  std::string_view number() {
    skip_blanks();
    const auto start = at_;
    while (at_ < text_.size() && (std::isalnum(static_cast<unsigned char>(text_[at_])) != 0 ||
                                  text_[at_] == '.' || text_[at_] == '-' || text_[at_] == '+')) {
      ++at_;
    }
    return text_.substr(start, at_ - start);
  }
  std::string_view rest() const { return text_.substr(std::min(at_, text_.size())); }
  std::size_t offset() const { return at_; }
  void advance(std::size_t n) { at_ += n; }

 private:
  std::string_view text_;
  std::size_t at_ = 0;
};

constexpr const char* kForms =
    "write NAME activates, NAME deactivates, MACHINE/STATE starts, MACHINE/STATE ends, "
    "NAME[i] > X, NAME[i] < X, event ~ \"TEXT\", step N or step >= N";

std::optional<Condition> fail(ConditionError& error, int column, int length, std::string message,
                              std::vector<Note> notes = {}, std::string code = "bad-condition") {
  error.column = column;
  error.length = length;
  error.code = std::move(code);
  error.message = std::move(message);
  error.notes = std::move(notes);
  return std::nullopt;
}

bool parse_unsigned(std::string_view text, std::uint64_t& out) {
  if (text.empty() || text.size() > 19) return false;
  out = 0;
  for (const char c : text) {
    if (c < '0' || c > '9') return false;
    out = out * 10 + static_cast<std::uint64_t>(c - '0');
  }
  return true;
}

bool parse_double(std::string_view text, double& out) {
  if (text.empty()) return false;
  const std::string copy(text);
  char* end = nullptr;
  errno = 0;
  out = std::strtod(copy.c_str(), &end);
  return end == copy.c_str() + copy.size() && errno == 0 && std::isfinite(out);
}

const char* kind_word(Condition::Kind kind) {
  switch (kind) {
    case Condition::Kind::kActivates:
      return "activates";
    case Condition::Kind::kDeactivates:
      return "deactivates";
    case Condition::Kind::kStarts:
      return "starts";
    case Condition::Kind::kEnds:
      return "ends";
    case Condition::Kind::kAbove:
      return ">";
    case Condition::Kind::kBelow:
      return "<";
    case Condition::Kind::kEvent:
      return "event";
    case Condition::Kind::kStep:
    case Condition::Kind::kStepFrom:
      break;
  }
  return "step";
}

}  // namespace

std::optional<Condition> parse_condition(std::string_view whole, ConditionError& error) {
  // Trimmed, so that columns count in the text the break is named by.
  while (!whole.empty() && std::isspace(static_cast<unsigned char>(whole.front())) != 0) {
    whole.remove_prefix(1);
  }
  while (!whole.empty() && std::isspace(static_cast<unsigned char>(whole.back())) != 0) {
    whole.remove_suffix(1);
  }
  Condition condition;
  condition.text = std::string(whole);
  Cursor in(whole);
  if (in.done()) return fail(error, 1, 0, "empty condition", {kForms});
  const int name_column = in.column();
  const auto name = in.name();
  if (name.empty()) {
    return fail(error, in.column(), 0, "expected a name, 'event' or 'step'", {kForms});
  }
  if (name == "step") {
    condition.kind = in.take(">=") ? Condition::Kind::kStepFrom : Condition::Kind::kStep;
    const int column = (in.skip_blanks(), in.column());
    const auto number = in.number();
    if (!parse_unsigned(number, condition.step) || condition.step == 0) {
      return fail(error, column, static_cast<int>(number.size()),
                  number.empty()
                      ? "expected a step number after 'step'"
                      : fmt::format("'{}' is no step number (steps count from 1)", number));
    }
  } else if (name == "event") {
    condition.kind = Condition::Kind::kEvent;
    if (!in.take("~")) {
      return fail(error, in.column(), 0, "expected '~' after 'event'",
                  {"write event ~ \"TEXT\": a reported event whose text contains TEXT"});
    }
    in.skip_blanks();
    const int quote_column = in.column();
    if (in.peek() != '"') return fail(error, quote_column, 0, "expected a quoted text after '~'");
    in.advance(1);
    bool closed = false;
    while (!in.rest().empty()) {
      const char c = in.peek();
      in.advance(1);
      if (c == '"') {
        closed = true;
        break;
      }
      if (c == '\\' && (in.peek() == '"' || in.peek() == '\\')) {
        condition.pattern += in.peek();
        in.advance(1);
        continue;
      }
      condition.pattern += c;
    }
    if (!closed) return fail(error, quote_column, 1, "the quoted text is not closed");
    if (condition.pattern.empty())
      return fail(error, quote_column, 2, "the text to match is empty");
  } else {
    condition.name = std::string(name);
    condition.name_column = name_column;
    if (in.take("[")) {
      in.skip_blanks();
      condition.component_column = in.column();
      const auto number = in.number();
      std::uint64_t index = 0;
      if (!parse_unsigned(number, index)) {
        return fail(error, condition.component_column, static_cast<int>(number.size()),
                    "expected a component index (0, 1, 2) in '[...]'");
      }
      condition.component = static_cast<std::size_t>(index);
      if (!in.take("]")) return fail(error, in.column(), 0, "expected ']'");
    }
    in.skip_blanks();
    const int word_column = in.column();
    if (in.take(">") || in.take("<")) {
      condition.kind =
          whole[in.offset() - 1] == '>' ? Condition::Kind::kAbove : Condition::Kind::kBelow;
      const int column = (in.skip_blanks(), in.column());
      const auto number = in.number();
      if (!parse_double(number, condition.bound)) {
        return fail(error, column, static_cast<int>(number.size()),
                    number.empty() ? "expected a number to compare with"
                                   : fmt::format("'{}' is no number", number));
      }
    } else {
      const auto word = in.name();
      if (word == "activates") {
        condition.kind = Condition::Kind::kActivates;
      } else if (word == "deactivates") {
        condition.kind = Condition::Kind::kDeactivates;
      } else if (word == "starts") {
        condition.kind = Condition::Kind::kStarts;
      } else if (word == "ends") {
        condition.kind = Condition::Kind::kEnds;
      } else {
        std::vector<Note> notes;
        if (!word.empty()) {
          if (auto hint = suggest(word, {"activates", "deactivates", "starts", "ends"}, "allowed");
              !hint.empty()) {
            notes.emplace_back(std::move(hint));
          }
        }
        notes.emplace_back(kForms);
        return fail(error, word_column, static_cast<int>(word.size()),
                    fmt::format("expected activates, deactivates, starts, ends, '>' or '<' "
                                "after '{}'",
                                name),
                    std::move(notes));
      }
      if (condition.component) {
        return fail(error, condition.component_column - 1, 0,
                    fmt::format("'[...]' picks a component of a value: '{}' takes none", word));
      }
    }
  }
  if (!in.done()) {
    return fail(error, in.column(), static_cast<int>(in.rest().size()),
                fmt::format("unexpected '{}' after the condition", in.rest()), {kForms});
  }
  return condition;
}

Diagnostic condition_diagnostic(const ConditionError& error, std::string_view option) {
  Diagnostic diagnostic;
  diagnostic.location.file = std::string(option);
  diagnostic.location.line = 1;
  diagnostic.location.column = error.column;
  diagnostic.location.length = error.length;
  diagnostic.code = error.code;
  diagnostic.message = error.message;
  diagnostic.notes = error.notes;
  return diagnostic;
}

namespace {

using Kind = ExplainTarget::Kind;

const char* kind_name(Kind kind) {
  switch (kind) {
    case Kind::kBehaviour:
      return "a behaviour";
    case Kind::kController:
      return "a state machine";
    case Kind::kActuator:
      return "an actuator";
    case Kind::kState:
      break;
  }
  return "a state";
}

Breakpoint::Value value_kind(const ValueType& type) {
  if (type.cpp_type == nullptr) return Breakpoint::Value::kNone;
  if (*type.cpp_type == typeid(bool)) return Breakpoint::Value::kBool;
  if (*type.cpp_type == typeid(std::int64_t)) return Breakpoint::Value::kInt;
  if (*type.cpp_type == typeid(double)) return Breakpoint::Value::kDouble;
  if (*type.cpp_type == typeid(Vec2)) return Breakpoint::Value::kVec2;
  if (*type.cpp_type == typeid(Vec3)) return Breakpoint::Value::kVec3;
  return Breakpoint::Value::kNone;
}

std::size_t components(Breakpoint::Value value) {
  return value == Breakpoint::Value::kVec2 ? 2 : value == Breakpoint::Value::kVec3 ? 3 : 0;
}

/// The names a condition of `kind` may name, each as explain names it alone.
std::vector<std::string> names_of(const Program& program, Kind kind) {
  std::vector<std::string> out;
  if (kind == Kind::kBehaviour) {
    for (std::uint32_t b = 0; b < program.behaviours.size(); ++b) {
      out.push_back(program.behaviours[b].name);
    }
  } else if (kind == Kind::kActuator) {
    for (const auto& actuator : program.actuators) out.push_back(actuator.name);
  } else if (kind == Kind::kState) {
    for (const auto& controller : program.controllers) {
      for (const auto& state : controller->states()) {
        out.push_back(controller->name() + "/" + state.name);
      }
    }
  }
  return out;
}

}  // namespace

std::optional<Breakpoint> resolve_breakpoint(const Program& program, Condition condition,
                                             ConditionError& error) {
  Breakpoint out;
  const auto kind = condition.kind;
  if (kind == Condition::Kind::kEvent || kind == Condition::Kind::kStep ||
      kind == Condition::Kind::kStepFrom) {
    out.condition = std::move(condition);
    return out;
  }
  const Kind wanted = kind == Condition::Kind::kActivates || kind == Condition::Kind::kDeactivates
                          ? Kind::kBehaviour
                      : kind == Condition::Kind::kStarts || kind == Condition::Kind::kEnds
                          ? Kind::kState
                          : Kind::kActuator;
  const int column = condition.name_column;
  const int length = static_cast<int>(condition.name.size());
  const auto located = [&](std::string message, std::vector<Note> notes,
                           std::string code = "unknown-name") {
    fail(error, column, length, std::move(message), std::move(notes), std::move(code));
    return std::nullopt;
  };
  Explanation unresolved;
  const auto target = resolve_target(program, condition.name, unresolved);
  if (!target) {
    if (unresolved.text.find("ambiguous") != std::string::npos) {
      return located(unresolved.text, unresolved.notes, "bad-condition");
    }
    std::vector<Note> notes;
    if (auto hint = suggest(condition.name, names_of(program, wanted)); !hint.empty()) {
      notes.emplace_back(std::move(hint));
    }
    return located(fmt::format("'{}' names no {} of '{}'", condition.name,
                               wanted == Kind::kBehaviour ? "behaviour"
                               : wanted == Kind::kState   ? "state (machine/state)"
                                                          : "actuator",
                               program.name),
                   std::move(notes));
  }
  if (target->kind != wanted) {
    std::vector<Note> notes;
    if (target->kind == Kind::kController && wanted == Kind::kState) {
      notes.emplace_back(fmt::format("name one of its states, as {}/STATE", condition.name));
    }
    return located(fmt::format("'{}' is {}: '{}' takes {}", condition.name, kind_name(target->kind),
                               kind_word(kind), kind_name(wanted)),
                   std::move(notes), "bad-condition");
  }
  out.target = *target;
  switch (wanted) {
    case Kind::kBehaviour:
      out.scope = program.layers[program.behaviours[target->index].layer].name;
      out.name = program.behaviours[target->index].name;
      break;
    case Kind::kState:
      out.scope = program.controllers[target->index]->name();
      out.name = program.controllers[target->index]->states()[target->state].name;
      break;
    case Kind::kActuator: {
      const auto& actuator = program.actuators[target->index];
      out.name = actuator.name;
      out.value = value_kind(*actuator.type);
      if (out.value == Breakpoint::Value::kNone) {
        return located(fmt::format("'{}' holds a {}, which has no number to compare", actuator.name,
                                   actuator.type->name),
                       {}, "bad-condition");
      }
      const auto count = components(out.value);
      if (count > 0 && !condition.component) {
        return located(fmt::format("'{}' is a {}: pick a component, as {}[0]", actuator.name,
                                   actuator.type->name, condition.name),
                       {}, "bad-condition");
      }
      if (condition.component && *condition.component >= std::max<std::size_t>(count, 1)) {
        fail(error, condition.component_column, 0,
             count == 0 ? fmt::format("'{}' is a {}: it has no components", actuator.name,
                                      actuator.type->name)
                        : fmt::format("'{}' is a {}: its components are 0 to {}", actuator.name,
                                      actuator.type->name, count - 1),
             {}, "bad-condition");
        return std::nullopt;
      }
      break;
    }
    case Kind::kController:
      break;
  }
  out.condition = std::move(condition);
  return out;
}

std::optional<Breakpoint> make_breakpoint(const Program& program, std::string_view text,
                                          std::string_view option, const FormatOptions& format,
                                          std::string& error) {
  ConditionError failed;
  auto condition = parse_condition(text, failed);
  std::optional<Breakpoint> breakpoint;
  if (condition) breakpoint = resolve_breakpoint(program, std::move(*condition), failed);
  if (!breakpoint) {
    // Columns count in the trimmed condition: that is what is shown.
    while (!text.empty() && std::isspace(static_cast<unsigned char>(text.front())) != 0) {
      text.remove_prefix(1);
    }
    error = arbiter::format(condition_diagnostic(failed, option), text, format);
  }
  return breakpoint;
}

namespace {

double live_value(const Manager& manager, const Breakpoint& breakpoint) {
  const auto a = breakpoint.target.index;
  const std::size_t i = breakpoint.condition.component.value_or(0);
  switch (breakpoint.value) {
    case Breakpoint::Value::kBool:
      return manager.actuator<bool>(a) ? 1.0 : 0.0;
    case Breakpoint::Value::kInt:
      return static_cast<double>(manager.actuator<std::int64_t>(a));
    case Breakpoint::Value::kDouble:
      return manager.actuator<double>(a);
    case Breakpoint::Value::kVec2: {
      const auto& v = manager.actuator<Vec2>(a);
      return i == 0 ? v.x : v.y;
    }
    case Breakpoint::Value::kVec3: {
      const auto& v = manager.actuator<Vec3>(a);
      return i == 0 ? v.x : i == 1 ? v.y : v.z;
    }
    case Breakpoint::Value::kNone:
      break;
  }
  return std::nan("");
}

bool compare(const Condition& condition, double value) {
  return condition.kind == Condition::Kind::kAbove ? value > condition.bound
                                                   : value < condition.bound;
}

/// Whether the breakpoint fires, given whether it holds now (`now`) and held the step before;
/// the conditions that are about a moment (a state's start, an event) hold only when it fires.
bool fires(Breakpoint& breakpoint, bool now) {
  const bool was = breakpoint.was;
  breakpoint.was = now;
  switch (breakpoint.condition.kind) {
    case Condition::Kind::kActivates:
    case Condition::Kind::kAbove:
    case Condition::Kind::kBelow:
      return now && !was;
    case Condition::Kind::kDeactivates:
      return !now && was;
    default:
      return now;
  }
}

}  // namespace

const char* Breakpoints::check(const Manager& manager) {
  const char* fired = nullptr;
  for (auto& breakpoint : items_) {
    if (!breakpoint.enabled) continue;
    const auto& condition = breakpoint.condition;
    bool now = false;
    switch (condition.kind) {
      case Condition::Kind::kActivates:
      case Condition::Kind::kDeactivates:
        now = manager.active(breakpoint.target.index);
        break;
      case Condition::Kind::kStarts:
      case Condition::Kind::kEnds: {
        const auto wanted = condition.kind == Condition::Kind::kStarts
                                ? Controller::Event::Kind::kActivate
                                : Controller::Event::Kind::kDeactivate;
        const auto& controller = *manager.program().controllers[breakpoint.target.index];
        const auto* events = controller.events();
        for (std::size_t e = 0; e < controller.event_count() && !now; ++e) {
          now = events[e].kind == wanted && events[e].state == breakpoint.target.state;
        }
        break;
      }
      case Condition::Kind::kAbove:
      case Condition::Kind::kBelow:
        now = compare(condition, live_value(manager, breakpoint));
        break;
      case Condition::Kind::kEvent:
        for (std::size_t e = 0; e < manager.event_count() && !now; ++e) {
          const auto& event = manager.event(e);
          now = event.text != nullptr && std::strstr(event.text, condition.pattern.c_str());
        }
        break;
      case Condition::Kind::kStep:
        now = manager.steps() == condition.step;
        break;
      case Condition::Kind::kStepFrom:
        now = manager.steps() >= condition.step;
        break;
    }
    if (fires(breakpoint, now) && fired == nullptr) fired = condition.text.c_str();
  }
  return fired;
}

bool Breakpoints::remove(std::string_view text) {
  const auto found = std::find_if(items_.begin(), items_.end(), [&](const Breakpoint& item) {
    return item.condition.text == text;
  });
  if (found == items_.end()) return false;
  items_.erase(found);
  return true;
}

void Breakpoints::on_reload(const Manager& manager) {
  for (auto& breakpoint : items_) {
    ConditionError ignored;
    auto again = resolve_breakpoint(manager.program(), breakpoint.condition, ignored);
    if (!again) {
      breakpoint.enabled = false;
      continue;
    }
    again->was = breakpoint.was;
    breakpoint = std::move(*again);
  }
}

namespace {

using Json = nlohmann::json;

const Json& member(const Json& object, const char* key) {
  static const Json kNull;
  if (!object.is_object()) return kNull;
  const auto found = object.find(key);
  return found == object.end() ? kNull : *found;
}

/// Whether an event of a trace's `events` list (`activate S`, `deactivate S ...`) is `word`
/// of `state`.
bool is_event(const Json& event, std::string_view word, const std::string& state) {
  if (!event.is_string()) return false;
  const auto& text = event.get_ref<const std::string&>();
  if (text.size() < word.size() + 1 + state.size()) return false;
  if (text.compare(0, word.size(), word) != 0 || text[word.size()] != ' ') return false;
  if (text.compare(word.size() + 1, state.size(), state) != 0) return false;
  const auto end = word.size() + 1 + state.size();
  return end == text.size() || text[end] == ' ';
}

bool recorded_holds(const Breakpoint& breakpoint, const Json& record, std::uint64_t step) {
  const auto& condition = breakpoint.condition;
  switch (condition.kind) {
    case Condition::Kind::kActivates:
    case Condition::Kind::kDeactivates: {
      const auto& active = member(member(member(member(record, "layers"), breakpoint.scope.c_str()),
                                         breakpoint.name.c_str()),
                                  "active");
      return active.is_boolean() && active.get<bool>();
    }
    case Condition::Kind::kStarts:
    case Condition::Kind::kEnds: {
      const auto& events =
          member(member(member(record, "controllers"), breakpoint.scope.c_str()), "events");
      if (!events.is_array()) return false;
      const std::string_view word =
          condition.kind == Condition::Kind::kStarts ? "activate" : "deactivate";
      return std::any_of(events.begin(), events.end(),
                         [&](const Json& event) { return is_event(event, word, breakpoint.name); });
    }
    case Condition::Kind::kAbove:
    case Condition::Kind::kBelow: {
      const auto& value =
          member(member(member(record, "actuators"), breakpoint.name.c_str()), "value");
      const auto& number =
          value.is_array() && condition.component && *condition.component < value.size()
              ? value[*condition.component]
              : value;
      if (number.is_boolean()) return compare(condition, number.get<bool>() ? 1.0 : 0.0);
      return number.is_number() && compare(condition, number.get<double>());
    }
    case Condition::Kind::kEvent: {
      const auto& reported = member(record, "reported");
      if (!reported.is_array()) return false;
      return std::any_of(reported.begin(), reported.end(), [&](const Json& event) {
        const auto& by = member(event, "by");
        const auto& text = member(event, "text");
        // A break's own mark is no event of the run's.
        if (by.is_string() && by.get_ref<const std::string&>() == "break") return false;
        return text.is_string() &&
               text.get_ref<const std::string&>().find(condition.pattern) != std::string::npos;
      });
    }
    case Condition::Kind::kStep:
      return step == condition.step;
    case Condition::Kind::kStepFrom:
      return step >= condition.step;
  }
  return false;
}

}  // namespace

std::optional<SeekHit> seek(TraceSource& trace, std::vector<Breakpoint>& breakpoints,
                            std::uint64_t after, std::optional<Diagnostic>& error) {
  for (auto& breakpoint : breakpoints) breakpoint.was = false;
  TraceRecord record;
  while (trace.next(record)) {
    if (record.kind != TraceRecord::Kind::kStep) continue;
    const auto json = Json::parse(record.text, nullptr, false);
    std::optional<SeekHit> hit;
    for (std::size_t b = 0; b < breakpoints.size(); ++b) {
      const bool now = recorded_holds(breakpoints[b], json, record.step);
      if (fires(breakpoints[b], now) && !hit && record.step > after) {
        hit = SeekHit{record.step, b};
      }
    }
    if (hit) return hit;
  }
  if (trace.error()) error = trace.error();
  return std::nullopt;
}

}  // namespace arbiter
