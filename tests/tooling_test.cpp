// The tools around the engine: the JSON Schema (checked with valijson against every config), the
// dumps (golden files), the lints, `explain`, `plugins`, `validate --format json` and the help.
// Run with ARBITER_UPDATE_GOLDEN=1 to rewrite the golden files in tests/data/golden from the
// current output (then review the diff by eye; never in CI).

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>
#include <valijson/adapters/nlohmann_json_adapter.hpp>
#include <valijson/schema.hpp>
#include <valijson/schema_parser.hpp>
#include <valijson/validation_results.hpp>
#include <valijson/validator.hpp>

#include "arbiter/catalog.hpp"
#include "arbiter/dump.hpp"
#include "arbiter/explain.hpp"
#include "arbiter/lint.hpp"
#include "arbiter/load.hpp"
#include "arbiter/scenario.hpp"
#include "arbiter/schema.hpp"
#include "arbiter/state.hpp"
#include "arbiter/trace.hpp"
#include "builtins.hpp"
#include "run_report.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using namespace arbiter;
using Json = nlohmann::json;

namespace {

const fs::path kSourceDir = ARBITER_SOURCE_DIR;
const fs::path kDataDir = kSourceDir / "tests" / "data";
const fs::path kGoldenDir = kDataDir / "golden";

using test::read_text;
using test::update_golden;
using test::write_text;

/// Compares `actual` with the golden file `name` (or rewrites it in update mode).
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

/// The test registry plus the classes the invalid configs use (tests/data/invalid).
Registry tooling_registry() {
  Registry registry = test::make_test_registry();
  registry.set_origin("tooling_test");
  test::add_param_check_classes(registry);
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

/// Every config file under `dir`, recursively, sorted.
std::vector<fs::path> configs_under(const fs::path& dir) {
  return test::files_in(dir, is_config, test::Walk::kRecursive);
}

// --- the schema, through valijson ---

/// A document as JSON. JSON files are parsed as they are; YAML goes through the engine's own
/// reader, so that scalars get the YAML 1.2 core-schema types the engine gives them ("yes" is a
/// string, 1 an integer). valijson's yaml-cpp adapter cannot do this: it sees every scalar as a
/// string and converts on demand, so `name: 5` and `kick: "true"` would pass as what they are not.
Json document_json(const Node& node) {
  switch (node.kind()) {
    case Node::Kind::kNull:
      return nullptr;
    case Node::Kind::kScalar:
      if (node.quoted()) return node.text();
      if (node.reads_as_null()) return nullptr;
      if (const auto value = node.as_bool()) return *value;
      if (const auto value = node.as_int()) return *value;
      if (const auto value = node.as_double()) return *value;
      return node.text();
    case Node::Kind::kSequence: {
      Json out = Json::array();
      for (const auto& item : node.items()) out.push_back(document_json(item));
      return out;
    }
    case Node::Kind::kMapping: {
      Json out = Json::object();
      for (const auto& entry : node.entries()) out[entry.key] = document_json(entry.value);
      return out;
    }
  }
  return nullptr;
}

/// The config as JSON; nullopt when it cannot be read at all (a syntax error).
std::optional<Json> config_json(const fs::path& path) {
  if (path.extension() == ".json") {
    try {
      return Json::parse(read_text(path));
    } catch (const Json::exception&) {
      return std::nullopt;
    }
  }
  Diagnostics diagnostics;
  const auto document = read_document(path.string(), diagnostics);
  if (!document) return std::nullopt;
  return document_json(*document);
}

class SchemaValidator {
 public:
  explicit SchemaValidator(const Json& schema) : schema_json_(schema) {
    valijson::SchemaParser parser(valijson::SchemaParser::kDraft7);
    valijson::adapters::NlohmannJsonAdapter adapter(schema_json_);
    parser.populateSchema(adapter, schema_);
  }

  /// The errors, one per line ("<path>: <description>"); empty when `document` is valid.
  std::string errors(const Json& document) const {
    valijson::Validator validator;
    valijson::ValidationResults results;
    valijson::adapters::NlohmannJsonAdapter target(document);
    if (validator.validate(schema_, target, &results)) return {};
    std::string out;
    valijson::ValidationResults::Error error;
    while (results.popError(error)) {
      std::string where;
      for (const auto& part : error.context) where += part;
      out += where + ": " + error.description + "\n";
    }
    return out.empty() ? "invalid\n" : out;
  }

 private:
  Json schema_json_;
  valijson::Schema schema_;
};

const SchemaValidator& base_schema() {
  static const SchemaValidator validator(Json::parse(config_schema()));
  return validator;
}

/// A schema whose root is the definition `name` of the base schema (e.g. included_file).
std::unique_ptr<SchemaValidator> definition_schema(const std::string& name) {
  Json schema = Json::parse(config_schema());
  Json root = {{"$ref", "#/definitions/" + name}, {"definitions", schema["definitions"]}};
  return std::make_unique<SchemaValidator>(root);
}

/// Whether the plugins a config names are built here (a plugin with optional dependencies, such
/// as dds, may not be); tells the test log when one is not. Only dds may be missing.
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

/// The schema extended with the test classes and the plugins `config` names.
std::unique_ptr<SchemaValidator> extended_schema(const fs::path& config) {
  Registry registry = tooling_registry();
  Diagnostics diagnostics;
  if (const auto document = read_document(config.string(), diagnostics)) {
    load_plugins(*document, PluginOptions{}, registry, diagnostics);
  }
  INFO(format(diagnostics));
  CHECK_FALSE(diagnostics.has_errors());
  return std::make_unique<SchemaValidator>(Json::parse(config_schema(registry)));
}

// --- the CLI ---

/// Runs `arbiter ARGUMENTS` in the source directory (paths relative to it), capturing both streams.
test::CliResult run_cli(const std::string& arguments) {
  return test::run_captured("cd \"" + kSourceDir.string() + "\" && \"" + std::string(ARBITER_CLI) +
                            "\" " + arguments);
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

/// Loads a config as `arbiter` does (relative to the source directory), with the test classes.
Program load_config(const std::string& relative, Registry& registry, Diagnostics& diagnostics) {
  test::WorkingDirectory here(kSourceDir);
  auto program = load(relative, registry, diagnostics, test::with_lints());
  INFO(format(diagnostics));
  REQUIRE(program.has_value());
  return std::move(*program);
}

/// The trace of `steps` steps of a config, as `arbiter run --trace` writes it.
std::string trace_of(const std::string& relative, int steps) {
  Registry registry = tooling_registry();
  Diagnostics diagnostics;
  Manager manager(load_config(relative, registry, diagnostics));
  std::ostringstream out;
  TraceWriter trace(out);
  manager.add_observer(trace);
  for (int i = 0; i < steps; ++i) manager.step();
  manager.finish();
  return out.str();
}

const char* const kWalkAndKick = "configs/paper/walk_and_kick.yaml";

}  // namespace

// --- schema ---

TEST_CASE("schema/arbiter.schema.json is the schema the engine prints", "[schema]") {
  const Json file = Json::parse(read_text(kSourceDir / "schema" / "arbiter.schema.json"));
  CHECK(Json::parse(config_schema()) == file);
  std::vector<std::string> codes;
  for (const auto& lint : lint_codes()) codes.emplace_back(lint.code);
  CHECK(file["definitions"]["lint"]["properties"]["ignore"]["items"]["enum"] == Json(codes));
}

TEST_CASE("every config in configs/ and tests/data/valid fits both schemas", "[schema]") {
  std::vector<fs::path> configs = configs_under(kSourceDir / "configs");
  const auto valid = configs_under(kDataDir / "valid");
  configs.insert(configs.end(), valid.begin(), valid.end());
  REQUIRE(configs.size() >= 8);
  const auto included = definition_schema("included_file");
  for (const auto& path : configs) {
    const std::string name = fs::relative(path, kSourceDir).string();
    DYNAMIC_SECTION(name) {
      const auto document = config_json(path);
      REQUIRE(document.has_value());
      // Subfolders of tests/data/valid hold included files, which set no name or version.
      if (path.parent_path().filename() == "includes") {
        CHECK(included->errors(*document).empty());
        continue;
      }
      CHECK(base_schema().errors(*document).empty());
      if (plugins_built(path)) CHECK(extended_schema(path)->errors(*document).empty());
    }
  }
}

TEST_CASE("configs in configs/ point editors at the schema", "[schema]") {
  for (const auto& path : configs_under(kSourceDir / "configs")) {
    INFO(path.string());
    const std::string schema =
        fs::relative(kSourceDir / "schema" / "arbiter.schema.json", path.parent_path()).string();
    const std::string text = read_text(path);
    if (path.extension() == ".json") {
      CHECK(Json::parse(text).value("$schema", "") == schema);
    } else {
      CHECK(text.rfind("# yaml-language-server: $schema=" + schema + "\n", 0) == 0);
    }
  }
}

TEST_CASE("invalid configs whose errors are structural are rejected by the schema", "[schema]") {
  // Wrong shapes, unknown and missing keys, names that are not identifiers: the schema alone
  // catches these, without the classes.
  const std::vector<std::string> structural = {"unknown_key.yaml",
                                               "wrong_type.yaml",
                                               "missing_key.yaml",
                                               "bad_identifier.yaml",
                                               "bad_version.yaml",
                                               "bad_version_string.json",
                                               "missing_version.yaml",
                                               "document_list.yaml",
                                               "document_scalar.yaml",
                                               "bad_inhibition_syntax.yaml",
                                               "interface_with_behaviours.yaml",
                                               "duplicate_sensor.yaml"};
  // Params, ports, class names and value types: the schema extended with the classes does.
  const std::vector<std::string> per_class = {
      "not_aggregatable.yaml", "unknown_class.yaml",      "unknown_param.yaml",
      "wrong_param_type.yaml", "missing_param.yaml",      "param_out_of_range.yaml",
      "wrong_class_kind.yaml", "unknown_value_type.yaml", "interface_layer.yaml"};
  const fs::path dir = kDataDir / "invalid";
  for (const auto& name : structural) {
    DYNAMIC_SECTION("structural: " << name) {
      REQUIRE(fs::exists(dir / name));
      const auto document = config_json(dir / name);
      REQUIRE(document.has_value());
      CHECK_FALSE(base_schema().errors(*document).empty());
    }
  }
  for (const auto& name : per_class) {
    DYNAMIC_SECTION("per class: " << name) {
      REQUIRE(fs::exists(dir / name));
      const auto document = config_json(dir / name);
      REQUIRE(document.has_value());
      CHECK_FALSE(extended_schema(dir / name)->errors(*document).empty());
    }
  }
}

TEST_CASE("the extended schema names each class and checks its params", "[schema]") {
  const Json schema = Json::parse(config_schema(tooling_registry()));
  const Json& definitions = schema["definitions"];
  std::vector<std::string> behaviours;
  for (const auto& choice : definitions["behaviour_class"]["anyOf"]) {
    behaviours.push_back(choice["const"]);
  }
  CHECK(behaviours == std::vector<std::string>{"scripted", "state_machine", "test.NanLevel",
                                               "test.Probe", "test.Thrower", "test.Tuned"});
  // test.Tuned has a required param, so it has no short form (`name: test.Tuned`).
  const auto& short_form = definitions["behaviour_short_class"]["anyOf"];
  CHECK(std::none_of(short_form.begin(), short_form.end(),
                     [](const Json& choice) { return choice["const"] == "test.Tuned"; }));
  CHECK(definitions["value_type"]["enum"] ==
        Json({"bool", "int", "double", "vec2", "vec3", "string"}));

  const SchemaValidator validator(schema);
  const auto with_behaviour = [](Json behaviour) {
    return Json{
        {"arbiter", 1},
        {"name", "x"},
        {"layers", {{{"name", "control"}, {"behaviours", {{"kick_ball", std::move(behaviour)}}}}}}};
  };
  CHECK(validator.errors(with_behaviour({{"type", "test.Tuned"}, {"params", {{"gain", 0.5}}}}))
            .empty());
  CHECK_FALSE(validator.errors(with_behaviour({{"type", "test.Tuned"}, {"params", {{"gain", 2}}}}))
                  .empty());
  CHECK_FALSE(validator.errors(with_behaviour({{"type", "test.Tuned"}})).empty());
  CHECK_FALSE(validator
                  .errors(with_behaviour(
                      {{"type", "test.Tuned"}, {"params", {{"gain", 0.5}, {"mode", "medium"}}}}))
                  .empty());
  CHECK_FALSE(validator.errors(with_behaviour({{"type", "test.Probe"}, {"ports", {{"nope", "x"}}}}))
                  .empty());
  CHECK(validator.errors(with_behaviour("scripted")).empty());
  CHECK_FALSE(validator.errors(with_behaviour("test.Tuned")).empty());
}

namespace {

/// Where a subschema that editors label has no title: definitions, properties, list items and
/// the choices of anyOf/oneOf (a bare $ref takes its target's). Conditions (if, not,
/// propertyNames) are not labelled.
void untitled(const Json& schema, const std::string& path, bool labelled,
              std::vector<std::string>& out) {
  if (!schema.is_object()) return;
  const bool bare_ref = schema.contains("$ref") && !schema.contains("type") &&
                        !schema.contains("anyOf") && !schema.contains("properties");
  if (labelled && !bare_ref && !schema.contains("title")) out.push_back(path);
  for (const auto& [key, value] : schema.items()) {
    const std::string at = path + "/" + key;
    if (key == "definitions" || key == "properties" || key == "patternProperties") {
      for (const auto& [name, item] : value.items()) untitled(item, at + "/" + name, true, out);
    } else if (key == "additionalProperties" || key == "items") {
      untitled(value, at, true, out);
    } else if (key == "anyOf" || key == "oneOf") {
      for (std::size_t i = 0; i < value.size(); ++i) {
        untitled(value[i], at + "/" + std::to_string(i), true, out);
      }
    } else if (key == "allOf") {
      for (std::size_t i = 0; i < value.size(); ++i) {
        untitled(value[i], at + "/" + std::to_string(i), false, out);
      }
    } else if (key == "then" || key == "else") {
      untitled(value, at, false, out);
    }
  }
}

}  // namespace

TEST_CASE("every subschema of both schemas has a title, so editors name what they show",
          "[schema]") {
  Registry registry = tooling_registry();
  Diagnostics diagnostics;
  for (const char* plugin : {"soccer", "dds"}) {
    load_plugin(plugin, {"test", 0, 0}, "", PluginOptions{}, registry, diagnostics);
  }
  INFO(format(diagnostics));
  for (const auto& [name, text] : {std::pair<std::string, std::string>{"static", config_schema()},
                                   {"extended", config_schema(registry)}}) {
    DYNAMIC_SECTION(name) {
      std::vector<std::string> missing;
      untitled(Json::parse(text), "#", true, missing);
      INFO(Json(missing).dump(1));
      CHECK(missing.empty());
    }
  }
}

TEST_CASE("an actuator's default has its type's shape in the schema, as the engine checks it",
          "[schema]") {
  const auto config = [](Json actuator) {
    return Json{{"arbiter", 1},
                {"name", "x"},
                {"layers", {{{"name", "world"}, {"actuators", {{"a", std::move(actuator)}}}}}}};
  };
  for (const auto& ok :
       {Json{{"type", "vec3"}, {"default", {1, 2, 3}}},
        Json{{"type", "vec2"}, {"default", {1, 2.5}}}, Json{{"type", "bool"}, {"default", true}},
        Json{{"type", "int"}, {"default", -4}}, Json{{"type", "double"}, {"default", 0.5}},
        Json{{"type", "string"}, {"default", "idle"}}}) {
    INFO(ok.dump());
    CHECK(base_schema().errors(config(ok)).empty());
  }
  for (const auto& bad :
       {Json{{"type", "vec3"}, {"default", {1, 2}}}, Json{{"type", "vec3"}, {"default", 1}},
        Json{{"type", "vec2"}, {"default", {1, "y"}}}, Json{{"type", "bool"}, {"default", 1}},
        Json{{"type", "int"}, {"default", 1.5}}, Json{{"type", "double"}, {"default", "fast"}},
        Json{{"type", "string"}, {"default", {1}}}}) {
    INFO(bad.dump());
    CHECK_FALSE(base_schema().errors(config(bad)).empty());
    // The engine rejects it too.
    CHECK(test::diagnose_text(config(bad).dump(), tooling_registry(), "bad.json").has_errors());
  }
}

TEST_CASE("the extended schema checks the DDS bridge's topics as the bridge does", "[schema]") {
  const fs::path probe = fs::temp_directory_path() / "arbiter_dds_schema_probe.yaml";
  write_text(probe, "arbiter: 1\nname: probe\nplugins: [dds]\n");
  if (!plugins_built(probe)) return;
  const auto validator = extended_schema(probe);
  fs::remove(probe);
  const auto config = [](Json topics) {
    return Json{{"arbiter", 1},
                {"name", "x"},
                {"plugins", {"dds"}},
                {"layers",
                 {{{"name", "link"},
                   {"interface", "dds.Bridge"},
                   {"params", {{"topics", std::move(topics)}}},
                   {"actuators", {{"kick", "bool"}}}}}}};
  };
  for (const auto& ok : {Json{{"kick", "/robot/kick"}},
                         Json{{"kick",
                               {{"topic", "kick_now"},
                                {"qos", "sensor_data"},
                                {"depth", 5},
                                {"message", "std_msgs/msg/Bool"},
                                {"durability", "transient_local"}}}},
                         Json(nullptr)}) {
    INFO(ok.dump());
    CHECK(validator->errors(config(ok)).empty());
  }
  for (const auto& bad :
       {Json{{"kick", "kick//now"}}, Json{{"kick", "2nd_robot"}}, Json{{"kick", 5}},
        Json{{"kick", {{"reliability", "reliabel"}}}}, Json{{"kick", {{"depth", 0}}}},
        Json{{"kick", {{"qos", "sensors"}}}}, Json{{"kick", {{"message", "std_msgs/msg/Bol"}}}},
        Json{{"kick", {{"topc", "x"}}}}, Json{{"Kick", "x"}}, Json::array({"kick"})}) {
    INFO(bad.dump());
    CHECK_FALSE(validator->errors(config(bad)).empty());
  }
}

TEST_CASE("arbiter schema prints the schema with the registered classes", "[schema][cli]") {
  const auto builtin = run_cli("schema --builtin");
  REQUIRE(builtin.exit_code == 0);
  CHECK(Json::parse(builtin.out) == Json::parse(config_schema(builtin_registry())));

  const auto with_soccer = run_cli("schema --load soccer");
  REQUIRE(with_soccer.exit_code == 0);
  CHECK(contains(with_soccer.out, "\"const\": \"soccer.KickBall\""));

  const auto missing = run_cli("schema --load no_such_plugin");
  CHECK(missing.exit_code == 1);
  CHECK(contains(missing.err, "plugin 'no_such_plugin' not found"));
}

// --- dump ---

TEST_CASE("arbiter dump prints the paper example the same way every time", "[dump][cli]") {
  for (const std::string format : {"text", "dot", "json"}) {
    DYNAMIC_SECTION(format) {
      const std::string command = std::string("dump ") + kWalkAndKick + " --format " + format;
      const auto first = run_cli(command);
      const auto second = run_cli(command);
      INFO(first.err);
      REQUIRE(first.exit_code == 0);
      CHECK(first.out == second.out);
      check_golden("walk_and_kick." + format, first.out);
    }
  }
}

TEST_CASE("a multi-layer config dumps as text, DOT and JSON", "[dump]") {
  Registry registry = tooling_registry();
  Diagnostics diagnostics;
  test::WorkingDirectory here(kGoldenDir);
  const auto program = load("relay.yaml", registry, diagnostics, test::with_lints());
  INFO(format(diagnostics));
  REQUIRE(program.has_value());
  CHECK(diagnostics.empty());  // its delayed sensor's lint is silenced in its layer
  check_golden("relay.text", dump_text(*program));
  check_golden("relay.dot", dump_dot(*program));
  check_golden("relay.json", dump_json(*program));
  CHECK(dump_dot(*program) == dump_dot(*program));

  SECTION("one layer") {
    const std::string dot = dump_dot(*program, "control");
    CHECK(contains(dot, "cluster_layer_control"));
    CHECK_FALSE(contains(dot, "cluster_layer_planning"));
    CHECK(contains(dot, "\"a:target\" [label=\"target\\nlayer planning\""));
    const Json json = Json::parse(dump_json(*program, "control"));
    REQUIRE(json["layers"].size() == 1);
    CHECK(json["state_machines"].empty());
  }
}

TEST_CASE("the DOT dump draws chaining double, non-chaining single and implicit dashed", "[dump]") {
  Registry registry = tooling_registry();
  Diagnostics diagnostics;
  const auto dot = dump_dot(load_config(kWalkAndKick, registry, diagnostics));
  CHECK(contains(dot,
                 "\"b:control/kick_ball\" -> \"b:control/go_behind_ball\" [color=\"black:invis:"
                 "black\""));
  CHECK(contains(dot, "\"b:control/search_for_ball\" -> \"b:control/head_control\" [tooltip="));
  CHECK(
      contains(dot, "\"b:control/kick_ball\" -> \"b:control/search_for_ball\" [style=\"dashed\""));
  CHECK(contains(dot, "implicit: kick_ball => go_behind_ball => search_for_ball"));
}

TEST_CASE("arbiter dump rejects an unknown layer as a usage error", "[dump][cli]") {
  const auto result = run_cli(std::string("dump ") + kWalkAndKick + " --layer contrl");
  CHECK(result.exit_code == 2);
  CHECK(contains(result.err, "did you mean 'control'?"));
  CHECK(run_cli(std::string("dump ") + kWalkAndKick + " --format svg").exit_code == 2);
}

TEST_CASE("a config's steps: is how long arbiter run runs unless --steps says otherwise",
          "[run][cli]") {
  const std::string goalie = "configs/soccer/goalie.yaml";
  const auto by_config = run_cli("run " + goalie);
  REQUIRE(by_config.exit_code == 0);
  CHECK(contains(by_config.out, "\n240 steps.\n"));
  CHECK(contains(by_config.out, "simulated 16.00 s at 15 Hz"));
  const auto by_option = run_cli("run " + goalie + " --steps 30");
  REQUIRE(by_option.exit_code == 0);
  CHECK(contains(by_option.out, "\n30 steps.\n"));
  // Without steps: in the config, the default stays 100.
  const auto default_length =
      run_cli(std::string("run ") + kWalkAndKick + " -q --trace /dev/stdout");
  REQUIRE(default_length.exit_code == 0);
  CHECK(contains(default_length.out, "{\"step\": 100,"));
  CHECK_FALSE(contains(default_length.out, "{\"step\": 101,"));

  const auto text = run_cli("dump " + goalie);
  CHECK(contains(text.out, "manager goalie (15 Hz, 240 steps, 2 layers, 1 behaviours)"));
  const auto json = Json::parse(run_cli("dump " + goalie + " --format json").out);
  CHECK(json["steps"] == 240);
  CHECK_FALSE(Json::parse(run_cli(std::string("dump ") + kWalkAndKick + " --format json").out)
                  .contains("steps"));
}

// --- lints ---

TEST_CASE("each lint is reported once, located, with its code", "[lint]") {
  Registry registry = tooling_registry();
  Diagnostics diagnostics;
  test::WorkingDirectory here(kGoldenDir);
  const auto program = load("lints.yaml", registry, diagnostics, test::with_lints());
  REQUIRE(program.has_value());
  CHECK(diagnostics.error_count() == 0);
  check_golden("lints.expected", format(diagnostics));
  std::vector<std::string> codes;
  for (const auto& item : diagnostics.items()) {
    CHECK(item.severity == Severity::kWarning);
    codes.push_back(item.code);
  }
  for (const auto& lint : lint_codes()) {
    CHECK(std::count(codes.begin(), codes.end(), std::string(lint.code)) == 1);
  }
}

TEST_CASE("a load without the lint step, as on a robot, reports no lint", "[lint]") {
  Registry registry = tooling_registry();
  Diagnostics diagnostics;
  test::WorkingDirectory here(kGoldenDir);
  LoadOptions strict;
  strict.strict = true;  // a lint would be an error here, and the load would fail
  CHECK(load("lints.yaml", registry, diagnostics, strict).has_value());
  CHECK(diagnostics.empty());
}

TEST_CASE("lints are silenced by code, for the config or for one layer", "[lint]") {
  const std::string text = read_text(kGoldenDir / "lints.yaml");
  const auto diagnose = [](const std::string& config) {
    const Registry registry = tooling_registry();
    Diagnostics diagnostics;
    auto document = parse_document(config, "lints.yaml", DocumentFormat::kYaml, diagnostics);
    REQUIRE(document.has_value());
    const Model model = build_model(*document, registry, diagnostics);
    REQUIRE_FALSE(diagnostics.has_errors());
    auto program = compile(model, registry, diagnostics);
    REQUIRE(program.has_value());
    lint(model, *program, diagnostics);
    std::vector<std::string> codes;
    for (const auto& item : diagnostics.items()) codes.push_back(item.code);
    return codes;
  };
  SECTION("every lint at the top level") {
    std::string ignore_all = "lint: {ignore: [";
    for (const auto& lint : lint_codes()) ignore_all += std::string(lint.code) + ", ";
    ignore_all += "]}\n";
    std::string config = text;
    config.insert(config.find("layers:"), ignore_all);
    CHECK(diagnose(config).empty());
  }
  SECTION("in one layer: that layer's only") {
    std::string config = text;
    config.insert(config.find("    sensors: [distance, kick]"),
                  "    lint: {ignore: [delayed-sensor, unread-actuator, conflicting-writers]}\n");
    CHECK(diagnose(config) ==
          std::vector<std::string>{"redundant-inhibition", "never-active", "unread-actuator"});
  }
  SECTION("an unknown code is reported with the known ones") {
    std::string config = text;
    config.insert(config.find("layers:"), "lint: {ignore: [never-activ]}\n");
    const auto codes = diagnose(config);
    CHECK(std::count(codes.begin(), codes.end(), "unknown-lint") == 1);
    CHECK(std::count(codes.begin(), codes.end(), "never-active") == 1);
  }
}

TEST_CASE("the configs in configs/ have no lint", "[lint]") {
  for (const auto& path : configs_under(kSourceDir / "configs")) {
    DYNAMIC_SECTION(fs::relative(path, kSourceDir).string()) {
      if (!plugins_built(path)) continue;
      Registry registry = builtin_registry();
      Diagnostics diagnostics;
      const auto program = load(path.string(), registry, diagnostics, test::with_lints());
      INFO(format(diagnostics));
      CHECK(program.has_value());
      CHECK(diagnostics.empty());
    }
  }
}

TEST_CASE("a chain of always-full scripted behaviours is followed through the closure", "[lint]") {
  // a requests 1 and nothing inhibits it: b is never active. b never active leaves c free, but
  // a => b => c also makes a inhibit c: c is never active too, through the chain.
  const std::string config = R"(
arbiter: 1
name: chain
layers:
  - name: l
    behaviours:
      a: scripted
      b: {type: scripted, params: {activation: 0.5}}
      c: {type: scripted, params: {activation: [1, 0]}}
      d: {type: scripted, params: {activation: 0}}
      e: scripted
    inhibitions: [a => b, b => c, d -> e]
)";
  const Registry registry = builtin_registry();
  Diagnostics diagnostics;
  auto document = parse_document(config, "chain.yaml", DocumentFormat::kYaml, diagnostics);
  const Model model = build_model(*document, registry, diagnostics);
  auto program = compile(model, registry, diagnostics);
  REQUIRE(program.has_value());
  lint(model, *program, diagnostics);
  std::string text = format(diagnostics);
  CHECK(contains(text, "behaviour 'b' can never be active: 'a' inhibits it"));
  CHECK(contains(text, "behaviour 'c' can never be active: 'a' inhibits it"));
  CHECK(contains(text, "'a' inhibits 'c' through chaining: a => b => c"));
  CHECK(contains(text, "'a' is scripted to request 1 at every step (its default activation)"));
  // d requests 0 at every step, so e (requesting 1) is not covered: it is always active.
  CHECK_FALSE(contains(text, "behaviour 'e'"));
  CHECK(diagnostics.warning_count() == 2);
}

TEST_CASE("never-active and redundant-inhibition agree with the closure on random graphs",
          "[lint]") {
  // The lints carry their properties along declared edges; here they are checked against a
  // brute force over Program's closed inhibitor lists and a search over chaining edges.
  std::mt19937 random(7);
  const Registry registry = builtin_registry();
  for (int round = 0; round < 40; ++round) {
    const int n = 5 + static_cast<int>(random() % 30);
    std::string config = "arbiter: 1\nname: random\nlayers:\n  - name: l\n    behaviours:\n";
    const char* levels[] = {"0", "1", "0.5", "[1, 1]", "[0, 1]"};
    for (int b = 0; b < n; ++b) {
      config += "      b" + std::to_string(b) +
                ": {type: scripted, params: {activation: " + levels[random() % 5] + "}}\n";
    }
    config += "    inhibitions:\n";
    struct Edge {
      int from, to;
      bool chaining;
    };
    std::vector<Edge> edges;
    for (int e = 0; e < 2 * n; ++e) {
      const int from = static_cast<int>(random() % n);
      const int to = static_cast<int>(random() % n);
      if (from >= to) continue;
      if (std::any_of(edges.begin(), edges.end(),
                      [&](const Edge& x) { return x.from == from && x.to == to; })) {
        continue;
      }
      edges.push_back({from, to, random() % 3 != 0});
      config += "      - b" + std::to_string(from) + (edges.back().chaining ? " => b" : " -> b") +
                std::to_string(to) + "\n";
    }
    Diagnostics diagnostics;
    auto document = parse_document(config, "random.yaml", DocumentFormat::kYaml, diagnostics);
    const Model model = build_model(*document, registry, diagnostics);
    auto program = compile(model, registry, diagnostics);
    INFO(config << format(diagnostics));
    REQUIRE(program.has_value());
    lint(model, *program, diagnostics);

    std::set<std::string> never_reported;
    std::set<std::string> redundant_reported;
    for (const auto& item : diagnostics.items()) {
      const auto first = item.message.find('\'') + 1;
      const std::string quoted = item.message.substr(first, item.message.find('\'', first) - first);
      if (item.code == "never-active") never_reported.insert(quoted);
      if (item.code == "redundant-inhibition") redundant_reported.insert(quoted);
    }
    // Brute force, in execution order, over the closed inhibitor lists.
    const auto count = program->behaviours.size();
    std::vector<bool> full(count, false);
    std::vector<bool> never(count, false);
    std::set<std::string> never_expected;
    for (std::uint32_t b = 0; b < count; ++b) {
      const auto closed = program->inhibitions.closed(b);
      const BehaviourDecl* decl = nullptr;
      for (const auto& candidate : model.layers[0].behaviours) {
        if (candidate.name.text == program->behaviours[b].name) decl = &candidate;
      }
      REQUIRE(decl != nullptr);
      const auto& requested = std::get<std::vector<double>>(decl->params.find("activation")->value);
      const auto all = [&](double v) {
        return std::all_of(requested.begin(), requested.end(), [&](double r) { return r == v; });
      };
      const bool covered =
          std::any_of(closed.begin(), closed.end(), [&](std::uint32_t i) { return full[i]; });
      const bool free =
          std::all_of(closed.begin(), closed.end(), [&](std::uint32_t i) { return never[i]; });
      full[b] = all(1.0) && free;
      never[b] = covered || all(0.0);
      if (covered) never_expected.insert(program->behaviours[b].name);
    }
    CHECK(never_reported == never_expected);
    // An edge a -> c is redundant when c is reachable from a chaining successor x != c of a.
    std::set<std::string> redundant_expected;
    for (const auto& edge : edges) {
      std::vector<int> stack;
      std::vector<bool> seen(static_cast<std::size_t>(n), false);
      for (const auto& out : edges) {
        if (out.from == edge.from && out.chaining && out.to != edge.to) stack.push_back(out.to);
      }
      bool reached = false;
      while (!stack.empty() && !reached) {
        const int at = stack.back();
        stack.pop_back();
        if (seen[static_cast<std::size_t>(at)]) continue;
        seen[static_cast<std::size_t>(at)] = true;
        for (const auto& out : edges) {
          if (out.from != at || !out.chaining) continue;
          reached = reached || out.to == edge.to;
          stack.push_back(out.to);
        }
      }
      if (reached) {
        redundant_expected.insert("b" + std::to_string(edge.from) +
                                  (edge.chaining ? " => b" : " -> b") + std::to_string(edge.to));
      }
    }
    CHECK(redundant_reported == redundant_expected);
  }
}

TEST_CASE("redundant inhibitions are found in layers larger than one block of reachability",
          "[lint]") {
  std::string config = "arbiter: 1\nname: long\nlayers:\n  - name: l\n    behaviours:\n";
  constexpr int kCount = 5000;
  for (int b = 0; b < kCount; ++b) {
    config += "      b" + std::to_string(b) + ": {type: scripted, params: {activation: 0.5}}\n";
  }
  config += "    inhibitions:\n";
  for (int b = 0; b + 1 < kCount; ++b) {
    config += "      - b" + std::to_string(b) + " => b" + std::to_string(b + 1) + "\n";
  }
  config += "      - b0 -> b4999\n      - b10 => b4100\n      - b4097 -> b4099\n";
  const Registry registry = builtin_registry();
  Diagnostics diagnostics;
  auto document = parse_document(config, "long.yaml", DocumentFormat::kYaml, diagnostics);
  const Model model = build_model(*document, registry, diagnostics);
  auto program = compile(model, registry, diagnostics);
  REQUIRE(program.has_value());
  lint(model, *program, diagnostics);
  std::vector<std::string> messages;
  for (const auto& item : diagnostics.items()) messages.push_back(item.message);
  CHECK(messages ==
        std::vector<std::string>{
            "inhibition 'b0 -> b4999' is already implied by chaining b0 => b1 => b2 => b3 => b4 "
            "=> b5 => b6 => b7 => b8 => b9 => b10 => b11 => b12 => ... => b4999",
            "inhibition 'b10 => b4100' is already implied by chaining b10 => b11 => b12 => b13 => "
            "b14 => b15 => b16 => b17 => b18 => b19 => b20 => b21 => b22 => ... => b4100",
            "inhibition 'b4097 -> b4099' is already implied by chaining b4097 => b4098 => b4099"});
}

// --- validate ---

TEST_CASE("arbiter validate --format json prints located diagnostics for machines",
          "[validate][cli]") {
  SECTION("errors, with exit code 1") {
    const auto result = run_cli("validate --format json tests/data/invalid/unknown_key.yaml");
    CHECK(result.exit_code == 1);
    const Json diagnostics = Json::parse(result.out);
    REQUIRE(diagnostics.is_array());
    REQUIRE(!diagnostics.empty());
    const Json& first = diagnostics[0];
    CHECK(first["file"] == "tests/data/invalid/unknown_key.yaml");
    CHECK(first["line"] == 3);
    CHECK(first["column"] == 1);
    CHECK(first["severity"] == "error");
    CHECK(first["code"] == "unknown-key");
    CHECK(first["message"] == "unknown key 'rate' in the config");
    CHECK(first["notes"].is_array());
    for (const auto& item : diagnostics) {
      for (const char* key : {"file", "line", "column", "severity", "code", "message", "notes"}) {
        CHECK(item.contains(key));
      }
    }
  }
  SECTION("a valid config gives an empty array") {
    const auto result = run_cli(std::string("validate --format json ") + kWalkAndKick);
    CHECK(result.exit_code == 0);
    CHECK(Json::parse(result.out) == Json::array());
  }
  SECTION("lints are warnings; --strict makes them errors") {
    const std::string config = "tests/data/golden/lints.yaml";
    // The test classes are not in the CLI: a copy with built-in classes only.
    std::string text = read_text(kSourceDir / config);
    for (const std::string from :
         {"interface: test.Feed\n    ports: {out: distance, in: speed}", "test.Probe"}) {
      for (auto at = text.find(from); at != std::string::npos; at = text.find(from)) {
        text.replace(at, from.size(), from == "test.Probe" ? "scripted" : "");
      }
    }
    const fs::path copy =
        fs::temp_directory_path() / ("arbiter_lints_" + std::to_string(::getpid()) + ".yaml");
    write_text(copy, text);
    const auto lenient = run_cli("validate --format json \"" + copy.string() + "\"");
    CHECK(lenient.exit_code == 0);
    const Json warnings = Json::parse(lenient.out);
    REQUIRE(!warnings.empty());
    CHECK(warnings[0]["severity"] == "warning");
    const auto strict = run_cli("validate --strict --format json \"" + copy.string() + "\"");
    CHECK(strict.exit_code == 1);
    CHECK(Json::parse(strict.out)[0]["severity"] == "error");
    const auto text_output = run_cli("validate \"" + copy.string() + "\"");
    CHECK(text_output.exit_code == 0);
    CHECK(contains(text_output.err, ": warning["));
    CHECK(contains(text_output.err, "never be active"));
    fs::remove(copy);
  }
}

TEST_CASE("a missing config is an error of its own and the other files are still checked",
          "[validate][cli]") {
  const auto result = run_cli(std::string("validate missing.yaml ") + kWalkAndKick +
                              " tests/data/invalid/unknown_key.yaml");
  CHECK(result.exit_code == 1);
  CHECK(contains(result.err,
                 "missing.yaml: error[file-not-found]: cannot open: No such file or directory\n"));
  CHECK(contains(result.err, std::string(kWalkAndKick) + ": ok\n"));
  CHECK(contains(result.err, "unknown_key.yaml:3:1: error[unknown-key]: unknown key 'rate'"));
  CHECK(contains(result.err, "4 error(s), 0 warning(s)\n"));
  SECTION("as JSON, located at the file") {
    const auto json = run_cli("validate --format json missing.yaml");
    CHECK(json.exit_code == 1);
    const Json diagnostics = Json::parse(json.out);
    REQUIRE(diagnostics.size() == 1);
    CHECK(diagnostics[0]["file"] == "missing.yaml");
    CHECK(diagnostics[0]["code"] == "file-not-found");
  }
  SECTION("the commands that run or print a config say the same") {
    for (const char* command : {"run missing.yaml", "dump missing.yaml"}) {
      INFO(command);
      const auto other = run_cli(command);
      CHECK(other.exit_code == 1);
      CHECK(other.err ==
            "missing.yaml: error[file-not-found]: cannot open: No such file or directory\n");
    }
  }
}

// --- plugins ---

TEST_CASE("arbiter plugins lists every class with its params and ports", "[plugins][cli]") {
  SECTION("the built-ins, as JSON") {
    const auto result = run_cli("plugins --builtin --format json");
    REQUIRE(result.exit_code == 0);
    const Json catalog = Json::parse(result.out);
    CHECK(catalog == Json::parse(catalog_json(builtin_registry())));
    const Json* scripted = nullptr;
    for (const auto& cls : catalog["classes"]) {
      if (cls["name"] == "scripted" && cls["kind"] == "behaviour") scripted = &cls;
    }
    REQUIRE(scripted != nullptr);
    CHECK((*scripted)["origin"] == "built-in");
    const Json& activation = (*scripted)["params"][0];
    CHECK(activation["name"] == "activation");
    CHECK(activation["type"] == "list of double");
    CHECK(activation["required"] == false);
    CHECK(activation["default"] == Json({1.0}));
    CHECK(activation["minimum"] == 0.0);
    CHECK(activation["maximum"] == 1.0);
    CHECK_FALSE(activation["description"].get<std::string>().empty());
    CHECK(catalog["value_types"].size() == 6);
  }
  SECTION("a plugin on the path, as text") {
    const auto result = run_cli("plugins --load soccer");
    INFO(result.err);
    REQUIRE(result.exit_code == 0);
    CHECK(contains(result.out, "behaviour classes\n  scripted (built-in)\n"));
    CHECK(contains(result.out, "  soccer.SearchForBall (plugin soccer ("));
    CHECK(contains(result.out, "      turn_rate: double, default "));
    CHECK(contains(result.out, "      gait_velocity: output vec3\n"));
    CHECK(contains(result.out, "      ball_visible: input bool"));
    CHECK(contains(result.out, "interface classes\n  soccer.WorldLink"));
  }
  SECTION("every plugin on the path, by default") {
    const auto result = run_cli("plugins --format json");
    REQUIRE(result.exit_code == 0);
    CHECK(contains(result.out, "\"name\": \"soccer.KickBall\""));
  }
  SECTION("a plugin that is not there") {
    const auto result = run_cli("plugins --load no_such_plugin");
    CHECK(result.exit_code == 1);
    CHECK(contains(result.err,
                   "arbiter plugins: error[plugin-not-found]: plugin 'no_such_plugin' not found"));
  }
}

// --- explain ---

TEST_CASE("explain tells why search_for_ball is inactive at step 8 of the paper example",
          "[explain]") {
  Registry registry = tooling_registry();
  Diagnostics diagnostics;
  const Program program = load_config(kWalkAndKick, registry, diagnostics);
  std::istringstream trace(trace_of(kWalkAndKick, 20));
  const auto explanation = explain(program, trace, 8, "search_for_ball");
  REQUIRE(explanation.status == Explanation::Status::kOk);
  check_golden("explain_search_for_ball.txt", explanation.text);
  CHECK(contains(explanation.text, "at step 8: inactive, activation 0\n"));
  CHECK(contains(explanation.text, "requested: 0.5\n"));
  CHECK(contains(explanation.text,
                 "implicit, from chaining kick_ball => go_behind_ball => "
                 "search_for_ball"));
  CHECK(contains(explanation.text, "inactive: go_behind_ball is fully active (factor 0)"));
}

TEST_CASE("explain gives the product of the factors and the normalisation", "[explain]") {
  Registry registry = tooling_registry();
  Diagnostics diagnostics;
  const std::string config = "tests/data/golden/relay.yaml";
  const Program program = load_config(config, registry, diagnostics);
  const std::string trace_text = trace_of(config, 6);
  std::istringstream trace(trace_text);
  const auto explanation = explain(program, trace, 2, "planning/retreat");
  REQUIRE(explanation.status == Explanation::Status::kOk);
  // approach 0.6 => retreat 0.3: refined 0.3 × 0.4 = 0.12; wait 0.5 × 0.4 × 0.88 = 0.176;
  // the layer's sum is 0.6 + 0.12 + 0.176 = 0.896.
  CHECK(contains(explanation.text, "refined = 0.3 × 0.4 = 0.12\n"));
  CHECK(contains(explanation.text,
                 "0.12 / 0.896 (the sum of the layer's refined levels) = "
                 "0.133929\n"));
  CHECK_FALSE(contains(explanation.text, "note:"));
}

TEST_CASE("explain tells what a state machine did in a step", "[explain]") {
  Registry registry = tooling_registry();
  Diagnostics diagnostics;
  const std::string config = "configs/paper/goalie_plan.yaml";
  const Program program = load_config(config, registry, diagnostics);
  const std::string trace_text = trace_of(config, 50);
  {
    std::istringstream trace(trace_text);
    const auto explanation = explain(program, trace, 6, "goalie");
    REQUIRE(explanation.status == Explanation::Status::kOk);
    check_golden("explain_goalie.txt", explanation.text);
    CHECK(contains(explanation.text,
                   "events, in order: deactivate wait_for_button, "
                   "activate walk_to_pose, execute walk_to_pose\n"));
  }
  {
    std::istringstream trace(trace_text);
    const auto explanation = explain(program, trace, 2, "state_machines/goalie");
    REQUIRE(explanation.status == Explanation::Status::kOk);
    CHECK(contains(explanation.text, "wait_for_button executed and held: it runs again at step 3"));
  }
  {
    // The scripted button press: the actual cause, not a list of the possible ones.
    std::istringstream trace(trace_text);
    const auto explanation = explain(program, trace, 40, "goalie");
    REQUIRE(explanation.status == Explanation::Status::kOk);
    CHECK(contains(explanation.text,
                   "    - monitor_ball was deactivated: pre-empted by wait_for_button (preempt: at "
                   "cycle 40); it had asked to proceed\n"));
  }
}

// --- why a state ended: the trace's `ended`, run's report and explain ---

namespace {

/// A run of a config of one state machine `m`, with the test classes: its trace, run's report,
/// and what explain says about `m` at every step.
struct Story {
  std::vector<Json> records;  ///< per step, from 1 (0: the header)
  std::string report;
  std::vector<std::string> explained;  ///< per step, from 1 (0: unused)

