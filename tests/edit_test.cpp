// The edit operations (engine/tools/edit): applied to every inhibition of every config in
// configs/, each gives a config that validates, with the edited change and no other.

#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "arbiter/edit.hpp"
#include "arbiter/load.hpp"
#include "arbiter/model.hpp"
#include "tooling_support.hpp"

namespace fs = std::filesystem;
using namespace arbiter;
using namespace arbiter::test;

namespace {

std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::size_t at = 0;
  while (at <= text.size()) {
    const auto newline = text.find('\n', at);
    if (newline == std::string::npos) {
      lines.push_back(text.substr(at));
      break;
    }
    lines.push_back(text.substr(at, newline - at));
    at = newline + 1;
  }
  return lines;
}

/// The lines of `before` outside the edits' lines are in `after`, in order, byte for byte: the
/// lines before the first edited one and after the last are equal.
void check_untouched(const std::string& before, const std::string& after,
                     const std::vector<TextEdit>& edits, const std::string& file) {
  std::size_t first = before.size(), last = 0;
  for (const auto& edit : edits) {
    if (edit.file != file) continue;
    first = std::min(first, edit.begin);
    last = std::max(last, edit.end);
  }
  const auto old_lines = split_lines(before);
  const auto new_lines = split_lines(after);
  const auto line_of = [&](std::size_t offset) {
    return static_cast<std::size_t>(std::count(before.begin(), before.begin() + offset, '\n'));
  };
  const std::size_t head = line_of(first);
  const std::size_t tail = old_lines.size() - 1 - line_of(last);
  REQUIRE(new_lines.size() >= head + tail);
  for (std::size_t i = 0; i < head; ++i) CHECK(new_lines[i] == old_lines[i]);
  for (std::size_t i = 0; i < tail; ++i)
    CHECK(new_lines[new_lines.size() - 1 - i] == old_lines[old_lines.size() - 1 - i]);
}

using Operation = EditResult (*)(const Loaded&, const InhibitionRef&);

/// The declared inhibition of `model`, or nullptr.
const InhibitionDecl* declared(const Model& model, const InhibitionRef& which) {
  for (const auto& layer : model.layers) {
    if (layer.name.text != which.layer) continue;
    for (const auto& inhibition : layer.inhibitions) {
      if (inhibition.inhibitor.text == which.inhibitor &&
          inhibition.inhibited.text == which.inhibited)
        return &inhibition;
    }
  }
  return nullptr;
}

/// Applies `operation` to every inhibition of every config in configs/; `expect` checks the
/// inhibition after the edit (nullptr when gone) against the one before.
void apply_to_every_inhibition(Operation operation, const char* name,
                               void (*expect)(const InhibitionDecl& before,
                                              const InhibitionDecl* after)) {
  for (const auto& path : configs_under(kSourceDir / "configs")) {
    if (!plugins_built(path)) continue;
    Registry registry = builtin_registry();
    const Loaded loaded = load_config(path.string(), registry);
    if (!loaded.model || loaded.diagnostics.has_errors()) continue;  // configs meant to fail
    for (const auto& layer : loaded.model->layers) {
      for (const auto& inhibition : layer.inhibitions) {
        const InhibitionRef which{layer.name.text, inhibition.inhibitor.text,
                                  inhibition.inhibited.text};
        DYNAMIC_SECTION(name << " " << fs::relative(path, kSourceDir).string() << " "
                             << which.inhibitor << " -> " << which.inhibited) {
          const EditResult result = operation(loaded, which);
          REQUIRE(result.ok());
          REQUIRE_FALSE(result.edits.empty());
          Registry again = builtin_registry();
          const EditedConfig after_edit = load_edited(loaded, result.edits, again);
          const Loaded& edited = after_edit.loaded;
          INFO(format(edited.diagnostics));
          CHECK_FALSE(edited.diagnostics.has_errors());
          REQUIRE(edited.model);
          expect(inhibition, declared(*edited.model, which));
          for (const auto& file : loaded.files.files()) {
            const SourceFile* after = edited.files.find(file->path);
            REQUIRE(after != nullptr);
            check_untouched(file->text, after->text, result.edits, file->path);
          }
        }
      }
    }
  }
}

}  // namespace

TEST_CASE("removing each inhibition of each shipped config leaves a valid config", "[edit]") {
  apply_to_every_inhibition(
      &remove_inhibition, "remove",
      [](const InhibitionDecl&, const InhibitionDecl* after) { CHECK(after == nullptr); });
}

TEST_CASE("flipping the chaining of each inhibition of each shipped config leaves a valid config",
          "[edit]") {
  apply_to_every_inhibition(&flip_chaining, "flip",
                            [](const InhibitionDecl& before, const InhibitionDecl* after) {
                              REQUIRE(after != nullptr);
                              CHECK(after->chaining == !before.chaining);
                            });
}

namespace {

/// `text` with its only occurrence of `from` replaced by `to`.
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  REQUIRE(at != std::string::npos);
  REQUIRE(text.find(from, at + 1) == std::string::npos);
  return text.replace(at, from.size(), to);
}

/// `config` (a file of `dir` named `name`) after `operation` on `which`, checked to validate.
std::string edited_text(const std::string& name, const std::string& config, Operation operation,
                        const InhibitionRef& which) {
  test::TempDir dir;
  const std::string path = dir.write(name, config);
  Registry registry = builtin_registry();
  const Loaded loaded = load_config(path, registry);
  INFO(format(loaded.diagnostics));
  REQUIRE_FALSE(loaded.diagnostics.has_errors());
  const EditResult result = operation(loaded, which);
  INFO(result.refused);
  REQUIRE(result.ok());
  const std::string text = apply_edits(config, path, result.edits);
  write_text(path, text);
  Registry again = builtin_registry();
  const Loaded edited = load_config(path, again);
  INFO(text << format(edited.diagnostics));
  CHECK_FALSE(edited.diagnostics.has_errors());
  return text;
}

}  // namespace

TEST_CASE("inhibitions written as mappings, as the only item, and in JSON are edited in place",
          "[edit]") {
  const std::string yaml = R"(arbiter: 1
name: forms
layers:
  - name: l
    behaviours: {a: scripted, b: scripted, c: scripted}
    inhibitions:
      - inhibitor: a   # the kick wins
        inhibited: b
      - {inhibitor: b, inhibited: c, chaining: true}
  - name: m
    behaviours: {d: scripted, e: scripted}
    inhibitions:
      - d => e
    normalise: false
)";
  const InhibitionRef ab{"l", "a", "b"}, bc{"l", "b", "c"}, de{"m", "d", "e"};
  CHECK(edited_text("forms.yaml", yaml, &flip_chaining, ab) ==
        replaced(yaml, "        inhibited: b\n", "        inhibited: b\n        chaining: true\n"));
  CHECK(edited_text("forms.yaml", yaml, &flip_chaining, bc) ==
        replaced(yaml, "chaining: true}", "chaining: false}"));
  CHECK(edited_text("forms.yaml", yaml, &remove_inhibition, ab) ==
        replaced(yaml, "      - inhibitor: a   # the kick wins\n        inhibited: b\n", ""));
  CHECK(edited_text("forms.yaml", yaml, &remove_inhibition, bc) ==
        replaced(yaml, "      - {inhibitor: b, inhibited: c, chaining: true}\n", ""));
  // The only item goes with its key: `inhibitions:` alone would be null.
  CHECK(edited_text("forms.yaml", yaml, &remove_inhibition, de) ==
        replaced(yaml, "    inhibitions:\n      - d => e\n", ""));

  const std::string json = R"({
  "arbiter": 1,
  "name": "forms",
  "layers": [
    {
      "name": "l",
      "behaviours": {"a": "scripted", "b": "scripted", "c": "scripted"},
      "inhibitions": ["a => b", {"inhibitor": "b", "inhibited": "c"}]
    }
  ]
}
)";
  CHECK(edited_text("forms.json", json, &flip_chaining, ab) ==
        replaced(json, "\"a => b\"", "\"a -> b\""));
  CHECK(edited_text("forms.json", json, &flip_chaining, bc) ==
        replaced(json, "\"inhibited\": \"c\"}", "\"inhibited\": \"c\", \"chaining\": true}"));
  CHECK(edited_text("forms.json", json, &remove_inhibition, ab) ==
        replaced(json, "\"a => b\", ", ""));
  CHECK(edited_text("forms.json", json, &remove_inhibition, bc) ==
        replaced(json, ", {\"inhibitor\": \"b\", \"inhibited\": \"c\"}", ""));

  // An inhibition that is not declared (a => c is implied at most) is refused with the reason.
  test::TempDir dir;
  Registry registry = builtin_registry();
  const Loaded loaded = load_config(dir.write("forms.json", json), registry);
  const EditResult refused = remove_inhibition(loaded, {"l", "a", "c"});
  CHECK(refused.edits.empty());
  CHECK(refused.refused == "no inhibition 'a -> c' in layer 'l'");
}

namespace {

/// A param's value as a config writes it, for the kinds written as one scalar; empty otherwise.
std::string written(const ParamValue& value) {
  if (const auto* b = std::get_if<bool>(&value)) return *b ? "true" : "false";
  if (const auto* i = std::get_if<std::int64_t>(&value)) return std::to_string(*i);
  if (const auto* d = std::get_if<double>(&value)) return fmt::format("{}", *d);
  if (const auto* s = std::get_if<std::string>(&value)) return nlohmann::json(*s).dump();
  return {};
}

}  // namespace

