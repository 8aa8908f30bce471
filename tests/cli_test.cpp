// The CLI's commands as a user meets them: validate (exit codes, colours, --format json),
// plugins, run's steps and events, and every command's help.

#include <unistd.h>

#include <fmt/format.h>
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include "arbiter/catalog.hpp"
#include "arbiter/recorded_inputs.hpp"
#include "arbiter/recording.hpp"
#include "arbiter/reload.hpp"
#include "core/record/mcap.hpp"
#include "tooling_support.hpp"

namespace fs = std::filesystem;
using namespace arbiter;
using namespace arbiter::test;
using Json = nlohmann::json;
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

TEST_CASE("arbiter validate --format json gives the place a note speaks of", "[validate][cli]") {
  const auto result = run_cli("validate --format json tests/data/invalid/duplicate_layer.yaml");
  CHECK(result.exit_code == 1);
  const Json diagnostics = Json::parse(result.out);
  REQUIRE(diagnostics.size() == 1);
  const Json& duplicate = diagnostics[0];
  CHECK(duplicate["notes"] ==
        Json::array({"first declared at tests/data/invalid/duplicate_layer.yaml:4:11"}));
  CHECK(duplicate["note_locations"] ==
        Json::parse(R"([{"file": "tests/data/invalid/duplicate_layer.yaml", "line": 4,
                         "column": 11}])"));
  // A note that is only text has a null place; a diagnostic with no placed note, no field.
  const std::string duplicates = "tests/data/invalid/warn_duplicate_inhibition.yaml";
  const auto both = Json::parse(run_cli("validate --format json " + duplicates).out);
  REQUIRE(both.size() == 3);
  CHECK(both[1]["notes"].size() == 2);
  CHECK(both[1]["note_locations"] ==
        Json::array({{{"file", duplicates}, {"line", 11}, {"column", 9}}, nullptr}));
  const auto typo =
      Json::parse(run_cli("validate --format json tests/data/invalid/unknown_key.yaml").out);
  REQUIRE(!typo.empty());
  CHECK(!typo[0]["notes"].empty());
  CHECK_FALSE(typo[0].contains("note_locations"));
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
    CHECK(contains(result.out, "interface classes\n  inputs (built-in)\n"));
    CHECK(contains(result.out, "\n  soccer.WorldLink (plugin soccer ("));
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

TEST_CASE("arbiter run prints a step's events in the order they happened", "[run][cli][soccer]") {
  // The world reports the shot in the input pass; the goalie behaviour then sees it and pre-empts
  // its plan to dive, and the dive state reports the dive, under its own name.
  const auto result = run_cli("run configs/soccer/goalie.yaml --steps 210");
  REQUIRE(result.exit_code == 0);
  CHECK(contains(result.out,
                 "step  201  world: shot on goal\n"
                 "step  201  goalie: monitor_ball ended (pre-empted by dive)\n"
                 "step  201  goalie: dive (cycle 201; queued: monitor_ball)\n"
                 "step  201  goalie/dive: goalie dives left\n"));
  CHECK(contains(result.out,
                 "step   11  goalie: wait_for_button ended (proceeded)\n"
                 "step   11  goalie: walk_to_pose {x: -4.2, y: 0.0, theta: 0.0} "
                 "(cycle 11; queued: monitor_ball)\n"));
}

TEST_CASE("every command's help ends with examples", "[help][cli]") {
  for (const std::string command :
       {"", "validate", "run", "dump", "explain", "plugins", "schema"}) {
    DYNAMIC_SECTION("arbiter " << command << " --help") {
      const auto result = run_cli(command + " --help");
      CHECK(result.exit_code == 0);
      // The heading says where the files the examples name are.
      CHECK(contains(result.out, "\nExamples (run them "));
      CHECK(contains(result.out, "where their files are"));
      CHECK(contains(result.out, "\n  arbiter " + command));
      CHECK(contains(result.out, "Exit codes: 0 ok"));
    }
  }
  CHECK(contains(run_cli("validate --help").out, "redundant-inhibition"));
}