  /// The trace's `ended` of `m` at `step` (null when there is none).
  const Json& ended(std::size_t step) const {
    static const Json kNull;
    const Json& entry = records.at(step)["controllers"]["m"];
    return entry.contains("ended") ? entry["ended"] : kNull;
  }
};

Story story_of(const std::string& states, const std::string& queue, int steps,
               const std::string& extra = "", ControllerHooks* hooks = nullptr) {
  const std::string yaml = "arbiter: 1\nname: t\nstate_machines:\n  m:\n    states:\n" + states +
                           "    queue: " + queue + "\n" + extra;
  Registry registry = tooling_registry();
  Manager manager(test::compile_text(yaml, registry));
  if (hooks != nullptr) manager.program().find_controller("m")->set_hooks(hooks);
  std::ostringstream trace_out;
  std::ostringstream report_out;
  TraceWriter trace(trace_out);
  cli::RunReport report(report_out, false);
  manager.add_observer(trace);
  manager.add_observer(report);
  for (int i = 0; i < steps; ++i) manager.step();
  manager.finish();
  Story story;
  story.report = report_out.str();
  std::istringstream lines(trace_out.str());
  for (std::string line; std::getline(lines, line);) story.records.push_back(Json::parse(line));
  story.explained.emplace_back();
  for (int step = 1; step <= steps; ++step) {
    std::istringstream in(trace_out.str());
    const auto explanation = explain(manager.program(), in, static_cast<std::uint64_t>(step), "m");
    REQUIRE(explanation.status == Explanation::Status::kOk);
    story.explained.push_back(explanation.text);
  }
  return story;
}

}  // namespace

TEST_CASE("a state that asked to proceed ended because it proceeded", "[scl][explain][run]") {
  const auto story = story_of("      a: scripted\n      b: scripted\n", "[a, b]", 2);
  CHECK(story.ended(1).is_null());
  CHECK(story.ended(2) == Json::parse(R"([{"state": "a", "cause": "proceeded"}])"));
  CHECK(contains(story.report,
                 "step    2  m: a ended (proceeded)\n"
                 "step    2  m: b (cycle 2; queued: nothing)\n"));
  CHECK(contains(story.explained[2], "    - a was deactivated: proceeded\n"));
  CHECK(contains(story.explained[1], "    - a executed and is deactivated at step 2: proceeded\n"));
}

TEST_CASE("a state that proceeded with nothing queued ended the machine", "[scl][explain][run]") {
  const auto story = story_of("      a: scripted\n", "[a]", 2);
  CHECK(story.ended(2) == Json::parse(R"([{"state": "a", "cause": "queue_empty"}])"));
  CHECK(contains(story.report,
                 "step    2  m: a ended (proceeded, queue empty)\n"
                 "step    2  m: finished\n"));
  CHECK(contains(story.explained[2], "    - a was deactivated: proceeded, queue empty\n"));
}

TEST_CASE("a pre-empted state says what pre-empted it", "[scl][explain][run]") {
  SECTION("the config's preempt: entry") {
    const auto story = story_of(
        "      wait: {type: scripted, params: {hold: 100}}\n"
        "      walk: {type: scripted, params: {hold: 100}}\n",
        "[wait, walk]", 3,
        "    preempt:\n      - {cycle: 2, go_to: wait}\n      - {cycle: 3, go_to: walk}\n");
    CHECK(story.ended(3) ==
          Json::parse(R"([{"state": "wait", "cause": "preempted", "to": "walk", "preempt": 1}])"));
    CHECK(contains(story.report,
                   "step    3  m: wait ended (pre-empted by walk (preempt: at cycle 3))\n"));
    CHECK(contains(story.explained[3],
                   "    - wait was deactivated: pre-empted by walk (preempt: at cycle 3)\n"));
    // At cycle 2 the pre-emption planned wait again: the wait of cycle 1 ended for it.
    CHECK(story.ended(2)[0]["to"] == "wait");
  }
  SECTION("a hook, after the state had asked to proceed") {
    struct ButtonPress : ControllerHooks {
      PlannedState target;
      bool pre_step(Controller& controller, Plan& plan) override {
        if (controller.cycle() != 2) return false;
        // Kept by the hooks: the planned instance refers to it.
        target = test::planned(controller, "walk");
        plan.go_to(target);
        return true;
      }
    } hooks;
    const auto story =
        story_of("      wait: scripted\n      walk: scripted\n      other: scripted\n",
                 "[wait, other]", 2, "", &hooks);
    CHECK(story.ended(2) == Json::parse(R"([{"state": "wait", "cause": "preempted", "to": "walk",
                                             "proceeded": true}])"));
    CHECK(contains(story.report,
                   "step    2  m: wait ended (pre-empted by walk; it had asked to proceed)\n"));
    CHECK(contains(story.explained[2],
                   "    - wait was deactivated: pre-empted by walk; it had asked to proceed\n"));
  }
}