TEST_CASE("setting each scalar param of each behaviour of each shipped config edits one value",
          "[edit]") {
  int written_params = 0, added_params = 0;
  for (const auto& path : configs_under(kSourceDir / "configs")) {
    if (!plugins_built(path)) continue;
    Registry registry = builtin_registry();
    const Loaded loaded = load_config(path.string(), registry);
    if (!loaded.model || loaded.diagnostics.has_errors()) continue;
    for (const auto& layer : loaded.model->layers) {
      for (const auto& behaviour : layer.behaviours) {
        for (const auto& param : behaviour.params.items) {
          const std::string value = written(param.value);
          if (value.empty()) continue;
          (param.defaulted ? added_params : written_params) += 1;
          DYNAMIC_SECTION(fs::relative(path, kSourceDir).string()
                          << " " << behaviour.name.text << "." << param.name << " = " << value) {
            const EditResult result =
                set_param(loaded, layer.name.text, behaviour.name.text, param.name, value);
            INFO(result.refused);
            REQUIRE(result.ok());
            Registry again = builtin_registry();
            const EditedConfig after_edit = load_edited(loaded, result.edits, again);
            const Loaded& edited = after_edit.loaded;
            INFO(format(edited.diagnostics));
            CHECK_FALSE(edited.diagnostics.has_errors());
            REQUIRE(edited.model);
            const Param* now = nullptr;
            for (const auto& l : edited.model->layers) {
              for (const auto& b : l.behaviours) {
                if (l.name.text == layer.name.text && b.name.text == behaviour.name.text)
                  now = b.params.find(param.name);
              }
            }
            REQUIRE(now != nullptr);
            CHECK(written(now->value) == value);
            // A param that was not written is now written, where set_param put it.
            CHECK_FALSE(now->defaulted);
            for (const auto& file : loaded.files.files()) {
              const SourceFile* after = edited.files.find(file->path);
              REQUIRE(after != nullptr);
              check_untouched(file->text, after->text, result.edits, file->path);
            }
          }
        }
      }
    }
  }
  // Both ways are tried: a written value replaced, a missing param added.
  CHECK(written_params > 0);
  CHECK(added_params > 0);
}

TEST_CASE("a param is set where it is written, added to params:, or params: added", "[edit]") {
  const std::string yaml = R"(arbiter: 1
name: params
layers:
  - name: l
    behaviours:
      a: scripted
      b: {type: scripted, params: {activation: 0.5}}
      c:
        type: scripted   # no params yet

      d:
        type: scripted
        params:
          activation: [1, 0]
)";
  test::TempDir dir;
  Registry registry = builtin_registry();
  const Loaded loaded = load_config(dir.write("params.yaml", yaml), registry);
  REQUIRE_FALSE(loaded.diagnostics.has_errors());
  auto set = [&](const std::string& behaviour, const std::string& param, const std::string& value) {
    const EditResult result = set_param(loaded, "l", behaviour, param, value);
    INFO(result.refused);
    REQUIRE(result.ok());
    Registry again = builtin_registry();
    const EditedConfig edited = load_edited(loaded, result.edits, again);
    INFO(format(edited.loaded.diagnostics));
    CHECK_FALSE(edited.loaded.diagnostics.has_errors());
    return edited.loaded.files.files().front()->text;
  };
  CHECK(set("a", "activation", "0.25") ==
        replaced(yaml, "a: scripted", "a: {type: scripted, params: {activation: 0.25}}"));
  CHECK(set("b", "activation", "0.75") == replaced(yaml, "activation: 0.5", "activation: 0.75"));
  CHECK(set("b", "writes", "{}") == replaced(yaml, "0.5}}", "0.5, writes: {}}}"));
  CHECK(set("c", "activation", "1") ==
        replaced(yaml, "# no params yet\n", "# no params yet\n        params: {activation: 1}\n"));
  CHECK(set("d", "activation", "[0, 1]") == replaced(yaml, "[1, 0]", "[0, 1]"));
  CHECK(set("d", "writes", "{}") == replaced(yaml, "[1, 0]\n", "[1, 0]\n          writes: {}\n"));
  CHECK(set_param(loaded, "l", "e", "activation", "1").refused == "no behaviour 'e' in layer 'l'");
}

TEST_CASE("adding an inhibition to each layer of each shipped config declares it and only it",
          "[edit]") {
  int added = 0;
  for (const auto& path : configs_under(kSourceDir / "configs")) {
    if (!plugins_built(path)) continue;
    Registry registry = builtin_registry();
    const Loaded loaded = load_config(path.string(), registry);
    if (!loaded.program || !loaded.model || loaded.diagnostics.has_errors()) continue;
    const Program& program = *loaded.program;
    for (const auto& layer : program.layers) {
      if (layer.behaviour_end - layer.behaviour_begin < 2) continue;
      // From the first behaviour in execution order to the last, in the direction the layer's
      // inhibitions run in that order, so that no cycle is made.
      std::uint32_t from = layer.behaviour_begin, to = layer.behaviour_end - 1;
      bool backwards = false;
      for (std::uint32_t b = layer.behaviour_begin; b < layer.behaviour_end; ++b) {
        for (const auto& inhibition : program.inhibitions.of(b))
          backwards = backwards || inhibition.inhibitor > inhibition.inhibited;
      }
      if (backwards) std::swap(from, to);
      const InhibitionRef which{layer.name, program.behaviours[from].name,
                                program.behaviours[to].name};
      if (declared(*loaded.model, which)) continue;
      for (const bool chaining : {true, false}) {
        ++added;
        DYNAMIC_SECTION(fs::relative(path, kSourceDir).string()
                        << " " << which.inhibitor << (chaining ? " => " : " -> ")
                        << which.inhibited) {
          const EditResult result = add_inhibition(loaded, which, chaining);
          INFO(result.refused);
          REQUIRE(result.ok());
          Registry again = builtin_registry();
          const EditedConfig after_edit = load_edited(loaded, result.edits, again);
          const Loaded& edited = after_edit.loaded;
          INFO(format(edited.diagnostics));
          CHECK_FALSE(edited.diagnostics.has_errors());
          REQUIRE(edited.model);
          const InhibitionDecl* now = declared(*edited.model, which);
          REQUIRE(now != nullptr);
          CHECK(now->chaining == chaining);
          for (const auto& file : loaded.files.files()) {
            const SourceFile* after = edited.files.find(file->path);
            REQUIRE(after != nullptr);
            check_untouched(file->text, after->text, result.edits, file->path);
          }
          // Declared twice is refused.
          CHECK_FALSE(add_inhibition(edited, which, chaining).ok());
        }
      }
    }
  }
  CHECK(added > 0);
}

TEST_CASE("an inhibition is added after the last item, or with the inhibitions: key", "[edit]") {
  const std::string yaml = R"(arbiter: 1
name: add
layers:
  - name: block
    behaviours: {a: scripted, b: scripted, c: scripted}
    inhibitions:
      - a => b   # first
    normalise: false
  - name: flow
    behaviours: {d: scripted, e: scripted, f: scripted}
    inhibitions: [d => e]
  - name: none
    behaviours: {g: scripted, h: scripted}
)";
  test::TempDir dir;
  Registry registry = builtin_registry();
  const Loaded loaded = load_config(dir.write("add.yaml", yaml), registry);
  REQUIRE_FALSE(loaded.diagnostics.has_errors());
  auto add = [&](const InhibitionRef& which, bool chaining) {
    const EditResult result = add_inhibition(loaded, which, chaining);
    INFO(result.refused);
    REQUIRE(result.ok());
    return apply_edits(yaml, loaded.files.files().front()->path, result.edits);
  };
  CHECK(add({"block", "b", "c"}, true) == replaced(yaml, "# first\n", "# first\n      - b => c\n"));
  CHECK(add({"flow", "e", "f"}, false) == replaced(yaml, "[d => e]", "[d => e, e -> f]"));
  CHECK(add({"none", "g", "h"}, true) ==
        replaced(yaml, "h: scripted}\n", "h: scripted}\n    inhibitions: [g => h]\n"));
  CHECK(add_inhibition(loaded, {"block", "a", "b"}, false).refused ==
        "the inhibition 'a -> b' in layer 'block' is already declared");
  CHECK(add_inhibition(loaded, {"other", "a", "b"}, false).refused == "no layer 'other'");
}

namespace {

/// Every line of `before` that no edit of `file` touches is in `after`, in order.
void check_lines_kept(const std::string& before, const std::string& after,
                      const std::vector<TextEdit>& edits, const std::string& file) {
  const auto old_lines = split_lines(before);
  const auto new_lines = split_lines(after);
  std::vector<bool> touched(old_lines.size(), false);
  const auto line_of = [&](std::size_t offset) {
    return static_cast<std::size_t>(std::count(before.begin(), before.begin() + offset, '\n'));
  };
  for (const auto& edit : edits) {
    if (edit.file != file) continue;
    for (std::size_t l = line_of(edit.begin); l <= line_of(edit.end); ++l) touched[l] = true;
  }
  std::size_t next = 0;
  for (std::size_t l = 0; l < old_lines.size(); ++l) {
    if (touched[l]) continue;
    while (next < new_lines.size() && new_lines[next] != old_lines[l]) ++next;
    INFO("line " << l + 1 << ": " << old_lines[l]);
    REQUIRE(next < new_lines.size());
    ++next;
  }
}

}  // namespace

TEST_CASE("a rename to the name a symbol already has says so, not that the name is taken",
          "[edit]") {
  Registry registry = builtin_registry();
  const Loaded loaded =
      load_config((kSourceDir / "configs/paper/walk_and_kick.yaml").string(), registry);
  const ConfigIndex index = index_config(loaded, &registry);
  const auto kick = std::find_if(
      index.occurrences.begin(), index.occurrences.end(),
      [](const Occurrence& item) { return item.definition && item.name == "kick_ball"; });
  REQUIRE(kick != index.occurrences.end());
  CHECK(rename_symbol(loaded, index, *kick, "kick_ball").refused ==
        "'kick_ball' is already its name");
  CHECK(rename_symbol(loaded, index, *kick, "go_behind_ball").refused ==
        "'go_behind_ball' is already taken");
}

