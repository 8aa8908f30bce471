// The load pipeline (engine/core/compile/load.cpp). Error messages are API: every config in
// tests/data/invalid is loaded and its diagnostics are compared, as text, with the approved
// `<case>.expected` beside it. Run with ARBITER_UPDATE_GOLDEN=1 to rewrite the expected files from
// the current output (then review the diff by eye; never in CI).

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "arbiter/load.hpp"
#include "arbiter/program.hpp"
#include "arbiter/state.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using namespace arbiter;

namespace {

const fs::path kDataDir = fs::path(ARBITER_SOURCE_DIR) / "tests" / "data";

using test::read_text;
using test::update_golden;
using test::write_text;

bool is_config(const fs::path& path) {
  const auto extension = path.extension();
  return extension == ".yaml" || extension == ".yml" || extension == ".json";
}

/// The top-level configs of `dir`, sorted by name. Subfolders hold included files only.
std::vector<fs::path> configs_in(const fs::path& dir) {
  return test::files_in(dir, is_config);
}

/// The cases: top-level configs with an `.expected` sibling (in update mode, every config).
std::vector<fs::path> golden_cases(const fs::path& dir) {
  std::vector<fs::path> cases;
  for (const auto& config : configs_in(dir)) {
    if (update_golden() || fs::exists(fs::path(config).replace_extension(".expected"))) {
      cases.push_back(config);
    }
  }
  return cases;
}

/// The test registry plus the classes whose params exercise every param check.
Registry golden_registry() {
  Registry registry = test::make_test_registry();
  registry.set_origin("invalid_configs_test");
  test::add_param_check_classes(registry);
  return registry;
}

bool starts_with(const std::string& text, const std::string& prefix) {
  return text.compare(0, prefix.size(), prefix) == 0;
}

}  // namespace

TEST_CASE("every invalid config reports the approved diagnostics", "[diagnostics]") {
  const fs::path dir = kDataDir / "invalid";
  const auto cases = golden_cases(dir);
  REQUIRE(cases.size() >= 30);

  for (const auto& path : cases) {
    const std::string name = path.filename().string();
    DYNAMIC_SECTION(name) {
      Registry registry = golden_registry();  // fresh: loading may add a config's plugins
      Diagnostics diagnostics;
      std::optional<Program> program;
      std::string actual;
      {
        test::WorkingDirectory here(dir);
        program = load(name, registry, diagnostics, test::with_lints());
        // Source lines are read where the config was loaded from, as the CLI reads them.
        actual = format(diagnostics, FormatOptions::readable());
      }
      const fs::path expected_path = fs::path(path).replace_extension(".expected");
      if (update_golden()) {
        write_text(expected_path, actual);
        WARN("rewrote " << expected_path.filename().string());
      } else {
        CHECK(actual == read_text(expected_path));
      }
      if (starts_with(name, "warn_")) {
        CHECK(program.has_value());
        CHECK(diagnostics.error_count() == 0);
        CHECK(diagnostics.warning_count() > 0);
      } else {
        CHECK_FALSE(program.has_value());
        CHECK(diagnostics.error_count() > 0);
      }
    }
  }
}

TEST_CASE("every config in tests/data/invalid has an expected file", "[diagnostics]") {
  for (const auto& config : configs_in(kDataDir / "invalid")) {
    INFO(config.filename().string());
    CHECK(fs::exists(fs::path(config).replace_extension(".expected")));
  }
}

TEST_CASE("every config in tests/data/valid loads without any diagnostic", "[diagnostics]") {
  const auto configs = configs_in(kDataDir / "valid");
  REQUIRE(configs.size() >= 3);
  for (const auto& path : configs) {
    DYNAMIC_SECTION(path.filename().string()) {
      Registry registry = golden_registry();
      Diagnostics diagnostics;
      const auto program = load(path.string(), registry, diagnostics, test::with_lints());
      INFO(format(diagnostics));
      CHECK(diagnostics.empty());
      CHECK(program.has_value());
    }
  }
}