TEST_CASE("a state that went to another with go_to says so", "[scl][explain][run]") {
  const auto story = story_of(
      "      a: {type: test.Planner, params: {op: go_to, target: c}}\n"
      "      b: scripted\n      c: scripted\n",
      "[a, b, b]", 2);
  CHECK(story.ended(2) == Json::parse(R"([{"state": "a", "cause": "go_to", "to": "c"}])"));
  CHECK(contains(story.report, "step    2  m: a ended (go_to c)\n"));
  CHECK(contains(story.explained[2], "    - a was deactivated: go_to c\n"));
}

TEST_CASE("a state that terminated its machine says so", "[scl][explain][run]") {
  SECTION("itself, in the step it ran") {
    const auto story = story_of(
        "      a: {type: scripted, params: {terminate: true}}\n      b: scripted\n", "[a, b]", 1);
    CHECK(story.ended(1) == Json::parse(R"([{"state": "a", "cause": "terminated", "by": "a"}])"));
    CHECK(contains(story.report,
                   "step    1  m: a ended (terminated)\n"
                   "step    1  m: finished\n"));
    CHECK(contains(story.explained[1], "    - a was deactivated: terminated\n"));
  }
  SECTION("the state after a proceeding one, in its activate()") {
    const auto story = story_of(
        "      a: scripted\n      b: {type: test.Planner, params: {op: terminate_in_activate}}\n",
        "[a, b]", 2);
    CHECK(story.ended(2) == Json::parse(R"([{"state": "a", "cause": "proceeded"},
                                            {"state": "b", "cause": "terminated", "by": "b"}])"));
    CHECK(contains(story.report,
                   "step    2  m: a ended (proceeded)\n"
                   "step    2  m: b (cycle 2; queued: nothing)\n"
                   "step    2  m: b ended (terminated)\n"
                   "step    2  m: finished\n"));
    CHECK(contains(story.explained[2],
                   "    - a was deactivated: proceeded\n"
                   "    - b became the current state (the head of the queue) "
                   "and was activated\n"
                   "    - b was deactivated: terminated\n"));
  }
}