TEST_CASE("renaming each name of each shipped config renames every use and nothing else",
          "[edit]") {
  int renamed = 0, refused = 0;
  for (const auto& path : configs_under(kSourceDir / "configs")) {
    if (!plugins_built(path)) continue;
    Registry registry = builtin_registry();
    const Loaded loaded = load_config(path.string(), registry);
    if (!loaded.model || loaded.diagnostics.has_errors()) continue;
    const ConfigIndex index = index_config(loaded, &registry);
    for (const auto& symbol : index.occurrences) {
      if (!symbol.definition || symbol.kind == SymbolKind::kClass) continue;
      const std::string name = symbol.name + "_renamed";
      ++renamed;
      DYNAMIC_SECTION(fs::relative(path, kSourceDir).string()
                      << " " << symbol.scope << " " << symbol.name << " -> " << name) {
        Registry check = builtin_registry();
        const EditResult result =
            checked(loaded, rename_symbol(loaded, index, symbol, name), check);
        if (!result.ok()) {
          // The uses no operation follows, refused with the reason: an actuator named in a
          // scripted behaviour's writes:, bound by name to a state's port or named in a class's
          // own params (the DDS bridge's topics:), a state a class plans by a name written in
          // its C++ (the soccer goalie's).
          INFO(result.refused);
          const bool actuator = symbol.kind == SymbolKind::kActuator &&
                                (contains(result.refused, "is not an actuator of layer") ||
                                 contains(result.refused, "a state has no ports:") ||
                                 contains(result.refused, "is neither an actuator nor a sensor"));
          const bool state =
              symbol.kind == SymbolKind::kState && (contains(result.refused, "does not declare") ||
                                                    contains(result.refused, "has no state"));
          CHECK((actuator || state));
          ++refused;
          continue;
        }
        Registry again = builtin_registry();
        const EditedConfig after_edit = load_edited(loaded, result.edits, again);
        const Loaded& edited = after_edit.loaded;
        INFO(format(edited.diagnostics));
        CHECK_FALSE(edited.diagnostics.has_errors());
        const ConfigIndex now = index_config(edited, &again);
        int old_names = 0, new_names = 0, declared = 0;
        for (const auto& other : now.occurrences) {
          if (other.kind != symbol.kind || other.scope != symbol.scope) continue;
          old_names += other.name == symbol.name;
          new_names += other.name == name;
          declared += other.name == name && other.definition;
        }
        CHECK(old_names == 0);
        CHECK(declared == 1);
        CHECK(new_names >= 1);
        for (const auto& file : loaded.files.files()) {
          const SourceFile* after = edited.files.find(file->path);
          REQUIRE(after != nullptr);
          check_lines_kept(file->text, after->text, result.edits, file->path);
        }
      }
    }
  }
  CHECK(renamed > 0);
  CHECK(refused < renamed / 4);
}

TEST_CASE(
    "a behaviour is added after the layer's last one, or with the behaviours: key in the "
    "layer's style",
    "[edit]") {
  const std::string yaml = R"(arbiter: 1
name: add
layers:
  - name: block
    behaviours:
      a: scripted   # first
      b:
        type: scripted
    inhibitions:
      - a => b
  - name: flow
    behaviours: {c: scripted}
  - name: none
    actuators: {x: {type: double}}
  - {name: flat, actuators: {w: {type: double}}}
)";
  test::TempDir dir;
  Registry registry = builtin_registry();
  const Loaded loaded = load_config(dir.write("add.yaml", yaml), registry);
  REQUIRE_FALSE(loaded.diagnostics.has_errors());
  auto add = [&](const std::string& layer, const std::string& name) {
    const EditResult result =
        checked(loaded, add_behaviour(loaded, layer, name, "scripted"), registry);
    INFO(result.refused);
    REQUIRE(result.ok());
    return apply_edits(yaml, loaded.files.files().front()->path, result.edits);
  };
  CHECK(add("block", "wave") == replaced(yaml, "        type: scripted\n",
                                         "        type: scripted\n      wave: {type: scripted}\n"));
  CHECK(add("flow", "wave") ==
        replaced(yaml, "{c: scripted}", "{c: scripted, wave: {type: scripted}}"));
  // A layer without behaviours: gets the key in the style the layer is written in, in a block
  // layer on a line of its own with the behaviour under it.
  CHECK(add("none", "wave") ==
        replaced(yaml, "{x: {type: double}}\n",
                 "{x: {type: double}}\n    behaviours:\n      wave: {type: scripted}\n"));
  CHECK(add("flat", "wave") ==
        replaced(yaml, "{w: {type: double}}}",
                 "{w: {type: double}}, behaviours: {wave: {type: scripted}}}"));
  // So does one moved into it.
  const EditResult moved =
      checked(loaded, move_behaviour(loaded, "flow", "c", "none", 0), registry);
  INFO(moved.refused);
  REQUIRE(moved.ok());
  CHECK(apply_edits(yaml, loaded.files.files().front()->path, moved.edits) ==
        replaced(replaced(yaml, "{c: scripted}", "{}"), "{x: {type: double}}\n",
                 "{x: {type: double}}\n    behaviours:\n      c: scripted\n"));
  CHECK(add_behaviour(loaded, "block", "a", "scripted").refused == "'a' is already taken");
  CHECK(add_behaviour(loaded, "block", "A b", "scripted").refused ==
        "'A b' is not a valid name: names are lower-case identifiers ([a-z_][a-z0-9_]*)");
  CHECK(add_behaviour(loaded, "other", "w", "scripted").refused == "no layer 'other'");
  // A class that does not exist: the check refuses it in validate's words.
  CHECK_THAT(checked(loaded, add_behaviour(loaded, "block", "w", "no.Such"), registry).refused,
             Catch::Contains("unknown"));
}

TEST_CASE("a behaviour is removed with its lines and the inhibitions that name it", "[edit]") {
  const std::string yaml = R"(arbiter: 1
name: remove
layers:
  - name: block
    behaviours:
      a: scripted   # first
      b:
        type: scripted
        params: {activation: 1}
      c: scripted
    inhibitions:
      - a => b
      - b -> c   # second
      - a => c
  - name: pair
    behaviours:
      g: scripted
      h: scripted
    inhibitions: [g => h]
  - name: flow
    behaviours: {e: scripted, f: scripted}
)";
  test::TempDir dir;
  Registry registry = builtin_registry();
  const Loaded loaded = load_config(dir.write("remove.yaml", yaml), registry);
  REQUIRE_FALSE(loaded.diagnostics.has_errors());
  const std::string& text = yaml;
  auto remove = [&](const std::string& layer, const std::string& name) {
    const EditResult result = checked(loaded, remove_behaviour(loaded, layer, name), registry);
    INFO(result.refused);
    REQUIRE(result.ok());
    return apply_edits(text, loaded.files.files().front()->path, result.edits);
  };
  CHECK(remove("block", "b") ==
        replaced(
            replaced(
                replaced(text,
                         "      b:\n        type: scripted\n        params: {activation: 1}\n", ""),
                "      - a => b\n", ""),
            "      - b -> c   # second\n", ""));
  CHECK(remove("block", "a") ==
        replaced(
            replaced(replaced(text, "      a: scripted   # first\n", ""), "      - a => b\n", ""),
            "      - a => c\n", ""));
  // The only inhibition of a flow sequence, as remove_inhibition removes it.
  CHECK(remove("pair", "h") == replaced(replaced(text, "      h: scripted\n", ""),
                                        "    inhibitions: [g => h]\n", "    inhibitions: []\n"));
  // In a flow mapping: its text and one comma.
  CHECK(remove("flow", "e") == replaced(text, "{e: scripted, f: scripted}", "{f: scripted}"));
  CHECK(remove("flow", "f") == replaced(text, "{e: scripted, f: scripted}", "{e: scripted}"));
  CHECK(remove_behaviour(loaded, "block", "z").refused == "no behaviour 'z' in layer 'block'");
}

namespace {

/// A config written in a temporary directory (its first file the config, the others its
/// includes), loaded with the test classes, for an operation's edits to be checked against.
class Workspace {
 public:
  explicit Workspace(const std::vector<std::pair<std::string, std::string>>& files)
      : registry_(make_test_registry()) {
    for (const auto& [name, text] : files) {
      paths_[name] = dir_.write(name, text);
      texts_[name] = text;
    }
    loaded_ = load_config(paths_.at(files.front().first), registry_);
    INFO(format(loaded_.diagnostics));
    REQUIRE_FALSE(loaded_.diagnostics.has_errors());
  }

  const Loaded& loaded() const { return loaded_; }

  /// The text of file `name` after the edits `proposed` makes, which checked() accepts.
  std::string edited(const EditResult& proposed, const std::string& name) {
    const EditResult result = checked(loaded_, proposed, registry_);
    INFO(result.refused);
    REQUIRE(result.ok());
    REQUIRE_FALSE(result.edits.empty());
    return apply_edits(texts_.at(name), loaded_.files.find(paths_.at(name))->path, result.edits);
  }

  /// Why `proposed` (checked) is refused; "" when it is not.
  std::string refused(const EditResult& proposed) {
    return checked(loaded_, proposed, registry_).refused;
  }

  const std::string& text(const std::string& name) const { return texts_.at(name); }

 private:
  test::TempDir dir_;
  Registry registry_;
  std::map<std::string, std::string> paths_, texts_;
  Loaded loaded_;
};

const std::string kOpsYaml = R"(arbiter: 1
name: ops
include: [part.yaml]
layers:
  - name: top   # first
    actuators:
      speed: {type: double}
      # not read by anyone
      spare: {type: double}
    behaviours:
      a: scripted   # the first
      b:
        type: scripted
        params: {activation: 0.5}
      c: scripted
    inhibitions:
      - a => b

