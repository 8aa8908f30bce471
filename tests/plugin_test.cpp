// Loading plugins: finding them (relative path, --plugin-path, ARBITER_PLUGIN_PATH, the engine's
// own directory), loading each library once, keeping it loaded while its classes' instances
// live, and one located diagnostic for each way a plugin can fail. The test plugins are built
// from tests/plugins/ into ARBITER_TEST_PLUGIN_DIR; their configs are in tests/data/plugins/.

#include <dlfcn.h>
#include <fmt/format.h>

#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "arbiter/load.hpp"
#include "arbiter/manager.hpp"
#include "arbiter/plugin.hpp"
#include "arbiter/program.hpp"
#include "builtins.hpp"

namespace arbiter {
namespace {

namespace fs = std::filesystem;

const std::string kSourceDir = ARBITER_SOURCE_DIR;
const std::string kTestPluginDir = ARBITER_TEST_PLUGIN_DIR;
const std::string kTestPluginConfigDir = ARBITER_TEST_PLUGIN_CONFIG_DIR;
const std::string kBuiltPluginDir = ARBITER_BUILT_PLUGIN_DIR;

std::string config(const std::string& name) {
  return kSourceDir + "/tests/data/plugins/" + name;
}

/// A test plugin's file as the loader names it in messages.
std::string library(const std::string& plugin) {
  return fs::canonical(kTestPluginDir + "/arbiter_" + plugin + ".so").string();
}

Registry builtin_registry() {
  Registry registry;
  register_builtin_behaviours(registry);
  return registry;
}

/// Options that look in the test plugins' directory, then the engine's own, but not in
/// ARBITER_PLUGIN_PATH (which the environment running the tests might set).
LoadOptions test_options() {
  LoadOptions options;
  options.plugins.path = {kTestPluginDir};
  options.plugins.use_environment = false;
  return options;
}

/// Sets (or, with nullopt, unsets) an environment variable for one scope.
class ScopedEnvironment {
 public:
  ScopedEnvironment(const char* name, const std::optional<std::string>& value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    if (value) {
      setenv(name, value->c_str(), 1);
    } else {
      unsetenv(name);
    }
  }
  ~ScopedEnvironment() {
    if (old_) {
      setenv(name_, old_->c_str(), 1);
    } else {
      unsetenv(name_);
    }
  }
  ScopedEnvironment(const ScopedEnvironment&) = delete;
  ScopedEnvironment& operator=(const ScopedEnvironment&) = delete;

 private:
  const char* name_;
  std::optional<std::string> old_;
};

/// Whether the dynamic loader has `path` loaded (without loading it).
bool is_loaded(const std::string& path) {
  void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_NOLOAD);
  if (handle == nullptr) return false;
  dlclose(handle);
  return true;
}

/// Loads a config expected to fail and returns its diagnostics.
Diagnostics failures(const std::string& file, const LoadOptions& options = test_options()) {
  Registry registry = builtin_registry();
  Diagnostics diagnostics;
  const auto program = load(config(file), registry, diagnostics, options);
  CHECK_FALSE(program.has_value());
  return diagnostics;
}

}  // namespace

TEST_CASE("a plugin named by a path relative to its config is loaded and its class runs",
          "[plugin]") {
  Registry registry = builtin_registry();
  Diagnostics diagnostics;
  auto program =
      load(kTestPluginConfigDir + "/by_relative_path.yaml", registry, diagnostics, test_options());
  INFO(format(diagnostics));
  REQUIRE(program.has_value());
  CHECK(diagnostics.empty());
  CHECK(registry.find_class(ClassKind::kBehaviour, "test_good.Constant")->origin ==
        fmt::format("plugin lib/arbiter_test_good.so ({})", library("test_good")));

  Manager manager(std::move(*program));
  manager.step();
  const auto out = *manager.program().find_actuator("out");
  CHECK(manager.actuator<double>(out) == -1.0);
  CHECK(manager.activation(*manager.program().find_behaviour("control", "constant")) == 0.5);
}