TEST_CASE("a mistyped option gets the option meant, and unexpected words are echoed in order",
          "[cli]") {
  const auto result = run_cli("run " + quoted(kSourceDir / "configs/paper/walk_and_kick.yaml") +
                              " --stesp 5 extra");
  CHECK(result.exit_code == 2);
  CHECK(result.err ==
        "arbiter run: these arguments were not expected: --stesp 5 extra\n"
        "  note: '--stesp': did you mean '--steps'?\n"
        "Run 'arbiter run --help' for more information.\n");
  const auto command = run_cli("valdate configs/paper/walk_and_kick.yaml");
  CHECK(command.exit_code == 2);
  CHECK(contains(command.err, "  note: 'valdate': did you mean 'validate'?\n"));
  // Help asked of a command there is not: the word is told, not the help of every command.
  const auto help = run_cli("valdate --help");
  CHECK(help.exit_code == 2);
  CHECK(contains(help.err, "  note: 'valdate': did you mean 'validate'?\n"));
  CHECK(help.out.empty());
  CHECK(run_cli("validate --help").exit_code == 0);
  // Every usage error is said by its command, with the help of that command.
  const auto missing = run_cli("run");
  CHECK(missing.exit_code == 2);
  CHECK(missing.err ==
        "arbiter run: FILE is required\nRun 'arbiter run --help' for more information.\n");
  const auto no_value = run_cli("new plugin");
  CHECK(no_value.exit_code == 2);
  CHECK(no_value.err ==
        "arbiter new plugin: NAME is required\nRun 'arbiter new plugin --help' "
        "for more information.\n");
  const auto no_command = run_cli("");
  CHECK(no_command.exit_code == 2);
  CHECK(no_command.err ==
        "arbiter: say which command to run\nRun 'arbiter --help' for more information.\n");
}

TEST_CASE("a --tolerance that is not a finite number from 0 is a usage error, said plainly",
          "[cli]") {
  const auto test_file =
      quoted(kSourceDir / "tests/scenarios/paper/scripted_levels_by_step.test.yaml");
  for (const std::string tolerance : {"nan", "inf", "-1", "1e400", "x"}) {
    INFO(tolerance);
    const auto test = run_cli("test " + test_file + " --tolerance " + tolerance);
    CHECK(test.exit_code == 2);
    CHECK(contains(test.err,
                   "--tolerance: must be a finite number from 0, found '" + tolerance + "'"));
    CHECK(test.out.empty());
    const auto diff = run_cli("diff " + test_file + " " + test_file + " --tolerance " + tolerance);
    CHECK(diff.exit_code == 2);
    CHECK(contains(diff.err,
                   "--tolerance: must be a finite number from 0, found '" + tolerance + "'"));
  }
  CHECK(run_cli("test " + test_file + " --tolerance 0.5").exit_code == 0);
}

TEST_CASE("plugins and schema refuse --builtin with --load, which one of them would drop",
          "[plugins][cli]") {
  for (const std::string command : {"plugins", "schema"}) {
    INFO(command);
    const auto result = run_cli(command + " --load soccer --builtin");
    CHECK(result.exit_code == 2);
    CHECK(contains(result.err, "--load excludes --builtin"));
    CHECK(result.out.empty());
  }
}

TEST_CASE("dump --layer refuses an empty name, and shows an unknown one escaped", "[dump][cli]") {
  const std::string config = quoted(kSourceDir / "configs/paper/walk_and_kick.yaml");
  const auto empty = run_cli("dump " + config + " --layer ''");
  CHECK(empty.exit_code == 2);
  CHECK(empty.out.empty());
  CHECK(contains(empty.err, "--layer: a layer's name cannot be empty"));
  const auto escaped = run_cli("dump " + config + " --layer \"$(printf 'a\\033[31m')\"");
  CHECK(escaped.exit_code == 2);
  CHECK(contains(escaped.err, "no layer 'a\\x1b[31m' in "));
  CHECK_FALSE(contains(escaped.err, "\x1b"));
}

TEST_CASE("an option that names a file refuses an empty name instead of leaving the file out",
          "[cli]") {
  const TempDir dir;
  const std::string config = quoted(kSourceDir / "configs/paper/walk_and_kick.yaml");
  const auto trace = dir / "run.jsonl";
  REQUIRE(run_cli("run " + config + " --steps 3 -q --trace " + quoted(trace)).exit_code == 0);
  const std::string test_file =
      quoted(kSourceDir / "tests/scenarios/paper/scripted_levels_by_step.test.yaml");
  for (const auto& [command, option] : std::vector<std::pair<std::string, std::string>>{
           {"run " + config + " --steps 3 -q", "--trace"},
           {"run " + config + " --steps 3 -q", "--record"},
           {"run " + config + " --steps 3 -q", "--inputs"},
           {"plot " + quoted(trace), "-o"},
           {"test " + test_file, "--junit"},
       }) {
    INFO(command << " " << option);
    const auto result = run_cli(command + " " + option + " ''");
    CHECK(result.exit_code == 2);
    CHECK(contains(result.err, "an empty name names no file"));
  }
}