  # the lower layer
  - name: low
    sensors: [speed]
    actuators: {out: {type: double}}
    behaviours: {d: scripted, e: test.Probe}

state_machines:
  plan:
    states:
      one: {type: scripted, params: {hold: 2}}
      two: scripted
      idle: scripted   # not planned
    queue:
      - one
      - two: {hold: 3}   # the second
      - one
  flat:
    states: {x: scripted, y: scripted}
    queue: [x, y]
)";

const std::string kOpsPart = R"(# The included layers.
layers:
  - name: inc
    behaviours:
      p: scripted
      q: scripted
  - name: inc2
    behaviours:
      r: scripted
)";

const std::string kOpsJson = R"({
  "arbiter": 1,
  "name": "ops",
  "layers": [
    {
      "name": "top",
      "actuators": {"speed": {"type": "double"}},
      "behaviours": {
        "a": "scripted",
        "b": {"type": "scripted", "params": {"activation": 0.5}},
        "c": "test.Probe"
      }
    },
    {"name": "low", "sensors": ["speed"], "actuators": {"spare": {"type": "int"}}, "behaviours": {"d": "scripted"}}
  ],
  "state_machines": {
    "plan": {"states": {"one": "scripted", "two": "scripted"}, "queue": ["one", "two"]}
  }
}
)";

}  // namespace

TEST_CASE("a behaviour moves within its layer, to another layer, and into an include", "[edit]") {
  Workspace yaml({{"ops.yaml", kOpsYaml}, {"part.yaml", kOpsPart}});
  const Loaded& loaded = yaml.loaded();
  const std::string& text = yaml.text("ops.yaml");
  const std::string abc =
      "      a: scripted   # the first\n      b:\n        type: scripted\n        params: "
      "{activation: 0.5}\n      c: scripted\n";
  CHECK(yaml.edited(move_behaviour(loaded, "top", "c", "", 0), "ops.yaml") ==
        replaced(text, abc,
                 "      c: scripted\n      a: scripted   # the first\n      b:\n        type: "
                 "scripted\n        params: {activation: 0.5}\n"));
  CHECK(yaml.edited(move_behaviour(loaded, "top", "b", "top", 2), "ops.yaml") ==
        replaced(text, abc,
                 "      a: scripted   # the first\n      c: scripted\n      b:\n        type: "
                 "scripted\n        params: {activation: 0.5}\n"));
  CHECK(yaml.edited(move_behaviour(loaded, "low", "d", "", 1), "ops.yaml") ==
        replaced(text, "{d: scripted, e: test.Probe}", "{e: test.Probe, d: scripted}"));
  // To a flow mapping of another layer, and to the included file that declares the layer.
  CHECK(yaml.edited(move_behaviour(loaded, "top", "c", "low", 0), "ops.yaml") ==
        replaced(replaced(text, "      c: scripted\n", ""), "{d: scripted,",
                 "{c: scripted, d: scripted,"));
  const EditResult into_include = move_behaviour(loaded, "top", "c", "inc", 1);
  CHECK(yaml.edited(into_include, "ops.yaml") == replaced(text, "      c: scripted\n", ""));
  CHECK(yaml.edited(into_include, "part.yaml") ==
        replaced(kOpsPart, "      q: scripted\n", "      c: scripted\n      q: scripted\n"));
  CHECK(yaml.edited(move_behaviour(loaded, "inc", "q", "inc2", 1), "part.yaml") ==
        replaced(replaced(kOpsPart, "      q: scripted\n", ""), "      r: scripted\n",
                 "      r: scripted\n      q: scripted\n"));

  CHECK(move_behaviour(loaded, "top", "b", "low", 0).refused ==
        "'b' is named by the inhibition 'a -> b' of layer 'top', which cannot follow it to another "
        "layer: remove it first");
  CHECK(move_behaviour(loaded, "top", "c", "", 3).refused ==
        "position 3 is past the end of layer 'top', which has 3 behaviour(s): positions count "
        "from 0");
  CHECK(move_behaviour(loaded, "top", "c", "", 2).refused == "'c' is at position 2 already");
  CHECK(move_behaviour(loaded, "top", "z", "", 0).refused == "no behaviour 'z' in layer 'top'");
  CHECK(move_behaviour(loaded, "top", "c", "nowhere", 0).refused == "no layer 'nowhere'");

  Workspace json({{"ops.json", kOpsJson}});
  const std::string& json_text = json.text("ops.json");
  CHECK(json.edited(move_behaviour(json.loaded(), "top", "a", "", 2), "ops.json") ==
        replaced(json_text,
                 R"("a": "scripted",
        "b": {"type": "scripted", "params": {"activation": 0.5}},
        "c": "test.Probe")",
                 R"("b": {"type": "scripted", "params": {"activation": 0.5}},
        "c": "test.Probe",
        "a": "scripted")"));
  CHECK(json.edited(move_behaviour(json.loaded(), "top", "c", "low", 1), "ops.json") ==
        replaced(replaced(json_text, ",\n        \"c\": \"test.Probe\"", ""),
                 R"({"d": "scripted"})", R"({"d": "scripted", "c": "test.Probe"})"));
}

TEST_CASE("a layer moves among its file's layers, its comments and blank lines kept", "[edit]") {
  Workspace yaml({{"ops.yaml", kOpsYaml}, {"part.yaml", kOpsPart}});
  const Loaded& loaded = yaml.loaded();
  const std::string& text = yaml.text("ops.yaml");
  // The config's order: inc and inc2 (the include's), then top and low.
  const std::string top = text.substr(text.find("  - name: top"),
                                      text.find("\n\n  # the lower") - text.find("  - name: top"));
  const std::string low = text.substr(text.find("  # the lower"),
                                      text.find("\n\nstate_machines") - text.find("  # the lower"));
  CHECK(yaml.edited(move_layer(loaded, "low", 2), "ops.yaml") ==
        replaced(text, top + "\n\n" + low, low + "\n\n" + top));
  CHECK(yaml.edited(move_layer(loaded, "inc2", 0), "part.yaml") ==
        replaced(kOpsPart,
                 "  - name: inc\n    behaviours:\n      p: scripted\n      q: scripted\n"
                 "  - name: inc2\n    behaviours:\n      r: scripted\n",
                 "  - name: inc2\n    behaviours:\n      r: scripted\n"
                 "  - name: inc\n    behaviours:\n      p: scripted\n      q: scripted\n"));
  CHECK(move_layer(loaded, "top", 0).refused ==
        fmt::format("position 0 holds layer 'inc' of {}, and layer 'top' is declared in {}: a "
                    "file's layers keep their place among the included ones, so move it between "
                    "the files in the text",
                    loaded.files.files()[1]->path, loaded.files.files()[0]->path));
  CHECK(move_layer(loaded, "top", 4).refused ==
        "position 4 is past the last layer: the config has 4 layer(s), positions count from 0");
  CHECK(move_layer(loaded, "top", 2).refused == "layer 'top' is at position 2 already");
  CHECK(move_layer(loaded, "none", 0).refused == "no layer 'none'");

  Workspace json({{"ops.json", kOpsJson}});
  const std::string& json_text = json.text("ops.json");
  const std::string json_top = json_text.substr(
      json_text.find("    {\n      \"name\": \"top\"") + 4,
      json_text.find("\n    },\n") + 6 - json_text.find("    {\n      \"name\": \"top\"") - 4);
  const std::string json_low =
      R"({"name": "low", "sensors": ["speed"], "actuators": {"spare": {"type": "int"}}, "behaviours": {"d": "scripted"}})";
  CHECK(json.edited(move_layer(json.loaded(), "top", 1), "ops.json") ==
        replaced(json_text, json_top + ",\n    " + json_low, json_low + ",\n    " + json_top));
}

TEST_CASE("an actuator is added and removed in its layer's actuators:, and refused while used",
          "[edit]") {
  Workspace yaml({{"ops.yaml", kOpsYaml}, {"part.yaml", kOpsPart}});
  const Loaded& loaded = yaml.loaded();
  const std::string& text = yaml.text("ops.yaml");
  CHECK(yaml.edited(add_actuator(loaded, "top", "gain", "int"), "ops.yaml") ==
        replaced(text, "      spare: {type: double}\n",
                 "      spare: {type: double}\n      gain: {type: int}\n"));
  CHECK(yaml.edited(add_actuator(loaded, "low", "gain", "vec2"), "ops.yaml") ==
        replaced(text, "{out: {type: double}}", "{out: {type: double}, gain: {type: vec2}}"));
  CHECK(yaml.edited(add_actuator(loaded, "inc2", "gain", "bool"), "part.yaml") ==
        kOpsPart + "    actuators: {gain: {type: bool}}\n");
  CHECK(add_actuator(loaded, "low", "speed", "double").refused ==
        "'speed' is already taken: layer 'top' declares an actuator of that name");
  CHECK(add_actuator(loaded, "low", "Speed", "double").refused ==
        "'Speed' is not a valid name: names are lower-case identifiers ([a-z_][a-z0-9_]*)");
  CHECK_THAT(yaml.refused(add_actuator(loaded, "low", "gain", "quaternion")),
             Catch::Contains("quaternion"));

  // Removed with the comment above it (the only one of a flow mapping leaves `{}`, below).
  CHECK(yaml.edited(remove_actuator(loaded, "top", "spare"), "ops.yaml") ==
        replaced(text, "      # not read by anyone\n      spare: {type: double}\n", ""));
  CHECK(remove_actuator(loaded, "low", "out").refused ==
        "actuator 'out' is still used: port 'out' of 'e' is bound to it. Remove or rebind those "
        "first");
  CHECK(remove_actuator(loaded, "top", "speed").refused ==
        "actuator 'speed' is still used: layer 'low' reads it. Remove or rebind those first");
  CHECK(remove_actuator(loaded, "top", "out").refused == "no actuator 'out' in layer 'top'");

  // A port bound to it, by a ports: entry or by its name, is a use too.
  const std::string bound = R"(arbiter: 1
name: ports
layers:
  - name: l
    actuators:
      out: {type: double}
      level: {type: double}
    behaviours:
      probe: test.Probe
      other: {type: test.Probe, ports: {out: level}}
)";
  Workspace ports({{"ports.yaml", bound}});
  CHECK(remove_actuator(ports.loaded(), "l", "out").refused ==
        "actuator 'out' is still used: port 'out' of 'probe' is bound to it. Remove or rebind "
        "those first");
  CHECK(remove_actuator(ports.loaded(), "l", "level").refused ==
        "actuator 'level' is still used: port 'out' of 'other' is bound to it. Remove or rebind "
        "those first");

  Workspace json({{"ops.json", kOpsJson}});
  CHECK(json.edited(add_actuator(json.loaded(), "low", "gain", "double"), "ops.json") ==
        replaced(json.text("ops.json"), R"({"spare": {"type": "int"}})",
                 R"({"spare": {"type": "int"}, "gain": {"type": "double"}})"));
  CHECK(json.edited(remove_actuator(json.loaded(), "low", "spare"), "ops.json") ==
        replaced(json.text("ops.json"), R"({"spare": {"type": "int"}})", "{}"));
}