TEST_CASE("a planned state shows its per-instance params", "[scl][explain][run]") {
  // From the config's queue, and from a Plan call at run time (x passed by test.Planner).
  const auto story = story_of(
      "      p: test.Pose\n      a: {type: test.Planner, params: {op: append, target: p, "
      "x: 2.5}}\n",
      "[{p: {x: 1.25}}, a]", 4);
  CHECK(story.records[1]["controllers"]["m"]["params"] == Json::parse(R"({"x": 1.25})"));
  CHECK(story.ended(2) ==
        Json::parse(R"([{"state": "p", "params": {"x": 1.25}, "cause": "proceeded"}])"));
  CHECK_FALSE(story.records[2]["controllers"]["m"].contains("params"));  // a has none of its own
  CHECK(story.records[3]["controllers"]["m"]["params"] == Json::parse(R"({"x": 2.5})"));
  CHECK(contains(story.report,
                 "step    1  m: p {x: 1.25} (cycle 1; queued: a)\n"
                 "step    2  m: p {x: 1.25} ended (proceeded)\n"
                 "step    2  m: a (cycle 2; queued: p)\n"
                 "step    3  m: a ended (proceeded)\n"
                 "step    3  m: p {x: 2.5} (cycle 3; queued: nothing)\n"
                 "step    4  m: p {x: 2.5} ended (proceeded, queue empty)\n"));
  CHECK(contains(story.explained[1], "after the step: state p {x: 1.25}; queue: a\n"));
  CHECK(contains(story.explained[2], "    - p {x: 1.25} was deactivated: proceeded\n"));
  CHECK(contains(story.explained[3],
                 "    - p {x: 2.5} became the current state (the head of the queue)"));
}