TEST_CASE("a plugin named by name is found in a --plugin-path directory", "[plugin]") {
  Registry registry = builtin_registry();
  Diagnostics diagnostics;
  auto program = load(config("good.yaml"), registry, diagnostics, test_options());
  INFO(format(diagnostics));
  REQUIRE(program.has_value());
  CHECK(registry.find_class(ClassKind::kBehaviour, "test_good.Constant")->origin ==
        fmt::format("plugin test_good ({})", library("test_good")));

  Manager manager(std::move(*program));
  manager.step();
  CHECK(manager.actuator<double>(*manager.program().find_actuator("out")) == 3.5);
}

TEST_CASE("a plugin named by name is found through ARBITER_PLUGIN_PATH", "[plugin]") {
  const ScopedEnvironment environment("ARBITER_PLUGIN_PATH",
                                      "/nonexistent/arbiter/plugins:" + kTestPluginDir);
  LoadOptions options;  // no --plugin-path
  Registry registry = builtin_registry();
  Diagnostics diagnostics;
  const auto program = load(config("good.yaml"), registry, diagnostics, options);
  INFO(format(diagnostics));
  CHECK(program.has_value());
  CHECK(diagnostics.empty());
}

TEST_CASE("the plugin path is --plugin-path, then ARBITER_PLUGIN_PATH, then the engine's own",
          "[plugin]") {
  const ScopedEnvironment environment("ARBITER_PLUGIN_PATH", "/env/one::/env/two:");
  PluginOptions options;
  options.path = {"/flag/one", "/flag/two"};
  CHECK(plugin_search_path(options) ==
        std::vector<std::string>{"/flag/one", "/flag/two", "/env/one", "/env/two",
                                 fs::canonical(kBuiltPluginDir).string()});
  options.use_environment = false;
  options.use_default_path = false;
  CHECK(plugin_search_path(options) == std::vector<std::string>{"/flag/one", "/flag/two"});
}

TEST_CASE("the engine finds the plugins built with it with no options", "[plugin]") {
  const ScopedEnvironment environment("ARBITER_PLUGIN_PATH", std::nullopt);
  Registry registry = builtin_registry();
  Diagnostics diagnostics;
  const auto program =
      load(kSourceDir + "/configs/soccer/walk_and_kick.yaml", registry, diagnostics);
  INFO(format(diagnostics));
  CHECK(program.has_value());
  CHECK(registry.find_class(ClassKind::kInterface, "soccer.WorldLink") != nullptr);
}

TEST_CASE("a plugin named by two configs is loaded into one registry once", "[plugin]") {
  Registry registry = builtin_registry();
  Diagnostics by_name;
  Diagnostics by_path;
  const auto first = load(config("good.yaml"), registry, by_name, test_options());
  const auto second =
      load(kTestPluginConfigDir + "/by_relative_path.yaml", registry, by_path, test_options());
  INFO(format(by_name) << format(by_path));
  CHECK(first.has_value());
  CHECK(second.has_value());
  CHECK(by_name.empty());
  CHECK(by_path.empty());  // no clash of test_good.Constant with itself
  CHECK(registry.libraries().size() == 1);
  CHECK(registry.find_class(ClassKind::kBehaviour, "test_good.Constant")->origin ==
        fmt::format("plugin test_good ({})", library("test_good")));
}

TEST_CASE("an instance made by a plugin class works after its registry is destroyed", "[plugin]") {
  const std::string plugin = library("test_unloadable");
  std::optional<Program> program;
  {
    Registry registry = builtin_registry();
    Diagnostics diagnostics;
    program = load(config("unloadable.yaml"), registry, diagnostics, test_options());
    INFO(format(diagnostics));
    REQUIRE(program.has_value());
  }
  REQUIRE(is_loaded(plugin));  // the program keeps it loaded
  Behaviour& still = *program->behaviours.at(0).instance;
  detail::StepData data;
  data.step = 1;
  CHECK(still.activation(StepContext(data, 0)) == 0.75);  // a virtual call into the plugin

  program.reset();  // runs the instance's destructor, from the plugin, then unloads it
  CHECK_FALSE(is_loaded(plugin));
}