TEST_CASE("a port is wired by its behaviour's ports: entry, added or replaced", "[edit]") {
  const std::string yaml = R"(arbiter: 1
name: ports
layers:
  - name: l
    sensors: [feed]
    actuators:
      out: {type: double}
      level: {type: double}
    behaviours:
      probe: test.Probe
      other: {type: test.Probe, ports: {out: level}}
      third:
        type: test.Probe   # no ports yet
  - name: m
    actuators: {feed: {type: double}}
)";
  Workspace ports({{"ports.yaml", yaml}});
  const Loaded& loaded = ports.loaded();
  CHECK(ports.edited(wire_port(loaded, "l", "probe", "out", "level"), "ports.yaml") ==
        replaced(yaml, "probe: test.Probe", "probe: {type: test.Probe, ports: {out: level}}"));
  CHECK(ports.edited(wire_port(loaded, "l", "other", "out", "out"), "ports.yaml") ==
        replaced(yaml, "{out: level}", "{out: out}"));
  CHECK(ports.edited(wire_port(loaded, "l", "other", "in", "feed"), "ports.yaml") ==
        replaced(yaml, "{out: level}", "{out: level, in: feed}"));
  CHECK(ports.edited(wire_port(loaded, "l", "third", "in", "feed"), "ports.yaml") ==
        replaced(yaml, "# no ports yet\n", "# no ports yet\n        ports: {in: feed}\n"));
  CHECK(wire_port(loaded, "l", "other", "out", "level").refused ==
        "port 'out' of 'other' is bound to 'level' already");
  CHECK(wire_port(loaded, "l", "nobody", "out", "level").refused ==
        "no behaviour 'nobody' in layer 'l'");
  CHECK(wire_port(loaded, "l", "probe", "out", "Level").refused ==
        "'Level' is not a name in a port binding: names are lower-case identifiers "
        "([a-z_][a-z0-9_]*)");
  // What validate refuses (a port the class does not have, a name the layer cannot bind) is
  // refused in its words.
  CHECK_THAT(ports.refused(wire_port(loaded, "l", "probe", "nope", "level")),
             Catch::Contains("nope"));
  CHECK_THAT(ports.refused(wire_port(loaded, "l", "probe", "out", "missing")),
             Catch::Contains("missing"));

  Workspace json({{"ops.json", kOpsJson}});
  CHECK(json.edited(wire_port(json.loaded(), "top", "c", "out", "speed"), "ops.json") ==
        replaced(json.text("ops.json"), R"("c": "test.Probe")",
                 R"("c": {"type": "test.Probe", "ports": {"out": "speed"}})"));
}

TEST_CASE("a state machine's queue gets a state with its params, loses one, and is reordered",
          "[edit]") {
  Workspace yaml({{"ops.yaml", kOpsYaml}, {"part.yaml", kOpsPart}});
  const Loaded& loaded = yaml.loaded();
  const std::string& text = yaml.text("ops.yaml");
  const std::string queue = "      - one\n      - two: {hold: 3}   # the second\n      - one\n";
  CHECK(yaml.edited(add_queue_entry(loaded, "plan", "two", {{"hold", "4"}}, 0), "ops.yaml") ==
        replaced(text, queue, "      - two: {hold: 4}\n" + queue));
  CHECK(yaml.edited(add_queue_entry(loaded, "plan", "one", {}, kAtEnd), "ops.yaml") ==
        replaced(text, queue, queue + "      - one\n"));
  CHECK(yaml.edited(add_queue_entry(loaded, "flat", "y", {}, 1), "ops.yaml") ==
        replaced(text, "queue: [x, y]", "queue: [x, y, y]"));
  CHECK(yaml.edited(add_queue_entry(loaded, "flat", "x", {{"hold", "2"}}, 0), "ops.yaml") ==
        replaced(text, "queue: [x, y]", "queue: [{x: {hold: 2}}, x, y]"));
  CHECK(yaml.edited(remove_queue_entry(loaded, "plan", 1), "ops.yaml") ==
        replaced(text, queue, "      - one\n      - one\n"));
  CHECK(yaml.edited(remove_queue_entry(loaded, "flat", 0), "ops.yaml") ==
        replaced(text, "queue: [x, y]", "queue: [y]"));
  CHECK(yaml.edited(move_queue_entry(loaded, "plan", 1, 2), "ops.yaml") ==
        replaced(text, queue, "      - one\n      - one\n      - two: {hold: 3}   # the second\n"));
  CHECK(yaml.edited(move_queue_entry(loaded, "flat", 1, 0), "ops.yaml") ==
        replaced(text, "queue: [x, y]", "queue: [y, x]"));

  CHECK(add_queue_entry(loaded, "plan", "one", {}, 4).refused ==
        "position 4 is past the end of the queue of state machine 'plan', which has 3 state(s): "
        "positions count from 0");
  CHECK(add_queue_entry(loaded, "nobody", "one", {}, 0).refused == "no state machine 'nobody'");
  CHECK(add_queue_entry(loaded, "plan", "one", {{"Hold", "1"}}, 0).refused ==
        "'Hold' is not a param's name: names are lower-case identifiers ([a-z_][a-z0-9_]*)");
  CHECK(move_queue_entry(loaded, "plan", 0, 0).refused ==
        "the state at position 0 is there already");
  CHECK(remove_queue_entry(loaded, "plan", 3).refused ==
        "position 3 is past the end of the queue of state machine 'plan', which has 3 state(s): "
        "positions count from 0");
  // A state the machine does not declare, or a param its class lacks: validate's words.
  CHECK_THAT(yaml.refused(add_queue_entry(loaded, "plan", "three", {}, 0)),
             Catch::Contains("three"));
  CHECK_THAT(yaml.refused(add_queue_entry(loaded, "plan", "one", {{"speed", "1"}}, 0)),
             Catch::Contains("speed"));

  // The last item of a block queue: `queue:` alone would be null.
  const std::string solo =
      "arbiter: 1\nname: solo\nstate_machines:\n  solo:\n    states: {s: "
      "scripted}\n    queue:\n      - s   # only\n    capacity: 4\n";
  Workspace one({{"solo.yaml", solo}});
  CHECK(one.edited(remove_queue_entry(one.loaded(), "solo", 0), "solo.yaml") ==
        replaced(solo, "    queue:\n      - s   # only\n", "    queue: []\n"));

  Workspace json({{"ops.json", kOpsJson}});
  const std::string& json_text = json.text("ops.json");
  CHECK(
      json.edited(add_queue_entry(json.loaded(), "plan", "two", {{"hold", "2"}}, 1), "ops.json") ==
      replaced(json_text, R"(["one", "two"])", R"(["one", {"two": {"hold": 2}}, "two"])"));
  CHECK(json.edited(move_queue_entry(json.loaded(), "plan", 0, 1), "ops.json") ==
        replaced(json_text, R"(["one", "two"])", R"(["two", "one"])"));
  CHECK(json.edited(remove_queue_entry(json.loaded(), "plan", 1), "ops.json") ==
        replaced(json_text, R"(["one", "two"])", R"(["one"])"));
}