TEST_CASE("a step number that is 0, not a number or past 2^64 is a usage error that says so",
          "[explain][cli]") {
  const TempDir dir;
  const std::string config = quoted(kSourceDir / "configs/paper/walk_and_kick.yaml");
  const auto trace = quoted(dir / "run.jsonl");
  REQUIRE(run_cli("run " + config + " --steps 3 -q --trace " + trace).exit_code == 0);
  const std::string explain = "explain " + config + " --trace " + trace + " kick_ball --step ";
  for (const std::string step : {"0", "-1", "1.5", "x"}) {
    INFO(step);
    const auto result = run_cli(explain + step);
    CHECK(result.exit_code == 2);
    CHECK(contains(result.err, "--step: must be a step number, 1 or more, found '" + step + "'"));
  }
  const std::string huge = "99999999999999999999999";
  auto result = run_cli(explain + huge);
  CHECK(result.exit_code == 2);
  CHECK(contains(
      result.err,
      "--step: must be a step number, at most 18446744073709551615, found '" + huge + "'"));
  result =
      run_cli("seek " + config + " --trace " + trace + " 'kick_ball activates' --from " + huge);
  CHECK(result.exit_code == 2);
  CHECK(contains(result.err, "--from: must be a step number, at most"));
  CHECK(run_cli(explain + "2").exit_code == 0);
}

TEST_CASE("plot and test refuse to write their output over a file they read", "[cli]") {
  const TempDir dir;
  const auto config = dir / "robot.yaml";
  fs::copy_file(kSourceDir / "configs/paper/walk_and_kick.yaml", config);
  const std::string config_text = read_text(config);
  const auto trace = dir / "run.jsonl";
  REQUIRE(run_cli("run " + quoted(config) + " --steps 3 -q --trace " + quoted(trace)).exit_code ==
          0);
  const std::string trace_text = read_text(trace);
  auto result = run_cli("plot " + quoted(trace) + " -o " + quoted(trace));
  CHECK(result.exit_code == 2);
  CHECK(contains(result.err, "is the trace being plotted"));
  CHECK(read_text(trace) == trace_text);

  const auto test_file = dir / "robot.test.yaml";
  const std::string test_text = "arbiter_test: 1\nconfig: robot.yaml\nexpect: []\nsteps: 2\n";
  write_text(test_file, test_text);
  result = run_cli("test " + quoted(test_file) + " --junit " + quoted(test_file));
  CHECK(result.exit_code == 2);
  CHECK(contains(result.err, "is a test file"));
  CHECK(read_text(test_file) == test_text);
  result = run_cli("test " + quoted(test_file) + " --junit " + quoted(config));
  CHECK(result.exit_code == 2);
  CHECK(contains(result.err, "names ('"));
  CHECK(read_text(config) == config_text);
  CHECK(run_cli("test " + quoted(test_file) + " --junit " + quoted(dir / "junit.xml")).exit_code ==
        0);
}

TEST_CASE("arbiter validate exits 0 when valid, 1 when invalid and 2 on a usage error", "[cli]") {
  SECTION("a valid config") {
    const auto result = run_cli("validate " + quoted(kDataDir / "valid" / "twin.yaml"));
    CHECK(result.exit_code == 0);
  }
  SECTION("an invalid config prints its diagnostics to stderr") {
    const auto result = run_cli("validate " + quoted(kDataDir / "invalid" / "unknown_key.yaml"));
    CHECK(result.exit_code == 1);
    CHECK(result.err.find("unknown_key.yaml:") != std::string::npos);
    CHECK(result.err.find("error[unknown-key]: unknown key") != std::string::npos);
  }
  SECTION("one invalid config among valid ones fails the run") {
    const auto result = run_cli("validate " + quoted(kDataDir / "valid" / "twin.yaml") + " " +
                                quoted(kDataDir / "invalid" / "self_inhibition.yaml"));
    CHECK(result.exit_code == 1);
    CHECK(result.err.find("cannot inhibit itself") != std::string::npos);
  }
  SECTION("an unknown option is a usage error") {
    const auto result =
        run_cli("validate --no-such-option " + quoted(kDataDir / "valid" / "twin.yaml"));
    CHECK(result.exit_code == 2);
  }
  SECTION("a missing command is a usage error") {
    CHECK(run_cli("").exit_code == 2);
  }
  SECTION("a --plugin-path that is missing, or cannot be looked at, is a usage error") {
    const auto valid = quoted(kDataDir / "valid" / "twin.yaml");
    const auto missing = run_cli("--plugin-path /no/such/folder validate " + valid);
    CHECK(missing.exit_code == 2);
    CHECK(missing.err.find("Directory does not exist: /no/such/folder") != std::string::npos);
    // A name longer than a path may be: the check cannot look, and says why (it threw before).
    const auto too_long =
        run_cli("--plugin-path /tmp/" + std::string(5000, 'a') + " validate " + valid);
    CHECK(too_long.exit_code == 2);
    CHECK(too_long.err.find("File name too long") != std::string::npos);
  }
}