TEST_CASE("arbiter run prints a step's events in the order they happened", "[run][cli][soccer]") {
  // The world reports the shot in the input pass; the goalie behaviour then sees it, pre-empts
  // its plan to dive and reports the dive.
  const auto result = run_cli("run configs/soccer/goalie.yaml --steps 210");
  REQUIRE(result.exit_code == 0);
  CHECK(contains(result.out,
                 "step  201  world: shot on goal\n"
                 "step  201  goalie: monitor_ball ended (pre-empted by dive)\n"
                 "step  201  goalie: dive (cycle 201; queued: monitor_ball)\n"
                 "step  201  goalie: goalie dives left\n"));
  CHECK(contains(result.out,
                 "step   11  goalie: wait_for_button ended (proceeded)\n"
                 "step   11  goalie: walk_to_pose {x: -4.2, y: 0.0, theta: 0.0} "
                 "(cycle 11; queued: monitor_ball)\n"));
}

TEST_CASE("explain reads a trace of a run reloaded with --watch", "[explain][reload]") {
  Registry registry = tooling_registry();
  Diagnostics diagnostics;
  const Program program = load_config(kWalkAndKick, registry, diagnostics);
  std::vector<std::string> lines;
  {
    std::istringstream in(trace_of(kWalkAndKick, 10));
    for (std::string line; std::getline(in, line);) lines.push_back(line);
  }
  REQUIRE(lines.size() == 11);
  // The header a reload after step 5 writes, for the program it swapped in.
  const auto reload_header = [](std::string header) {
    const std::string start = "{\"arbiter_trace\": 1, ";
    REQUIRE(header.rfind(start, 0) == 0);
    return start + "\"reload\": 1, \"after_step\": 5, " + header.substr(start.size());
  };
  const auto reloaded = [&](const std::string& header) {
    std::string text;
    for (std::size_t i = 0; i < lines.size(); ++i) {
      if (i == 6) text += reload_header(header) + "\n";
      text += lines[i] + "\n";
    }
    return text;
  };
  const auto explain_text = [&](const std::string& trace, std::uint64_t step) {
    std::istringstream in(trace);
    return explain(program, in, step, "search_for_ball");
  };
  std::string other_header;
  std::getline(std::istringstream(trace_of("configs/paper/hierarchical.yaml", 1)) >> std::ws,
               other_header);

  // Reloaded into the config given: steps on both sides of the reload are explained.
  const std::string same = reloaded(lines[0]);
  CHECK(explain_text(same, 3).status == Explanation::Status::kOk);
  std::string whole;
  for (const auto& line : lines) whole += line + "\n";
  const auto after = explain_text(same, 7);
  REQUIRE(after.status == Explanation::Status::kOk);
  CHECK(after.text == explain_text(whole, 7).text);

  // Reloaded into another config: the steps before it still match this one, those after do not.
  const std::string other = reloaded(other_header);
  CHECK(explain_text(other, 5).status == Explanation::Status::kOk);
  const auto mismatch = explain_text(other, 7);
  CHECK(mismatch.status == Explanation::Status::kBadTrace);
  CHECK(mismatch.text == "the trace was written for 'hierarchical', not for 'walk_and_kick'");
}