TEST_CASE("a JSON config and its YAML twin compile to the same graph", "[diagnostics]") {
  Registry registry = golden_registry();
  const auto yaml = load_program((kDataDir / "valid" / "twin.yaml").string(), registry);
  const auto json = load_program((kDataDir / "valid" / "twin.json").string(), registry);
  REQUIRE(yaml.behaviours.size() == json.behaviours.size());
  for (std::size_t b = 0; b < yaml.behaviours.size(); ++b) {
    CHECK(yaml.behaviours[b].name == json.behaviours[b].name);
  }
  REQUIRE(yaml.inhibitions.size() == json.inhibitions.size());
  for (std::size_t i = 0; i < yaml.inhibitions.size(); ++i) {
    CHECK(yaml.inhibitions[i].inhibitor == json.inhibitions[i].inhibitor);
    CHECK(yaml.inhibitions[i].inhibited == json.inhibitions[i].inhibited);
    CHECK(yaml.inhibitions[i].chaining == json.inhibitions[i].chaining);
    CHECK(yaml.inhibitions[i].implicit == json.inhibitions[i].implicit);
  }
  REQUIRE(yaml.actuators.size() == json.actuators.size());
  for (std::size_t a = 0; a < yaml.actuators.size(); ++a) {
    CHECK(yaml.actuators[a].name == json.actuators[a].name);
    CHECK(yaml.actuators[a].type == json.actuators[a].type);
    CHECK(yaml.actuators[a].aggregate == json.actuators[a].aggregate);
  }
}

TEST_CASE("the compact format is one line per diagnostic and per note, without codes",
          "[diagnostics]") {
  Diagnostics diagnostics;
  diagnostics.error({"no_such_file.yaml", 3, 1}, "unknown-key", "unknown key 'rate'").notes = {
      "did you mean 'rate_hz'?"};
  CHECK(format(diagnostics) ==
        "no_such_file.yaml:3:1: error: unknown key 'rate'\n"
        "no_such_file.yaml:3:1: note: did you mean 'rate_hz'?\n");
  // A file that cannot be read gets no source line, but keeps its code.
  CHECK(format(diagnostics, FormatOptions::readable()) ==
        "no_such_file.yaml:3:1: error[unknown-key]: unknown key 'rate'\n"
        "no_such_file.yaml:3:1: note: did you mean 'rate_hz'?\n");
}

TEST_CASE("load_config reads texts held in memory before the disk, for included files too",
          "[load]") {
  const test::TempDir scratch;
  const auto dir = scratch.path() / "arbiter_overlay_test";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string main = (dir / "main.yaml").string();
  const std::string part = (dir / "part.yaml").string();
  test::write_text(main,
                   "arbiter: 1\nname: m\ninclude: [part.yaml]\nlayers:\n  - name: control\n"
                   "    behaviours:\n      a: {type: scripted, params: {activation: 1}}\n");
  test::write_text(part, "arbiter: 1\nlayers:\n  - name: other\n");
  Registry registry = test::make_test_registry();

  Overlay overlay;
  overlay.set(part, "arbiter: 1\nlayers:\n  - name: other\n    sensors: [sped]\n");
  LoadOptions options;
  options.source = &overlay;
  Loaded loaded = load_config(main, registry, options);
  REQUIRE_FALSE(loaded.program);
  REQUIRE(loaded.diagnostics.items().size() == 1);
  CHECK(loaded.diagnostics.items()[0].location.file == part);
  CHECK(loaded.diagnostics.items()[0].location.line == 4);
  REQUIRE(loaded.files.files().size() == 2);
  CHECK(loaded.files.files()[1]->text == *overlay.find(part));
  REQUIRE(loaded.model);
  CHECK(loaded.model->files == std::vector<std::string>{main, part});

  overlay.erase(part);  // the disk again
  Loaded fixed = load_config(main, registry, options);
  CHECK(fixed.program);
  CHECK(fixed.diagnostics.empty());
  CHECK(fixed.document() != nullptr);
  std::filesystem::remove_all(dir);
}

TEST_CASE("a 'known:' list prints a last name rather than '(1 more)', and counts two or more",
          "[diagnostics]") {
  std::vector<std::string> known;
  for (char c = 'a'; c <= 'm'; ++c) known.emplace_back(3, c);
  CHECK(suggest("zzz", known) ==
        "known: aaa, bbb, ccc, ddd, eee, fff, ggg, hhh, iii, jjj, kkk, lll, mmm");
  known.emplace_back("nnn");
  CHECK(suggest("zzz", known) ==
        "known: aaa, bbb, ccc, ddd, eee, fff, ggg, hhh, iii, jjj, kkk, lll, ... (2 more)");
}