TEST_CASE("arbiter validate colours its diagnostics only when asked or in a terminal", "[cli]") {
  const std::string config = quoted(kDataDir / "invalid" / "unknown_key.yaml");
  const std::string escape = "\x1b[";
  SECTION("--color always colours the severity, the code and the underline") {
    const auto result = run_cli("--color always validate " + config);
    CHECK(result.exit_code == 1);
    CHECK(result.err.find("\x1b[1;31merror[unknown-key]\x1b[0m") != std::string::npos);
    CHECK(result.err.find("\x1b[1;32m^~~~\x1b[0m") != std::string::npos);
  }
  SECTION("auto leaves a pipe uncoloured, with the source line and its underline") {
    const auto result = run_cli("validate " + config);
    CHECK(result.err.find(escape) == std::string::npos);
    CHECK(result.err.find("3 | rate: 15\n  | ^~~~\n") != std::string::npos);
  }
  SECTION("--color never, given after the command, too") {
    const auto result = run_cli("validate " + config + " --color never");
    CHECK(result.exit_code == 1);
    CHECK(result.err.find(escape) == std::string::npos);
  }
  SECTION("anything else is a usage error") {
    CHECK(run_cli("--color sometimes validate " + config).exit_code == 2);
  }
}

namespace {

using AddMetadata = std::function<void(const std::string&,
                                       const std::vector<std::pair<std::string, std::string>>&)>;

// The recording `from` written again to `to`, by hand, records outside chunks, as MCAP allows
// (https://mcap.dev/spec), with its metadata, and its messages but for the log, each given to
// `edit` first: it may change the message's data, drop it (false), and add metadata before it.
void rewrite_recording(
    const fs::path& from, const fs::path& to,
    const std::function<bool(const mcap::Record&, std::string& data, const AddMetadata&)>& edit) {
  std::ifstream in(from, std::ios::binary);
  mcap::Reader reader(in);
  std::string out(mcap::kMagic);
  const auto number = [](std::string& to, std::uint64_t value, int bytes) {
    for (int i = 0; i < bytes; ++i) to += static_cast<char>((value >> (8 * i)) & 0xff);
  };
  const auto text = [&](std::string& to, std::string_view value) {
    number(to, value.size(), 4);
    to += value;
  };
  const auto add = [&](std::uint8_t op, const std::string& content) {
    out += static_cast<char>(op);
    number(out, content.size(), 8);
    out += content;
  };
  const AddMetadata metadata = [&](const std::string& name,
                                   const std::vector<std::pair<std::string, std::string>>& map) {
    std::string content;
    text(content, name);
    std::string entries;
    for (const auto& [key, value] : map) {
      text(entries, key);
      text(entries, value);
    }
    text(content, entries);
    add(mcap::kMetadata, content);
  };
  std::string content;
  text(content, "arbiter");
  text(content, "arbiter");
  add(mcap::kHeader, content);
  std::map<std::string, std::uint16_t> channels;
  for (const char* topic : {"/arbiter/header", "/arbiter/step", "/arbiter/inputs"}) {
    const auto id = static_cast<std::uint16_t>(channels.size() + 1);
    content.clear();
    number(content, id, 2);
    text(content, topic);
    text(content, "jsonschema");
    text(content, "{}");
    add(mcap::kSchema, content);
    content.clear();
    number(content, id, 2);
    number(content, id, 2);
    text(content, topic);
    text(content, "json");
    number(content, 0, 4);  // no channel metadata
    add(mcap::kChannel, content);
    channels[topic] = id;
  }
  mcap::Record record;
  while (reader.next(record)) {
    if (record.kind == mcap::Record::Kind::kMetadata) {
      metadata(record.name, record.metadata);
      continue;
    }
    if (channels.count(record.topic) == 0) continue;  // the log is not needed to replay
    std::string data = record.data;
    if (!edit(record, data, metadata)) continue;
    content.clear();
    number(content, channels.at(record.topic), 2);
    number(content, 0, 4);  // sequence
    number(content, record.log_time, 8);
    number(content, record.log_time, 8);
    content += data;
    add(mcap::kMessage, content);
  }
  REQUIRE(reader.error().empty());
  add(mcap::kDataEnd, std::string(4, '\0'));  // no CRC
  add(mcap::kFooter, std::string(20, '\0'));  // no summary
  out += mcap::kMagic;
  std::ofstream(to, std::ios::binary) << out;
}

// The test plugins tests/data/replay/counter.yaml loads.
const std::string kCounterPlugins = std::string(" --plugin-path ") + ARBITER_TEST_PLUGIN_DIR;

/// A recording of tests/data/replay/counter.yaml's first 5 steps, at `path`.
void record_counter(const fs::path& path) {
  REQUIRE(run_cli("run tests/data/replay/counter.yaml --steps 5 -q --record " + quoted(path) +
                  kCounterPlugins)
              .exit_code == 0);
}

}  // namespace