TEST_CASE("a plugin stays loaded while its registry lives and is unloaded with it", "[plugin]") {
  const std::string plugin = library("test_unloadable");
  {
    Registry registry = builtin_registry();
    Diagnostics diagnostics;
    CHECK(load(config("unloadable.yaml"), registry, diagnostics, test_options()).has_value());
    CHECK(is_loaded(plugin));  // the program is gone; the registry still holds the classes
  }  // destroying a class's factory runs library code: the library must go after the classes
  CHECK_FALSE(is_loaded(plugin));
}

TEST_CASE("a plugin's classes keep its library loaded when merged into another registry",
          "[plugin]") {
  const std::string plugin = library("test_unloadable");
  std::optional<Registry> merged(std::in_place);
  {
    Registry registry = builtin_registry();
    Diagnostics diagnostics;
    CHECK(load(config("unloadable.yaml"), registry, diagnostics, test_options()).has_value());
    merged->merge(std::move(registry), {}, diagnostics);
    CHECK(diagnostics.empty());
  }
  REQUIRE(is_loaded(plugin));
  const ClassInfo* still = merged->find_class(ClassKind::kBehaviour, "test_unloadable.Still");
  REQUIRE(still != nullptr);
  detail::StepData data;
  CHECK(still->make_behaviour()->activation(StepContext(data, 0)) == 0.75);
  merged.reset();
  CHECK_FALSE(is_loaded(plugin));
}

TEST_CASE("a plugin that is on no directory of the plugin path is reported with the path",
          "[plugin][diagnostic]") {
  const Diagnostics diagnostics = failures("not_found.yaml");
  const std::string at = config("not_found.yaml") + ":5:5: ";
  REQUIRE(diagnostics.items().size() == 1);
  CHECK(diagnostics.items()[0].code == "plugin-not-found");
  CHECK(format(diagnostics) ==
        at + "error: plugin 'test_missing' not found: no arbiter_test_missing.so on the plugin " +
            "path\n" + at + "note: looked in " + kTestPluginDir + "\n" + at + "note: looked in " +
            fs::canonical(kBuiltPluginDir).string() + "\n" + at +
            "note: add directories with --plugin-path DIR or ARBITER_PLUGIN_PATH, or name the " +
            "file relative to the config ('./libs/arbiter_x.so')\n");
}

TEST_CASE("the classes of a listed plugin that is not found are no errors of their own",
          "[plugin][diagnostic]") {
  const Diagnostics diagnostics = failures("not_found_used.yaml");
  std::vector<std::string> codes;
  for (const auto& item : diagnostics.items()) codes.push_back(item.code);
  INFO(format(diagnostics));
  // The missing plugin, and the unrelated typo; not test_missing.Dive nor test_missing.Wait.
  CHECK(codes == std::vector<std::string>{"plugin-not-found", "unknown-class"});
  CHECK(diagnostics.items()[1].message == "unknown behaviour class 'scriptd'");
}

TEST_CASE("a plugin file named relative to its config that does not exist is reported",
          "[plugin][diagnostic]") {
  const Diagnostics diagnostics = failures("not_found_by_path.yaml");
  REQUIRE(diagnostics.items().size() == 1);
  CHECK(diagnostics.items()[0].code == "plugin-not-found");
  CHECK(format(diagnostics) ==
        fmt::format("{}:5:5: error: plugin file 'missing/arbiter_test_missing.so' not found "
                    "(looked for {})\n",
                    config("not_found_by_path.yaml"), config("missing/arbiter_test_missing.so")));
}