namespace {

/// One operation of the edit engine, applied to an element of a config chosen by `make` (none
/// when the config has no such element). A refusal is accepted only when `may_refuse` says it is
/// one of the documented reasons.
struct Applied {
  const char* name;
  std::function<std::optional<EditResult>(const Loaded&, const Model&)> make;
  bool reorders = false;  ///< a move: the same bytes, in another order
  std::function<bool(const std::string&)> may_refuse = [](const std::string&) { return false; };
  /// Accepted in some shipped config. Every actuator they declare is used, so each removal is
  /// refused (with its uses named); an accepted one is tested on a config of its own above.
  bool accepted_somewhere = true;
};

const LayerDecl* first_behaviour_layer(const Model& model) {
  for (const auto& layer : model.layers) {
    if (!layer.is_interface() && !layer.behaviours.empty()) return &layer;
  }
  return nullptr;
}

/// The config's first inhibition, in the order of its layers; none when it has none.
std::optional<InhibitionRef> first_inhibition(const Model& model) {
  for (const auto& layer : model.layers) {
    for (const auto& inhibition : layer.inhibitions)
      return InhibitionRef{layer.name.text, inhibition.inhibitor.text, inhibition.inhibited.text};
  }
  return std::nullopt;
}

/// The bytes of `text`, sorted: what a move of its items leaves as it was.
std::string sorted_bytes(std::string text) {
  std::sort(text.begin(), text.end());
  return text;
}

/// A removal of an actuator refused for its uses: named by remove_actuator, or in validate's
/// words for a scripted behaviour's writes: to it.
bool actuator_in_use(const std::string& why) {
  return contains(why, "is still used") || (contains(why, "the edit would leave an error") &&
                                            contains(why, "is not an actuator of layer"));
}

std::vector<Applied> every_operation() {
  using Made = std::optional<EditResult>;
  return {
      {"rename behaviour",
       [](const Loaded& loaded, const Model& model) -> Made {
         const LayerDecl* layer = first_behaviour_layer(model);
         if (!layer) return std::nullopt;
         Registry registry = builtin_registry();
         const ConfigIndex index = index_config(loaded, &registry);
         for (const auto& symbol : index.occurrences) {
           if (symbol.definition && symbol.kind == SymbolKind::kBehaviour &&
               symbol.scope == layer->name.text)
             return rename_symbol(loaded, index, symbol, symbol.name + "_renamed");
         }
         return std::nullopt;
       }},
      {"flip the first inhibition",
       [](const Loaded& loaded, const Model& model) -> Made {
         const auto inhibition = first_inhibition(model);
         if (!inhibition) return std::nullopt;
         return flip_chaining(loaded, *inhibition);
       }},
      {"remove the first inhibition",
       [](const Loaded& loaded, const Model& model) -> Made {
         const auto inhibition = first_inhibition(model);
         if (!inhibition) return std::nullopt;
         return remove_inhibition(loaded, *inhibition);
       }},
      {"set activation of the first behaviour",
       [](const Loaded& loaded, const Model& model) -> Made {
         for (const auto& layer : model.layers) {
           for (const auto& behaviour : layer.behaviours) {
             if (behaviour.params.find("activation") != nullptr)
               return set_param(loaded, layer.name.text, behaviour.name.text, "activation", "1");
           }
         }
         return std::nullopt;
       }},
      {"add a behaviour",
       [](const Loaded& loaded, const Model& model) -> Made {
         const LayerDecl* layer = first_behaviour_layer(model);
         if (!layer) return std::nullopt;
         return add_behaviour(loaded, layer->name.text, "added_behaviour", "scripted");
       }},
      {"add a layer last",
       [](const Loaded& loaded, const Model&) -> Made { return add_layer(loaded, "added_layer"); }},
      {"remove the last layer",
       [](const Loaded& loaded, const Model& model) -> Made {
         if (model.layers.empty()) return std::nullopt;
         return remove_layer(loaded, model.layers.back().name.text);
       },
       false,
       // Read by another layer, or owning a state machine whose states bind its ports.
       [](const std::string& why) {
         return contains(why, "is still used") || contains(why, "the edit would leave an error");
       }},
      {"add a state machine",
       [](const Loaded& loaded, const Model&) -> Made {
         return add_state_machine(loaded, "added_machine");
       }},
      {"remove the last state machine",
       [](const Loaded& loaded, const Model& model) -> Made {
         if (model.state_machines.empty()) return std::nullopt;
         Registry registry = builtin_registry();
         return remove_state_machine(loaded, index_config(loaded, &registry),
                                     model.state_machines.back().name.text);
       },
       false,
       // Owned by a behaviour or a state, or planned by a class.
       [](const std::string& why) {
         return contains(why, "is still named") || contains(why, "the edit would leave an error");
       }},
      {"remove the last behaviour",
       [](const Loaded& loaded, const Model& model) -> Made {
         const LayerDecl* layer = first_behaviour_layer(model);
         if (!layer) return std::nullopt;
         return remove_behaviour(loaded, layer->name.text, layer->behaviours.back().name.text);
       },
       false,
       // What else names it (a port, a state machine's owner) is refused in validate's words.
       [](const std::string& why) {
         return contains(why, "the edit would leave an error") ||
                contains(why, "is not written on a line of its own");
       }},
      {"move the last behaviour first",
       [](const Loaded& loaded, const Model& model) -> Made {
         for (const auto& layer : model.layers) {
           if (layer.behaviours.size() >= 2)
             return move_behaviour(loaded, layer.name.text, layer.behaviours.back().name.text, "",
                                   0);
         }
         return std::nullopt;
       },
       true},
      {"move the last layer of a file first among its layers",
       [](const Loaded& loaded, const Model& model) -> Made {
         if (model.layers.size() < 2) return std::nullopt;
         // The first layer declared in the file that declares the last one.
         const std::string& last = model.layers.back().name.text;
         const SourceFile* file = nullptr;
         for (const auto& source : loaded.files.files()) {
           const Node* layers =
               source->root && source->root->is_mapping() ? source->root->find("layers") : nullptr;
           for (std::size_t i = 0; layers && layers->is_sequence() && i < layers->size(); ++i) {
             const Node* name = layers->items()[i].find("name");
             if (name && name->text() == last) file = source.get();
           }
         }
         const Node& own = *file->root->find("layers");
         if (own.size() < 2) return std::nullopt;
         const std::string first = own.items().front().find("name")->text();
         for (std::size_t i = 0; i < model.layers.size(); ++i) {
           if (model.layers[i].name.text == first) return move_layer(loaded, last, i);
         }
         return std::nullopt;
       },
       true},
      {"add an actuator",
       [](const Loaded& loaded, const Model& model) -> Made {
         if (model.layers.empty()) return std::nullopt;
         return add_actuator(loaded, model.layers.back().name.text, "added_actuator", "double");
       }},
      {"remove an actuator",
       [](const Loaded& loaded, const Model& model) -> Made {
         // The first that nothing uses, else the first refusal that is not for a use, else the
         // last.
         Made last;
         for (const auto& layer : model.layers) {
           for (const auto& actuator : layer.actuators) {
             Registry registry = builtin_registry();
             last = checked(loaded, remove_actuator(loaded, layer.name.text, actuator.name.text),
                            registry);
             if (last->ok() || !actuator_in_use(last->refused)) return last;
           }
         }
         return last;
       },
       false, &actuator_in_use, false},
      {"wire the first bound port to its target by name",
       [](const Loaded& loaded, const Model& model) -> Made {
         for (const auto& layer : model.layers) {
           for (const auto& behaviour : layer.behaviours) {
             for (const auto& binding : behaviour.ports) {
               if (binding.port && !binding.target.empty() && binding.target == binding.port->name)
                 return wire_port(loaded, layer.name.text, behaviour.name.text, binding.port->name,
                                  binding.target);
             }
           }
         }
         return std::nullopt;
       },
       false, [](const std::string& why) { return contains(why, "already"); }},
      {"add a state",
       [](const Loaded& loaded, const Model& model) -> Made {
         if (model.state_machines.empty()) return std::nullopt;
         return add_state(loaded, model.state_machines.front().name.text, "added_state",
                          "scripted");
       }},
      {"remove the last state",
       [](const Loaded& loaded, const Model& model) -> Made {
         if (model.state_machines.empty()) return std::nullopt;
         const auto& machine = model.state_machines.front();
         Registry registry = builtin_registry();
         return remove_state(loaded, index_config(loaded, &registry), machine.name.text,
                             machine.states.back().name.text);
       },
       false,
       // Named in the config, or planned by a class (the soccer goalie's dive), in validate's
       // words. Every state of the shipped configs is one or the other; an accepted removal is
       // tested on a config of its own above.
       [](const std::string& why) {
         return contains(why, "is still named at") || contains(why, "does not declare");
       },
       false},
      {"plan the first state last",
       [](const Loaded& loaded, const Model& model) -> Made {
         for (const auto& machine : model.state_machines) {
           if (!machine.states.empty())
             return add_queue_entry(loaded, machine.name.text, machine.states.front().name.text, {},
                                    kAtEnd);
         }
         return std::nullopt;
       }},
      {"remove the first state of a queue",
       [](const Loaded& loaded, const Model& model) -> Made {
         for (const auto& machine : model.state_machines) {
           if (!machine.queue.empty()) return remove_queue_entry(loaded, machine.name.text, 0);
         }
         return std::nullopt;
       }},
      {"move the first state of a queue last",
       [](const Loaded& loaded, const Model& model) -> Made {
         for (const auto& machine : model.state_machines) {
           if (machine.queue.size() >= 2)
             return move_queue_entry(loaded, machine.name.text, 0, machine.queue.size() - 1);
         }
         return std::nullopt;
       },
       true},
  };
}

}  // namespace

TEST_CASE(
    "every operation applied to every shipped config leaves a valid config and every "
    "untouched line",
    "[edit]") {
  const std::vector<Applied> operations = every_operation();
  std::map<std::string, int> applied;
  for (const auto& path : configs_under(kSourceDir / "configs")) {
    if (!plugins_built(path)) continue;
    Registry registry = builtin_registry();
    const Loaded loaded = load_config(path.string(), registry);
    if (!loaded.model || loaded.diagnostics.has_errors()) continue;
    for (const auto& operation : operations) {
      {
        // No sections: each config and operation once, the counts below seeing every one.
        INFO(operation.name << " in " << fs::relative(path, kSourceDir).string());
        const std::optional<EditResult> made = operation.make(loaded, *loaded.model);
        if (!made) continue;
        Registry check = builtin_registry();
        const EditResult result = checked(loaded, *made, check);
        INFO(result.refused);
        if (!result.ok()) {
          CHECK(operation.may_refuse(result.refused));
          continue;
        }
        CHECK_FALSE(result.edits.empty());
        ++applied[operation.name];
        Registry again = builtin_registry();
        const EditedConfig after_edit = load_edited(loaded, result.edits, again);
        const Loaded& edited = after_edit.loaded;
        INFO(format(edited.diagnostics));
        CHECK_FALSE(edited.diagnostics.has_errors());
        for (const auto& file : loaded.files.files()) {
          const SourceFile* after = edited.files.find(file->path);
          CHECK(after != nullptr);
          if (after == nullptr) continue;
          INFO(after->text);
          if (operation.reorders) {
            check_untouched(file->text, after->text, result.edits, file->path);
            CHECK(sorted_bytes(file->text) == sorted_bytes(after->text));
          } else {
            check_lines_kept(file->text, after->text, result.edits, file->path);
          }
        }
      }
    }
  }
  // Each operation found an element to apply to somewhere, and was accepted there.
  for (const auto& operation : operations) {
    INFO(operation.name);
    CHECK((applied[operation.name] > 0) == operation.accepted_somewhere);
  }
}