TEST_CASE("view --step of a step a trace lacks names the steps around it", "[view][cli]") {
  const TempDir dir;
  const std::string config = quoted(kSourceDir / "configs/paper/walk_and_kick.yaml");
  const auto whole = dir / "whole.jsonl";
  REQUIRE(run_cli("run " + config + " --steps 6 -q --trace " + quoted(whole)).exit_code == 0);
  // Steps 3, 4 and 6 of it: a trace missing the steps a writer that fell behind dropped.
  std::vector<std::string> lines;
  std::istringstream in(read_text(whole));
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  REQUIRE(lines.size() == 7);
  const auto gap = dir / "gap.jsonl";
  write_text(gap, lines[0] + "\n" + lines[3] + "\n" + lines[4] + "\n" + lines[6] + "\n");
  const auto view = [&](int step) {
    return run_cli("view " + config + " --trace " + quoted(gap) + " --serve 0 --step " +
                   std::to_string(step));
  };
  auto result = view(5);
  CHECK(result.exit_code == 2);
  CHECK(contains(result.err,
                 "--step 5: " + gap.string() + " has no step 5: it goes from step 4 to step 6\n"));
  result = view(1);
  CHECK(result.exit_code == 2);
  CHECK(contains(result.err, "--step 1: " + gap.string() + " has steps 3 to 6\n"));
}

TEST_CASE("a recording whose first step was dropped replays up to its gap", "[replay][cli]") {
  const TempDir dir;
  const auto whole = dir / "run.mcap";
  const auto gap = dir / "gap.mcap";
  // Its interface layer declares an actuator, whose recorded input must be there to compile.
  record_counter(whole);
  // The recording again, with step 1 dropped as a recorder whose writer fell behind drops it.
  rewrite_recording(whole, gap,
                    [](const mcap::Record& record, std::string& data, const AddMetadata& metadata) {
                      if (data.rfind("{\"step\": 1,", 0) != 0) return true;
                      if (record.topic == "/arbiter/step") {
                        metadata("arbiter.gap", {{"after_step", "0"}, {"dropped", "1"}});
                      }
                      return false;
                    });
  const auto replayed = run_cli("replay " + quoted(gap) + kCounterPlugins);
  INFO(replayed.err);
  CHECK_FALSE(contains(replayed.err, "the recording has no input"));
  CHECK(contains(replayed.err,
                 "warning: the recording dropped 1 steps after step 0; the replay "
                 "runs up to there"));
  CHECK(contains(replayed.out, "replayed 0 steps"));
}

TEST_CASE("a recorded input of the wrong type is located in the recording's config, as recorded",
          "[replay][cli]") {
  const TempDir dir;
  const auto whole = dir / "run.mcap";
  const auto bad = dir / "bad.mcap";
  record_counter(whole);
  // The count of step 3 recorded as a string.
  rewrite_recording(whole, bad, [](const mcap::Record& record, std::string& data, const auto&) {
    if (record.topic == "/arbiter/inputs" && data.rfind("{\"step\": 3,", 0) == 0) {
      data = std::regex_replace(data, std::regex(R"("value": [-+.0-9eE]+)"), R"("value": "three")",
                                std::regex_constants::format_first_only);
    }
    return true;
  });
  const auto replayed = run_cli("replay " + quoted(bad) + kCounterPlugins);
  INFO(replayed.err);
  CHECK(replayed.exit_code == 1);
  // Named by the recording and the config's name as recorded, not by where the replay put the
  // recorded config's files (a directory that does not exist).
  CHECK(contains(replayed.err, bad.string() +
                                   ": tests/data/replay/counter.yaml:11:7: error: recorded input "
                                   "'count' at step 3 is \"three\""));
  CHECK_FALSE(contains(replayed.err, "arbiter_replay_"));
  // No config was edited: the reason says that the two disagree, not what an edit must keep.
  CHECK(contains(replayed.err, "the recording and the config replayed disagree on its type"));
}

