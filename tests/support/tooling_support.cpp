#include "tooling_support.hpp"

#include <catch2/catch.hpp>
#include <sstream>

#include "arbiter/load.hpp"
#include "arbiter/manager.hpp"
#include "arbiter/plugin.hpp"
#include "arbiter/trace.hpp"
#include "builtins.hpp"

namespace fs = std::filesystem;

namespace arbiter::test {

const fs::path kSourceDir = ARBITER_SOURCE_DIR;
const fs::path kDataDir = kSourceDir / "tests" / "data";
const fs::path kGoldenDir = kDataDir / "golden";

const char* const kWalkAndKick = "configs/paper/walk_and_kick.yaml";

void check_golden(const std::string& name, const std::string& actual) {
  const fs::path path = kGoldenDir / name;
  if (update_golden()) {
    write_text(path, actual);
    WARN("rewrote tests/data/golden/" << name);
    return;
  }
  INFO("golden file tests/data/golden/" << name);
  REQUIRE(fs::exists(path));
  CHECK(actual == read_text(path));
}

Registry tooling_registry() {
  Registry registry = make_test_registry();
  registry.set_origin("tooling_test");
  add_param_check_classes(registry);
  return registry;
}

Registry builtin_registry() {
  Registry registry;
  register_builtin_behaviours(registry);
  return registry;
}

bool is_config(const fs::path& path) {
  const auto extension = path.extension();
  return extension == ".yaml" || extension == ".yml" || extension == ".json";
}

std::vector<fs::path> configs_under(const fs::path& dir) {
  return files_in(dir, is_config, Walk::kRecursive);
}

bool plugins_built(const fs::path& config) {
  Registry registry;
  Diagnostics diagnostics;
  if (const auto document = read_document(config.string(), diagnostics)) {
    load_plugins(*document, PluginOptions{}, registry, diagnostics);
  }
  for (const auto& item : diagnostics.items()) {
    if (item.code == "plugin-not-found") {
      WARN(config.filename().string() << ": not checked with its classes: " << item.message);
      CHECK(item.message.find("plugin 'dds' not found") != std::string::npos);
      return false;
    }
  }
  return true;
}

CliResult run_cli(const std::string& arguments) {
  return run_captured("cd \"" + kSourceDir.string() + "\" && \"" + std::string(ARBITER_CLI) +
                      "\" " + arguments);
}

std::string quoted(const fs::path& path) {
  return "\"" + path.string() + "\"";
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

Program load_config(const std::string& relative, Registry& registry, Diagnostics& diagnostics) {
  WorkingDirectory here(kSourceDir);
  auto program = load(relative, registry, diagnostics, with_lints());
  INFO(format(diagnostics));
  REQUIRE(program.has_value());
  return std::move(*program);
}

std::string trace_of(const std::string& relative, int steps) {
  Registry registry = tooling_registry();
  Diagnostics diagnostics;
  Manager manager(load_config(relative, registry, diagnostics));
  return run_traced(manager, steps);
}

}  // namespace arbiter::test