TEST_CASE("the index gives each item of a queue by its position, a state queued twice at each",
          "[edit]") {
  Workspace yaml({{"ops.yaml", kOpsYaml}, {"part.yaml", kOpsPart}});
  const ConfigIndex index = index_config(yaml.loaded(), nullptr);
  const std::string& text = yaml.text("ops.yaml");
  std::vector<std::string> plan;
  for (const auto& item : index.queue_items) {
    if (item.machine != "plan") continue;
    // The state's name, by which an editor finds the item under the cursor.
    CHECK(text.substr(item.begin, item.end - item.begin) == item.state);
    plan.push_back(fmt::format("{}@{}", item.state, item.index));
  }
  CHECK(plan == std::vector<std::string>{"one@0", "two@1", "one@2"});

  Workspace json({{"ops.json", kOpsJson}});
  std::vector<std::string> queued;
  for (const auto& item : index_config(json.loaded(), nullptr).queue_items) {
    CHECK(json.text("ops.json").substr(item.begin, item.end - item.begin) == item.state);
    queued.push_back(fmt::format("{}@{}", item.state, item.index));
  }
  CHECK(queued == std::vector<std::string>{"one@0", "two@1"});
}

TEST_CASE("a state is declared in its machine's states:, and removed unless something names it",
          "[edit]") {
  Workspace yaml({{"ops.yaml", kOpsYaml}, {"part.yaml", kOpsPart}});
  const Loaded& loaded = yaml.loaded();
  const std::string& text = yaml.text("ops.yaml");
  CHECK(yaml.edited(add_state(loaded, "plan", "three", "scripted"), "ops.yaml") ==
        replaced(text, "# not planned\n", "# not planned\n      three: {type: scripted}\n"));
  CHECK(yaml.edited(add_state(loaded, "flat", "z", "scripted"), "ops.yaml") ==
        replaced(text, "{x: scripted, y: scripted}",
                 "{x: scripted, y: scripted, z: {type: scripted}}"));
  CHECK(add_state(loaded, "plan", "one", "scripted").refused ==
        "'one' is already taken in state machine 'plan'");
  CHECK(add_state(loaded, "none", "one", "scripted").refused == "no state machine 'none'");
  CHECK_THAT(yaml.refused(add_state(loaded, "plan", "three", "no.Such")),
             Catch::Contains("no.Such"));

  Registry registry = make_test_registry();
  const ConfigIndex index = index_config(loaded, &registry);
  CHECK(yaml.edited(remove_state(loaded, index, "plan", "idle"), "ops.yaml") ==
        replaced(text, "      idle: scripted   # not planned\n", ""));
  const std::string path = loaded.files.files().front()->path;
  CHECK(remove_state(loaded, index, "plan", "two").refused ==
        fmt::format("state 'two' of state machine 'plan' is still named at {}:33:9: remove those "
                    "first",
                    path));
  CHECK(remove_state(loaded, index, "flat", "x").refused ==
        fmt::format("state 'x' of state machine 'flat' is still named at {}:37:13: remove those "
                    "first",
                    path));
  CHECK(remove_state(loaded, index, "plan", "nobody").refused ==
        "no state 'nobody' in state machine 'plan'");

  Workspace json({{"ops.json", kOpsJson}});
  CHECK(json.edited(add_state(json.loaded(), "plan", "three", "scripted"), "ops.json") ==
        replaced(json.text("ops.json"), R"({"one": "scripted", "two": "scripted"})",
                 R"({"one": "scripted", "two": "scripted", "three": {"type": "scripted"}})"));
}

/// One file's name and text, or several: a Workspace's files.
using Files = std::vector<std::pair<std::string, std::string>>;

TEST_CASE("a layer is added at its position, or as the first of a list, and removed unless read",
          "[edit]") {
  Workspace yaml({{"ops.yaml", kOpsYaml}, {"part.yaml", kOpsPart}});
  const Loaded& loaded = yaml.loaded();
  const std::string& text = yaml.text("ops.yaml");
  // The config's order: inc and inc2 (the include's), then top and low.
  CHECK(yaml.edited(add_layer(loaded, "mid", 3), "ops.yaml") ==
        replaced(text, "  # the lower layer\n", "  - name: mid\n  # the lower layer\n"));
  CHECK(yaml.edited(add_layer(loaded, "io", kAtEnd, "inputs"), "ops.yaml") ==
        replaced(text, "{d: scripted, e: test.Probe}\n",
                 "{d: scripted, e: test.Probe}\n  - name: io\n    interface: inputs\n"));
  CHECK(add_layer(loaded, "mid", 1).refused ==
        "position 1 holds a layer of an included file: an included file's layers come first, so "
        "the config's own start at position 2");
  CHECK(add_layer(loaded, "mid", 5).refused ==
        "position 5 is past the end: the config has 4 layer(s), positions count from 0");
  CHECK(add_layer(loaded, "inc", kAtEnd).refused ==
        "'inc' is already taken: a layer of that name is declared");
  CHECK(add_layer(loaded, "Mid", kAtEnd).refused ==
        "'Mid' is not a valid name: names are lower-case identifiers ([a-z_][a-z0-9_]*)");
  // A name pasted from a page: refused, and the refusal shows its start, not the page.
  CHECK(add_layer(loaded, std::string(10 << 20, 'm'), kAtEnd).refused ==
        "'" + std::string(32, 'm') +
            "…' (10485760 characters) is not a valid name: names are at most 128 characters");
  CHECK(add_layer(loaded, std::string(128, 'm'), kAtEnd).ok());

  // Removed with everything it declares and the comment above it; refused while another layer
  // reads its actuators.
  CHECK(yaml.edited(remove_layer(loaded, "low"), "ops.yaml") ==
        replaced(text,
                 "  # the lower layer\n  - name: low\n    sensors: [speed]\n    actuators: {out: "
                 "{type: double}}\n    "
                 "behaviours: {d: scripted, e: test.Probe}\n",
                 ""));
  CHECK(yaml.edited(remove_layer(loaded, "inc"), "part.yaml") ==
        replaced(kOpsPart, "  - name: inc\n    behaviours:\n      p: scripted\n      q: scripted\n",
                 ""));
  CHECK(remove_layer(loaded, "top").refused ==
        "layer 'top' is still used: layer 'low' reads its actuator 'speed'. Remove those sensors "
        "first");
  CHECK(remove_layer(loaded, "none").refused == "no layer 'none'");

  // An empty list becomes a block list in YAML; a missing one is added.
  Workspace empty(Files{{"empty.yaml", "arbiter: 1\nname: empty\nlayers: []  # none yet\n"}});
  CHECK(empty.edited(add_layer(empty.loaded(), "top"), "empty.yaml") ==
        "arbiter: 1\nname: empty\nlayers:\n  - name: top  # none yet\n");
  Workspace none(Files{{"none.yaml", "arbiter: 1\nname: none\n"}});
  CHECK(none.edited(add_layer(none.loaded(), "top", 0, "inputs"), "none.yaml") ==
        "arbiter: 1\nname: none\nlayers:\n  - name: top\n    interface: inputs\n");
  Workspace only(Files{{"only.yaml", "arbiter: 1\nname: only\nlayers:\n  - name: top\n"}});
  CHECK(only.edited(remove_layer(only.loaded(), "top"), "only.yaml") ==
        "arbiter: 1\nname: only\nlayers: []\n");

  Workspace json({{"ops.json", kOpsJson}});
  const std::string& json_text = json.text("ops.json");
  CHECK(json.edited(add_layer(json.loaded(), "mid", 1), "ops.json") ==
        replaced(json_text, "    },\n    {\"name\": \"low\"",
                 "    },\n    {\"name\": \"mid\"},\n    {\"name\": \"low\""));
  CHECK(json.edited(remove_layer(json.loaded(), "low"), "ops.json") ==
        replaced(json_text,
                 ",\n    {\"name\": \"low\", \"sensors\": [\"speed\"], \"actuators\": {\"spare\": "
                 "{\"type\": \"int\"}}, \"behaviours\": {\"d\": \"scripted\"}}",
                 ""));
  Workspace json_empty(
      Files{{"empty.json", "{\"arbiter\": 1, \"name\": \"empty\", \"layers\": []}\n"}});
  CHECK(json_empty.edited(add_layer(json_empty.loaded(), "top", kAtEnd, "inputs"), "empty.json") ==
        "{\"arbiter\": 1, \"name\": \"empty\", \"layers\": [{\"name\": \"top\", \"interface\": "
        "\"inputs\"}]}\n");
}