namespace {

// The `/arbiter/scene` messages of a recording, and what a viewer shows after each: per step
// that drew, every primitive of the entities shown then, as its JSON, under its kind and frame.
struct SceneShown {
  std::vector<std::pair<std::uint64_t, Json>> messages;  // with their steps
  std::map<std::uint64_t, std::vector<Json>> by_step;
};

// A number rounded, for an order that two pictures a rounding apart share.
Json coarse(const Json& value) {
  if (value.is_number_float()) return std::round(value.get<double>() * 1e3) / 1e3;
  if (!value.is_structured()) return value;
  Json out = value;
  for (auto& item : out) item = coarse(item);
  return out;
}

SceneShown scene_shown(const fs::path& recording) {
  std::ifstream in(recording, std::ios::binary);
  mcap::Reader reader(in);
  mcap::Record record;
  SceneShown shown;
  std::map<std::string, Json> entities;  // by id, as a viewer keeps them
  std::uint64_t step = 0;
  while (reader.next(record)) {
    if (record.kind != mcap::Record::Kind::kMessage) continue;
    if (record.topic == "/arbiter/step")
      step = Json::parse(record.data)["step"].get<std::uint64_t>();
    if (record.topic != "/arbiter/scene") continue;
    const auto message = Json::parse(record.data);
    shown.messages.emplace_back(step, message);
    for (const auto& deletion : message["deletions"]) {
      if (deletion["type"] == 1) entities.clear();
      if (deletion["type"] == 0) entities.erase(deletion["id"].get<std::string>());
    }
    for (const auto& entity : message["entities"]) entities[entity["id"]] = entity;
    auto& primitives = shown.by_step[step];
    primitives.clear();
    for (const auto& [id, entity] : entities) {
      for (const char* kind :
           {"arrows", "cubes", "spheres", "cylinders", "lines", "triangles", "texts", "models"}) {
        for (const auto& primitive : entity[kind]) {
          primitives.push_back({{"kind", kind}, {"frame", entity["frame_id"]}, {"is", primitive}});
        }
      }
    }
    std::sort(primitives.begin(), primitives.end(), [](const Json& a, const Json& b) {
      const auto ka = coarse(a).dump(), kb = coarse(b).dump();
      return ka != kb ? ka < kb : a.dump() < b.dump();
    });
  }
  REQUIRE(reader.error().empty());
  return shown;
}

// A message without its times: a run and its replay started at different times.
Json untimed(Json message) {
  if (!message.is_structured()) return message;
  if (message.is_object()) message.erase("timestamp");
  for (auto& item : message) item = untimed(item);
  return message;
}

// Whether two messages or primitives are alike, their numbers within `tolerance`.
bool alike(const Json& a, const Json& b, double tolerance) {
  if (a.is_number() && b.is_number()) {
    return std::abs(a.get<double>() - b.get<double>()) <= tolerance;
  }
  if (a.type() != b.type() || a.size() != b.size()) return false;
  if (a.is_object()) {
    for (auto it = a.begin(); it != a.end(); ++it) {
      if (!b.contains(it.key()) || !alike(it.value(), b[it.key()], tolerance)) return false;
    }
    return true;
  }
  if (a.is_array()) {
    for (std::size_t i = 0; i < a.size(); ++i) {
      if (!alike(a[i], b[i], tolerance)) return false;
    }
    return true;
  }
  return a == b;
}

// The scene messages of a replay of `config`'s recorded run of `steps` steps (`what_if`: with
// the config again, as a what-if), and those of the run.
std::pair<SceneShown, SceneShown> replayed_scene(const std::string& config, int steps,
                                                 bool what_if) {
  const auto dir =
      fs::temp_directory_path() / ("arbiter_replay_scene_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const auto run = dir / "run.mcap";
  const auto replay = dir / "replay.mcap";
  REQUIRE(run_cli(fmt::format("run {} --steps {} -q --record {}", config, steps, quoted(run)))
              .exit_code == 0);
  const auto replayed = run_cli("replay " + quoted(run) + " --record " + quoted(replay) +
                                (what_if ? " --config " + config : std::string()));
  INFO(replayed.err);
  REQUIRE(replayed.exit_code == 0);
  auto shown = std::make_pair(scene_shown(run), scene_shown(replay));
  fs::remove_all(dir);
  return shown;
}

}  // namespace

TEST_CASE("a replay draws the recorded picture: its recording shows what the run's showed",
          "[replay][cli][soccer]") {
  // The soccer demo, long enough for a kick and a goal: texts come and go, the ball's motion
  // arrow too; the goalie, whose walks draw their targets.
  const auto [config, steps] = GENERATE(std::make_pair("configs/soccer/walk_and_kick.yaml", 300),
                                        std::make_pair("configs/soccer/goalie.yaml", 120));
  INFO(config);
  const auto [original, again] = replayed_scene(config, steps, false);
  // The soccer world draws in every step.
  REQUIRE(original.by_step.size() == static_cast<std::size_t>(steps));
  REQUIRE(again.by_step.size() == original.by_step.size());
  // An arrow is written as a pose and lengths, each rounded to 1e-6, and drawn again from them:
  // its numbers come back within a rounding or two.
  constexpr double kRounding = 3e-6;
  for (const auto& [step, primitives] : original.by_step) {
    INFO("step " << step);
    REQUIRE(again.by_step.count(step) == 1);
    const auto& replayed_primitives = again.by_step.at(step);
    REQUIRE(replayed_primitives.size() == primitives.size());
    for (std::size_t i = 0; i < primitives.size(); ++i) {
      INFO(primitives[i].dump() << "\nreplayed: " << replayed_primitives[i].dump());
      CHECK(alike(primitives[i], replayed_primitives[i], kRounding));
    }
  }
  // And the messages as the run wrote them (but for their times, the replay's own): the whole
  // pictures at the same steps, what does not move and what does in the same entities, in the
  // same order.
  REQUIRE(again.messages.size() == original.messages.size());
  for (std::size_t i = 0; i < original.messages.size(); ++i) {
    const auto& [step, message] = original.messages[i];
    INFO("step " << step << ": " << message.dump()
                 << "\nreplayed: " << again.messages[i].second.dump());
    CHECK(again.messages[i].first == step);
    CHECK(alike(untimed(message), untimed(again.messages[i].second), kRounding));
  }
}

TEST_CASE("a what-if replay draws the recorded picture and what its behaviours draw beside it",
          "[replay][cli][soccer]") {
  // The goalie's walks draw their targets: in the recorded picture, and again by the what-if's
  // own walks.
  const auto [original, again] = replayed_scene("configs/soccer/goalie.yaml", 60, true);
  REQUIRE(again.by_step.size() == original.by_step.size());
  std::size_t more = 0;
  for (const auto& [step, primitives] : original.by_step) {
    INFO("step " << step);
    const auto& replayed_primitives = again.by_step.at(step);
    // Every recorded primitive is there.
    for (const auto& primitive : primitives) {
      CHECK(std::any_of(replayed_primitives.begin(), replayed_primitives.end(),
                        [&](const Json& p) { return alike(primitive, p, 3e-6); }));
    }
    more += replayed_primitives.size() - primitives.size();
  }
  CHECK(more > 0);
}
TEST_CASE("a scene message that a recorder does not write stops a replay at its step and field",
          "[replay]") {
  // One line of two points, as SceneUpdates writes it; `point` is the second point's y.
  const auto message = [](const std::string& id, const std::string& point,
                          const std::string& more = "") {
    return R"({"deletions":[{"timestamp":{"sec":0,"nsec":0},"type":1,"id":""}],"entities":[)"
           R"({"timestamp":{"sec":0,"nsec":0},"frame_id":"field","id":")" +
           id +
           R"(","lifetime":{"sec":0,"nsec":0},"frame_locked":false,"metadata":[],"arrows":[],)"
           R"("cubes":[],"spheres":[],"cylinders":[],"lines":[{"type":0,"pose":{"position":)"
           R"({"x":0,"y":0,"z":0},"orientation":{"x":0,"y":0,"z":0,"w":1}},"thickness":0.05,)"
           R"("scale_invariant":false,"points":[{"x":0,"y":0,"z":0},{"x":1,"y":)" +
           point +
           R"(,"z":0}],"color":{"r":1,"g":1,"b":1,"a":1},"colors":[],"indices":[]}],)"
           R"("triangles":[],"texts":[],"models":[])" +
           more + "}]}";
  };
  const auto error = [](const std::string& scene) {
    RecordedInputs inputs;
    Diagnostics diagnostics;
    const bool loaded = inputs.load(7, "", diagnostics, scene, {"run.mcap"});
    return loaded ? std::string("loaded") : format(diagnostics);
  };
  CHECK(error(message("field/still", "2")) == "loaded");
  CHECK(contains(error(message("field/still", "\"two\"")),
                 "run.mcap: error: the /arbiter/scene message of step 7: "
                 "entities[0].lines[0].points[1].y: expected a number"));
  CHECK(contains(error(message("robot/still", "2")),
                 "entities[0].id: expected 'field/still' or 'field/moving', not 'robot/still'"));
  CHECK(contains(error(message("field/still", "2", R"(,"extra":1)")), "loaded"));
  CHECK(contains(error(R"({"deletions":[{"type":2}],"entities":[]})"),
                 "deletions[0].type: expected 0 (an id) or 1 (all), not 2"));
  CHECK(contains(error("{\"deletions\": ["), "step 7: not a JSON object"));
  CHECK(contains(error(R"({"deletions":[],"entities":[{"frame_id":"f","id":"f/moving"}]})"),
                 "entities[0].arrows: expected an array"));
}