TEST_CASE("a plugin file that is not a shared library is reported with the loader's reason",
          "[plugin][diagnostic]") {
  const Diagnostics diagnostics = failures("not_a_library.yaml");
  const std::string file = fs::canonical(config("not_a_library/arbiter_garbage.so")).string();
  REQUIRE(diagnostics.items().size() == 1);
  CHECK(diagnostics.items()[0].code == "plugin-load-failed");
  CHECK_THAT(format(diagnostics),
             Catch::StartsWith(fmt::format(
                 "{}:5:5: error: cannot load plugin 'not_a_library/arbiter_garbage.so' ({}): {}: ",
                 config("not_a_library.yaml"), file, file)));
}

TEST_CASE("a library without the version entry point is not a plugin", "[plugin][diagnostic]") {
  const Diagnostics diagnostics = failures("not_a_plugin.yaml");
  const std::string at = config("not_a_plugin.yaml") + ":5:5: ";
  REQUIRE(diagnostics.items().size() == 1);
  CHECK(diagnostics.items()[0].code == "not-a-plugin");
  CHECK(format(diagnostics) ==
        fmt::format("{}error: 'test_not_a_plugin' ({}) is not an Arbiter plugin: it lacks the "
                    "entry point arbiter_plugin_api_version\n"
                    "{}note: a plugin defines its entry points with ARBITER_PLUGIN(registry) "
                    "{{ ... }}\n",
                    at, library("test_not_a_plugin"), at));
}

TEST_CASE("a library without the registration entry point is not a plugin",
          "[plugin][diagnostic]") {
  const Diagnostics diagnostics = failures("no_register.yaml");
  const std::string at = config("no_register.yaml") + ":5:5: ";
  REQUIRE(diagnostics.items().size() == 1);
  CHECK(diagnostics.items()[0].code == "not-a-plugin");
  CHECK(format(diagnostics) ==
        fmt::format("{}error: 'test_no_register' ({}) is not an Arbiter plugin: it lacks the "
                    "entry point arbiter_plugin_register\n"
                    "{}note: a plugin defines its entry points with ARBITER_PLUGIN(registry) "
                    "{{ ... }}\n",
                    at, library("test_no_register"), at));
}

TEST_CASE("a plugin built for another API version is reported with both versions",
          "[plugin][diagnostic]") {
  // The plugin's registration function aborts: the version must be checked before it is called.
  const Diagnostics diagnostics = failures("wrong_version.yaml");
  const std::string at = config("wrong_version.yaml") + ":5:5: ";
  REQUIRE(diagnostics.items().size() == 1);
  CHECK(diagnostics.items()[0].code == "plugin-api-mismatch");
  CHECK(format(diagnostics) ==
        fmt::format("{}error: plugin 'test_wrong_version' ({}) was built for plugin API version "
                    "{}; this Arbiter has version {}\n"
                    "{}note: rebuild the plugin against this Arbiter's headers\n",
                    at, library("test_wrong_version"), ARBITER_PLUGIN_API_VERSION + 1,
                    ARBITER_PLUGIN_API_VERSION, at));
}

TEST_CASE("the API version is checked before the registration entry point is looked up",
          "[plugin][diagnostic]") {
  const Diagnostics diagnostics = failures("future.yaml");
  REQUIRE(diagnostics.items().size() == 1);
  CHECK(diagnostics.items()[0].code == "plugin-api-mismatch");
  CHECK(diagnostics.items()[0].message ==
        fmt::format("plugin 'test_future' ({}) was built for plugin API version {}; this Arbiter "
                    "has version {}",
                    library("test_future"), ARBITER_PLUGIN_API_VERSION + 1,
                    ARBITER_PLUGIN_API_VERSION));
}