TEST_CASE("explain reports what it cannot explain", "[explain]") {
  Registry registry = tooling_registry();
  Diagnostics diagnostics;
  const Program program = load_config(kWalkAndKick, registry, diagnostics);
  const std::string trace_text = trace_of(kWalkAndKick, 20);
  const auto explain_text = [&](const std::string& trace, std::uint64_t step,
                                const std::string& target) {
    std::istringstream in(trace);
    return explain(program, in, step, target);
  };
  auto result = explain_text(trace_text, 8, "search_for_bal");
  CHECK(result.status == Explanation::Status::kNotFound);
  REQUIRE(!result.notes.empty());
  CHECK(contains(result.notes[0], "did you mean 'search_for_ball'?"));
  result = explain_text(trace_text, 21, "search_for_ball");
  CHECK(result.status == Explanation::Status::kNotFound);
  CHECK(result.text == "the trace has steps 1 to 20, not step 21");
  result = explain_text(trace_of("configs/paper/hierarchical.yaml", 3), 2, "kick_ball");
  CHECK(result.status == Explanation::Status::kBadTrace);
  CHECK(result.text == "the trace was written for 'hierarchical', not for 'walk_and_kick'");
  result = explain_text("{\"arbiter_trace\": 1, \"name\": \"walk_and_kick\"\n", 1, "kick_ball");
  CHECK(result.status == Explanation::Status::kBadTrace);
}