namespace {

// Each reading a quarter of a second after the one before, however fast the run goes.
class QuarterSecondClock : public StepClock {
 public:
  double now() override { return t += 0.25; }
  double t = 0.0;
};

std::string clock_config(int rate_hz, bool second_behaviour) {
  std::string text = fmt::format(
      "arbiter: 1\nname: clock\nrate_hz: {}\nlayers:\n  - name: control\n    actuators:\n"
      "      x: {{type: double}}\n    behaviours:\n"
      "      a: {{type: scripted, params: {{activation: 1.0, writes: {{x: 1.0}}}}}}\n",
      rate_hz);
  if (second_behaviour) text += "      b: {type: scripted, params: {activation: 0.5}}\n";
  return text;
}

struct Logged {
  std::string what;   // "step N" or the topic
  double time = 0.0;  // the log time, in seconds after the first header's
  double t = -1.0;    // a step's "t"
};

// The messages of a recording of 10 steps of clock_config(10), reloaded with clock_config(20)
// before the sixth; and the reload's after_step.
std::pair<std::vector<Logged>, std::uint64_t> clock_recording(bool paced) {
  const auto dir = fs::temp_directory_path() /
                   ("arbiter_clock_" + std::to_string(::getpid()) + (paced ? "_paced" : ""));
  fs::create_directories(dir);
  const auto config = dir / "clock.yaml";
  Registry registry = make_test_registry();
  write_text(config, clock_config(10, false));
  Reloader reloader(registry);
  Diagnostics diagnostics;
  auto program = reloader.load(config.string(), diagnostics);
  INFO(format(diagnostics));
  REQUIRE(program);
  Manager manager(std::move(*program));
  QuarterSecondClock clock;
  manager.set_clock(&clock);
  const auto path = dir / "run.mcap";
  {
    RecordingInfo info;
    info.version = "test";
    info.paced = paced;
    Recorder recorder(path.string(), info, Recorder::kSlots, RingFull::kWaitForWriter);
    REQUIRE(recorder.ok());
    manager.add_observer(recorder);
    for (int i = 0; i < 10; ++i) {
      if (i == 5) {
        write_text(config, clock_config(20, true));
        REQUIRE(reloader.reload(manager).staged);
      }
      manager.step();
    }
    manager.finish();
  }
  std::ifstream in(path, std::ios::binary);
  mcap::Reader reader(in);
  mcap::Record record;
  std::vector<Logged> times;
  std::uint64_t start = 0, after_step = 0;
  while (reader.next(record)) {
    if (record.kind != mcap::Record::Kind::kMessage || record.topic == "/arbiter/inputs") continue;
    if (times.empty()) start = record.log_time;
    const auto message = Json::parse(record.data);
    if (message.contains("after_step")) after_step = message["after_step"].get<std::uint64_t>();
    Logged logged;
    logged.what = record.topic;
    logged.time = static_cast<double>(record.log_time - start) / 1e9;
    if (record.topic == "/arbiter/step") {
      logged.what = fmt::format("step {}", message["step"].get<std::uint64_t>());
      logged.t = message["t"].get<double>();
    }
    times.push_back(logged);
  }
  REQUIRE(reader.error().empty());
  fs::remove_all(dir);
  return {times, after_step};
}

}  // namespace

