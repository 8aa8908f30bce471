// The JSON Schemas (schema/, arbiter schema), checked with valijson against every config, the
// invalid ones, the test files and the classes' params.

#include <catch2/catch.hpp>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <valijson/adapters/nlohmann_json_adapter.hpp>
#include <valijson/schema.hpp>
#include <valijson/schema_parser.hpp>
#include <valijson/validation_results.hpp>
#include <valijson/validator.hpp>
#include <vector>

#include "arbiter/document.hpp"
#include "arbiter/lint.hpp"
#include "arbiter/plugin.hpp"
#include "arbiter/scenario.hpp"
#include "arbiter/schema.hpp"
#include "tooling_support.hpp"

namespace fs = std::filesystem;
using namespace arbiter;
using namespace arbiter::test;
using Json = nlohmann::json;

namespace {

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

}  // namespace

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
  const test::TempDir scratch;
  const fs::path probe = scratch.path() / "arbiter_dds_schema_probe.yaml";
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

TEST_CASE("every scenario test file fits schema/arbiter-test.schema.json, a misshapen one does not",
          "[schema]") {
  const SchemaValidator schema(
      Json::parse(read_text(kSourceDir / "schema" / "arbiter-test.schema.json")));
  std::size_t checked = 0;
  for (const auto& dir : {kSourceDir / "tests" / "scenarios", kDataDir / "scenarios" / "failing",
                          kDataDir / "scenarios" / "recorded"}) {
    const auto is_test_file = [](const fs::path& path) { return is_scenario_file(path.string()); };
    for (const auto& path : files_in(dir, is_test_file, Walk::kRecursive)) {
      if (path.filename() == "inputs_and_replay.test.yaml") continue;  // below
      const auto document = config_json(path);
      REQUIRE(document);
      INFO(path.string());
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