TEST_CASE("a state machine is declared empty, and removed unless something names it", "[edit]") {
  Workspace yaml({{"ops.yaml", kOpsYaml}, {"part.yaml", kOpsPart}});
  const Loaded& loaded = yaml.loaded();
  const std::string& text = yaml.text("ops.yaml");
  CHECK(yaml.edited(add_state_machine(loaded, "extra"), "ops.yaml") ==
        text + "  extra:\n    states: {}\n    queue: []\n");
  CHECK(add_state_machine(loaded, "plan").refused ==
        "'plan' is already taken: a state machine of that name is declared");
  CHECK(add_state_machine(loaded, "Plan").refused ==
        "'Plan' is not a valid name: names are lower-case identifiers ([a-z_][a-z0-9_]*)");

  Registry registry = make_test_registry();
  const ConfigIndex index = index_config(loaded, &registry);
  CHECK(yaml.edited(remove_state_machine(loaded, index, "flat"), "ops.yaml") ==
        replaced(text, "  flat:\n    states: {x: scripted, y: scripted}\n    queue: [x, y]\n", ""));
  CHECK(remove_state_machine(loaded, index, "none").refused == "no state machine 'none'");

  // Refused while a behaviour owns it.
  Workspace owned(Files{{"owned.yaml",
                         "arbiter: 1\nname: owned\nlayers:\n  - name: top\n    behaviours:\n"
                         "      run: {type: state_machine, params: {machine: plan}}\n"
                         "state_machines:\n  plan: {states: {}, queue: []}\n"}});
  const ConfigIndex owned_index = index_config(owned.loaded(), &registry);
  CHECK(remove_state_machine(owned.loaded(), owned_index, "plan").refused ==
        fmt::format("state machine 'plan' is still named at {}:6:52: remove those first",
                    owned.loaded().files.files().front()->path));

  // The key is added when missing, and goes with the last machine.
  Workspace none(Files{{"none.yaml", "arbiter: 1\nname: none\n"}});
  const std::string added = none.edited(add_state_machine(none.loaded(), "plan"), "none.yaml");
  CHECK(added ==
        "arbiter: 1\nname: none\nstate_machines:\n  plan:\n    states: {}\n    queue: []\n");
  Workspace one(Files{{"one.yaml", added}});
  const ConfigIndex one_index = index_config(one.loaded(), &registry);
  CHECK(one.edited(remove_state_machine(one.loaded(), one_index, "plan"), "one.yaml") ==
        "arbiter: 1\nname: none\n");

  Workspace json({{"ops.json", kOpsJson}});
  CHECK(json.edited(add_state_machine(json.loaded(), "extra"), "ops.json") ==
        replaced(json.text("ops.json"), R"("queue": ["one", "two"]})",
                 R"("queue": ["one", "two"]}, "extra": {"states": {}, "queue": []})"));
  Workspace json_none(Files{{"none.json", "{\"arbiter\": 1, \"name\": \"none\"}\n"}});
  CHECK(json_none.edited(add_state_machine(json_none.loaded(), "plan"), "none.json") ==
        "{\"arbiter\": 1, \"name\": \"none\", \"state_machines\": {\"plan\": {\"states\": {}, "
        "\"queue\": []}}}\n");
}

TEST_CASE("a plugin is named in plugins:, which is added when missing", "[edit]") {
  Workspace none(Files{{"none.yaml", "arbiter: 1\nname: none\nlayers: []\n"}});
  CHECK_THAT(none.refused(add_plugin(none.loaded(), "no_such_plugin")),
             Catch::Contains("no_such_plugin"));
  CHECK(add_plugin(none.loaded(), "So ccer").refused ==
        "'So ccer' is not a plugin's name: names are lower-case identifiers ([a-z_][a-z0-9_]*)");
  Workspace listed(Files{{"listed.yaml", "arbiter: 1\nname: listed\nplugins: [soccer]\n"}});
  CHECK(add_plugin(listed.loaded(), "soccer").refused == "plugin 'soccer' is named already");
  if (!plugins_built(kSourceDir / "configs/soccer/walk_and_kick.yaml")) return;
  CHECK(none.edited(add_plugin(none.loaded(), "soccer"), "none.yaml") ==
        "arbiter: 1\nname: none\nlayers: []\nplugins: [soccer]\n");
  Workspace empty(Files{{"empty.yaml", "arbiter: 1\nname: empty\nplugins: []\n"}});
  CHECK(empty.edited(add_plugin(empty.loaded(), "soccer"), "empty.yaml") ==
        "arbiter: 1\nname: empty\nplugins: [soccer]\n");
  Workspace json(Files{{"none.json", "{\"arbiter\": 1, \"name\": \"none\"}\n"}});
  CHECK(json.edited(add_plugin(json.loaded(), "soccer"), "none.json") ==
        "{\"arbiter\": 1, \"name\": \"none\", \"plugins\": [\"soccer\"]}\n");
}

TEST_CASE("a layer's sensors: list gets a sensor and loses one", "[edit]") {
  Workspace yaml({{"ops.yaml", kOpsYaml}, {"part.yaml", kOpsPart}});
  const Loaded& loaded = yaml.loaded();
  const std::string& text = yaml.text("ops.yaml");
  CHECK(yaml.edited(add_sensor(loaded, "top", "out"), "ops.yaml") ==
        replaced(text, "      - a => b\n", "      - a => b\n    sensors: [out]\n"));
  CHECK(add_sensor(loaded, "low", "speed").refused == "layer 'low' reads 'speed' already");
  CHECK_THAT(yaml.refused(add_sensor(loaded, "low", "nothing")), Catch::Contains("nothing"));
  CHECK(yaml.edited(remove_sensor(loaded, "low", "speed"), "ops.yaml") ==
        replaced(text, "    sensors: [speed]\n", "    sensors: []\n"));
  CHECK(remove_sensor(loaded, "low", "out").refused == "layer 'low' does not read 'out'");

  Workspace block(Files{{"block.yaml",
                         "arbiter: 1\nname: block\nlayers:\n  - name: a\n    actuators: {x: "
                         "bool, y: bool}\n  - name: b\n    sensors:\n      - x\n"}});
  CHECK(block.edited(add_sensor(block.loaded(), "b", "y"), "block.yaml") ==
        "arbiter: 1\nname: block\nlayers:\n  - name: a\n    actuators: {x: bool, y: bool}\n  - "
        "name: b\n    sensors:\n      - x\n      - y\n");
  CHECK(block.edited(remove_sensor(block.loaded(), "b", "x"), "block.yaml") ==
        "arbiter: 1\nname: block\nlayers:\n  - name: a\n    actuators: {x: bool, y: bool}\n  - "
        "name: b\n    sensors: []\n");
}

TEST_CASE(
    "an operation named by a JSON request is applied, and a request that is not one is "
    "refused naming what it lacks",
    "[edit]") {
  Workspace yaml({{"ops.yaml", kOpsYaml}, {"part.yaml", kOpsPart}});
  const Loaded& loaded = yaml.loaded();
  const std::string& text = yaml.text("ops.yaml");
  Registry registry = make_test_registry();
  const auto apply = [&](const std::string& request) {
    return apply_operation(loaded, request, &registry);
  };

  const OperationResult added = apply(R"({"op": "add_layer", "name": "mid", "index": 3})");
  CHECK(added.invalid.empty());
  CHECK(yaml.edited(added.result, "ops.yaml") ==
        replaced(text, "  # the lower layer\n", "  - name: mid\n  # the lower layer\n"));
  // A value is written as the request gives it, an object's keys in its order.
  const OperationResult set = apply(
      R"({"op": "set_param", "layer": "top", "behaviour": "c", "param": "p", "value": {"z": 1, "a": [true]}})");
  REQUIRE(set.result.edits.size() == 1);
  CHECK_THAT(set.result.edits[0].text, Catch::Contains(R"(p: {"z":1,"a":[true]})"));
  // The operation's own refusal is its result's, not the request's.
  const OperationResult used = apply(R"({"op": "remove_layer", "name": "top"})");
  CHECK(used.invalid.empty());
  CHECK(used.result.refused ==
        "layer 'top' is still used: layer 'low' reads its actuator 'speed'. Remove those sensors "
        "first");
  CHECK(apply(R"({"op": "rename", "kind": "behaviour", "name": "nobody", "to": "x"})")
            .result.refused == "no behaviour 'nobody' is declared");

  const std::map<std::string, std::string> invalid = {
      {"[1]", "the body is not a JSON object"},
      {"not json", "the body is not a JSON object"},
      {R"({"name": "x"})", "an operation needs 'op'"},
      {R"({"op": 5})", "'op' is 5, not the name of an operation"},
      {R"({"op": "add_inhibition", "layer": "top"})", "add_inhibition needs 'inhibitor'"},
      {R"({"op": "set_param", "layer": "top", "behaviour": "a", "param": "p"})",
       "set_param needs 'value'"},
      {R"({"op": "add_behaviour", "layer": "top", "name": "", "type": "scripted"})",
       "add_behaviour needs 'name'"},
      {R"({"op": "move_layer", "layer": "top", "index": -1})",
       "move_layer needs 'index' (names as strings, positions as integers from 0)"},
      {R"({"op": "remove_layer", "name": 3})",
       "remove_layer needs 'name' (names as strings, positions as integers from 0)"},
      {R"({"op": "add_layer", "name": "x", "index": "0"})",
       "add_layer needs 'index' (names as strings, positions as integers from 0)"},
      {R"({"op": "add_layer", "name": "x", "interface": 3})",
       "add_layer's 'interface' is not a string"},
      {R"({"op": "add_inhibition", "layer": "top", "inhibitor": "c", "inhibited": "b", "chaining": "yes"})",
       "add_inhibition's 'chaining' is not true or false"},
      {R"({"op": "add_queue_entry", "machine": "plan", "state": "one", "params": [1]})",
       "add_queue_entry's 'params' is not an object of param values"},
      {R"({"op": "rename", "kind": "file", "name": "a", "to": "x"})",
       "cannot rename a 'file': a behaviour, actuator, layer, state or machine can be renamed"},
  };
  for (const auto& [request, message] : invalid) {
    INFO(request);
    const OperationResult result = apply(request);
    CHECK(result.invalid == message);
    CHECK(result.result.edits.empty());
  }
  // A value nested 50 000 deep: printed for its edit, it would overflow the stack.
  const std::string deep =
      R"({"op": "set_param", "layer": "top", "behaviour": "a", "param": "p", "value": )" +
      std::string(50000, '[') + std::string(50000, ']') + "}";
  const OperationResult nested = apply(deep);
  CHECK(nested.invalid == "the body is nested deeper than 200 levels (at byte 276)");
  CHECK(nested.result.edits.empty());
  const OperationResult unknown = apply(R"({"op": "explode"})");
  CHECK_THAT(unknown.invalid,
             Catch::StartsWith("no operation 'explode': add_inhibition, remove_inhibition,") &&
                 Catch::EndsWith("remove_queue_entry or move_queue_entry"));
}