TEST_CASE("a plugin whose registration throws is reported with the exception's message",
          "[plugin][diagnostic]") {
  Registry registry = builtin_registry();
  Diagnostics diagnostics;
  CHECK_FALSE(load(config("throws.yaml"), registry, diagnostics, test_options()).has_value());
  REQUIRE(diagnostics.items().size() == 1);
  CHECK(diagnostics.items()[0].code == "plugin-register-failed");
  CHECK(format(diagnostics) ==
        fmt::format("{}:5:5: error: plugin 'test_throws' ({}) failed to register its classes: "
                    "calibration table kicker.csv is missing\n",
                    config("throws.yaml"), library("test_throws")));
  // What it registered before it threw is discarded.
  CHECK(registry.find_any_class("test_throws.Kicker") == nullptr);
}

namespace {
/// A member of each C++ type the param-kind test binds.
struct Kinds final : Behaviour {
  double activation(const StepContext&) override { return 0.0; }
  double gain = 0.0;
  std::int64_t rounds = 0;
  std::vector<std::string> names;
  Vec2 target;
  double speed = 0.0;
  std::int64_t steps = 0;
  std::int64_t count = 0;
  bool loud = false;
};
}  // namespace

TEST_CASE("a param declared by its C++ type gets that type's kind and a default of that type",
          "[plugin][registry]") {
  Registry registry;
  auto& info = registry.add_behaviour<Kinds>("test.Kinds");
  CHECK(info.param("gain", &Kinds::gain).kind == ParamKind::kDouble);
  CHECK(info.param("rounds", &Kinds::rounds).kind == ParamKind::kInt);
  CHECK(info.param("names", &Kinds::names).kind == ParamKind::kStringList);
  CHECK(info.param("target", &Kinds::target).kind == ParamKind::kVec2);
  // An integer literal is taken for a double, so that `.defaults_to(3)` means 3.0.
  const auto& gain = info.param("speed", &Kinds::speed).defaults_to(3);
  REQUIRE(gain.default_value);
  CHECK(std::get<double>(*gain.default_value) == 3.0);
  CHECK(std::get<std::int64_t>(*info.param("steps", &Kinds::steps).defaults_to(3).default_value) ==
        3);
  // A default of another type is the registration's mistake, told with the param's name.
  CHECK_THROWS_WITH(info.param("count", &Kinds::count).defaults_to("3"),
                    "param 'count' is of kind int, but its default is of kind string");
  CHECK_THROWS_WITH(info.param("loud", &Kinds::loud).defaults_to(1),
                    "param 'loud' is of kind bool, but its default is of kind int");
}

TEST_CASE("a plugin class named like a built-in one is reported with both origins",
          "[plugin][diagnostic]") {
  Registry registry = builtin_registry();
  Diagnostics diagnostics;
  CHECK_FALSE(load(config("clash_builtin.yaml"), registry, diagnostics, test_options()));
  REQUIRE(diagnostics.items().size() == 1);
  CHECK(diagnostics.items()[0].code == "class-clash");
  CHECK(format(diagnostics) ==
        fmt::format("{}:5:5: error: behaviour class 'scripted' from plugin test_clash_builtin "
                    "({}) clashes with the one from built-in\n",
                    config("clash_builtin.yaml"), library("test_clash_builtin")));
  CHECK(registry.find_class(ClassKind::kBehaviour, "scripted")->origin == "built-in");
}

TEST_CASE("two plugins that register the same class are reported with both origins",
          "[plugin][diagnostic]") {
  Registry registry = builtin_registry();
  Diagnostics diagnostics;
  CHECK_FALSE(load(config("clash_each_other.yaml"), registry, diagnostics, test_options()));
  REQUIRE(diagnostics.items().size() == 1);
  CHECK(diagnostics.items()[0].code == "class-clash");
  CHECK(format(diagnostics) ==
        fmt::format("{}:6:5: error: behaviour class 'clash.Same' from plugin test_clash_b ({}) "
                    "clashes with the one from plugin test_clash_a ({})\n",
                    config("clash_each_other.yaml"), library("test_clash_b"),
                    library("test_clash_a")));
}

}  // namespace arbiter