TEST_CASE("arbiter explain runs from a trace file", "[explain][cli]") {
  const fs::path trace =
      fs::temp_directory_path() / ("arbiter_explain_" + std::to_string(::getpid()) + ".jsonl");
  REQUIRE(
      run_cli(std::string("run -q --steps 20 --trace \"") + trace.string() + "\" " + kWalkAndKick)
          .exit_code == 0);
  const std::string base =
      std::string("explain ") + kWalkAndKick + " --trace \"" + trace.string() + "\"";
  const auto ok = run_cli(base + " --step 8 search_for_ball");
  CHECK(ok.exit_code == 0);
  CHECK(ok.out == read_text(kGoldenDir / "explain_search_for_ball.txt"));
  CHECK(run_cli(base + " --step 8 control/search_for_ball").exit_code == 0);
  const auto unknown = run_cli(base + " --step 8 nobody");
  CHECK(unknown.exit_code == 2);
  CHECK(contains(unknown.err, "arbiter explain: 'nobody' names no behaviour"));
  CHECK(run_cli(base + " --step 99 kick_ball").exit_code == 2);
  CHECK(run_cli(std::string("explain ") + kWalkAndKick + " --step 1 kick_ball").exit_code == 2);
  fs::remove(trace);
}

// --- help ---

TEST_CASE("every command's help ends with examples", "[help][cli]") {
  for (const std::string command :
       {"", "validate", "run", "dump", "explain", "plugins", "schema"}) {
    DYNAMIC_SECTION("arbiter " << command << " --help") {
      const auto result = run_cli(command + " --help");
      CHECK(result.exit_code == 0);
      CHECK(contains(result.out, "\nExamples:\n  arbiter "));
      CHECK(contains(result.out, "\n  arbiter " + command));
      CHECK(contains(result.out, "Exit codes: 0 ok"));
    }
  }
  CHECK(contains(run_cli("validate --help").out, "redundant-inhibition"));
}