TEST_CASE("a recording is logged on the run's own clock", "[record]") {
  SECTION("not paced: step / rate_hz after the start, at the rate of the program running") {
    const auto [times, after] = clock_recording(false);
    REQUIRE(after >= 5);
    std::vector<std::pair<std::string, double>> expected{{"/arbiter/header", 0.0}};
    for (std::uint64_t step = 1; step <= after; ++step) {
      expected.emplace_back(fmt::format("step {}", step), step / 10.0);
    }
    expected.emplace_back("/arbiter/header", after / 10.0);
    for (std::uint64_t step = after + 1; step <= 10; ++step) {
      expected.emplace_back(fmt::format("step {}", step), after / 10.0 + (step - after) / 20.0);
    }
    REQUIRE(times.size() == expected.size());
    for (std::size_t i = 0; i < times.size(); ++i) {
      INFO(times[i].what << " at " << times[i].time);
      CHECK(times[i].what == expected[i].first);
      CHECK(times[i].time == Approx(expected[i].second).margin(1e-8));
    }
  }
  SECTION("paced: the wall clock of each step, its \"t\" after the start") {
    const auto [times, after] = clock_recording(true);
    REQUIRE(times.size() == 12);  // the two headers and ten steps
    double last = 0.0;
    for (const auto& logged : times) {
      if (logged.t < 0.0) continue;
      INFO(logged.what);
      CHECK(logged.time == Approx(logged.t).margin(1e-8));
      CHECK(logged.time > last + 0.2);  // a quarter of a second, or more, after the one before
      last = logged.time;
    }
  }
}