TEST_CASE("every scenario test file fits schema/arbiter-test.schema.json, a misshapen one does not",
          "[schema]") {
  const SchemaValidator schema(
      Json::parse(read_text(kSourceDir / "schema" / "arbiter-test.schema.json")));
  std::size_t checked = 0;
  for (const auto& dir : {kSourceDir / "tests" / "scenarios", kDataDir / "scenarios" / "failing",
                          kDataDir / "scenarios" / "recorded"}) {
    for (const auto& entry : fs::recursive_directory_iterator(dir)) {
      if (!is_scenario_file(entry.path().string())) continue;
      if (entry.path().filename() == "inputs_and_replay.test.yaml") continue;  // below
      const auto document = config_json(entry.path());
      REQUIRE(document);
      INFO(entry.path().string());
      CHECK(schema.errors(*document) == "");
      ++checked;
    }
  }
  CHECK(checked >= 7);
  const auto misshapen =
      config_json(kDataDir / "scenarios" / "invalid" / "test_file_shape.test.yaml");
  REQUIRE(misshapen);
  CHECK(schema.errors(*misshapen) != "");
  const auto both_inputs =
      config_json(kDataDir / "scenarios" / "recorded" / "inputs_and_replay.test.yaml");
  REQUIRE(both_inputs);
  CHECK(schema.errors(*both_inputs) != "");
}

TEST_CASE("load_config reads texts held in memory before the disk, for included files too",
          "[load]") {
  const auto dir = std::filesystem::temp_directory_path() / "arbiter_overlay_test";
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
