// `arbiter test` end to end: scenario files that fail or are invalid print the approved output
// (tests/data/scenarios/*/NAME.test.yaml beside NAME.expected), exit codes, directories, and the
// JUnit XML that CI systems read.

#include <unistd.h>
#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "arbiter/scenario.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using namespace arbiter;

namespace {

const fs::path kSourceDir = ARBITER_SOURCE_DIR;
const fs::path kScenarios = kSourceDir / "tests" / "data" / "scenarios";

/// Runs `arbiter ARGUMENTS` in the source directory, so that paths in the output are relative;
/// `environment` (NAME=VALUE ...) before it.
test::CliResult run_cli(const std::string& arguments, const std::string& environment = "") {
  return test::run_captured("cd \"" + kSourceDir.string() + "\" && " + environment + "\"" +
                            std::string(ARBITER_CLI) + "\" " + arguments);
}

std::vector<fs::path> scenarios_in(const fs::path& dir) {
  return test::files_in(dir, [](const fs::path& path) { return is_scenario_file(path.string()); });
}

fs::path expected_of(const fs::path& scenario) {
  std::string name = scenario.filename().string();
  name.resize(name.find(".test."));
  return scenario.parent_path() / (name + ".expected");
}

/// Compares what `arbiter test` printed, and its exit code, with the approved output beside the
/// scenario (or rewrites it under ARBITER_UPDATE_GOLDEN).
void check_against_golden(const fs::path& scenario, const test::CliResult& result) {
  const std::string actual =
      result.out + result.err + "exit " + std::to_string(result.exit_code) + "\n";
  if (test::update_golden()) {
    test::write_text(expected_of(scenario), actual);
    WARN("rewrote " << expected_of(scenario).string());
  } else {
    CHECK(actual == test::read_text(expected_of(scenario)));
  }
}

std::size_t count(const std::string& text, const std::string& part) {
  std::size_t n = 0;
  for (auto at = text.find(part); at != std::string::npos; at = text.find(part, at + 1)) ++n;
  return n;
}

}  // namespace

TEST_CASE("every failing or invalid scenario prints the approved output and exit code",
          "[scenario]") {
  std::size_t cases = 0;
  for (const char* kind : {"failing", "invalid"}) {
    for (const auto& path : scenarios_in(kScenarios / kind)) {
      ++cases;
      const std::string relative = fs::relative(path, kSourceDir).string();
      DYNAMIC_SECTION(relative) {
        const auto result = run_cli("test " + relative);
        check_against_golden(path, result);
        CHECK(result.exit_code == (std::string(kind) == "failing" ? 1 : 2));
      }
    }
  }
  CHECK(cases >= 8);
}

TEST_CASE(
    "recording-based scenarios: the demo replays identically, edits fail with the diff summary, "
    "bad replays are located errors",
    "[scenario][replay]") {
  // The recording is made now, beside copies of the test files (tests/cli/record_scenarios.sh),
  // and the tests run there with the paths they have in the source tree.
  const test::TempDir scratch;
  const fs::path out = scratch.path() / "arbiter_recorded_scenarios";
  const auto made = test::run_captured(
      "bash \"" + (kSourceDir / "tests/cli/record_scenarios.sh").string() + "\" \"" + ARBITER_CLI +
      "\" \"" + kSourceDir.string() + "\" \"" + out.string() + "\"");
  INFO(made.out << made.err);
  REQUIRE(made.exit_code == 0);
  const auto run_there = [&](const std::string& arguments) {
    return test::run_captured("cd \"" + out.string() + "\" && \"" + std::string(ARBITER_CLI) +
                              "\" " + arguments);
  };
  const auto passing = run_there("test tests/scenarios/recorded");
  INFO(passing.out << passing.err);
  CHECK(passing.exit_code == 0);
  CHECK(count(passing.out, "PASS ") ==
        scenarios_in(kSourceDir / "tests/scenarios/recorded").size());

  std::size_t cases = 0;
  for (const auto& path : scenarios_in(kScenarios / "recorded")) {
    ++cases;
    const std::string relative = fs::relative(path, kSourceDir).string();
    DYNAMIC_SECTION(relative) {
      const auto result = run_there("test " + relative);
      check_against_golden(path, result);
      CHECK(result.exit_code != 0);
    }
  }
  CHECK(cases >= 8);
}

TEST_CASE(
    "a scenario replays each of two interface layers from its own recorded inputs and reports",
    "[scenario][replay]") {
  const test::TempDir scratch;
  const fs::path dir = scratch.path() / "arbiter_two_counters_scenario";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string cli =
      std::string("\"") + ARBITER_CLI + "\" --plugin-path \"" + ARBITER_TEST_PLUGIN_DIR + "\" ";
  const std::string config = (kSourceDir / "tests/data/replay/two_counters.yaml").string();
  const auto recorded = test::run_captured(cli + "run \"" + config + "\" --steps 6 -q --record \"" +
                                           (dir / "two.mcap").string() + "\"");
  INFO(recorded.out << recorded.err);
  REQUIRE(recorded.exit_code == 0);
  test::write_text(dir / "two.test.yaml", "arbiter_test: 1\nconfig: " + config +
                                              "\nreplay: two.mcap\nexpect: identical\n");
  const auto result = test::run_captured(cli + "test \"" + (dir / "two.test.yaml").string() + "\"");
  INFO(result.out << result.err);
  CHECK(result.exit_code == 0);
  CHECK(result.out.find("PASS ") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("the soccer demo's scenarios pass, found by directory", "[scenario]") {
  const auto result = run_cli("test tests/scenarios/soccer");
  INFO(result.out << result.err);
  CHECK(result.exit_code == 0);
  CHECK(count(result.out, "PASS ") == scenarios_in(kSourceDir / "tests/scenarios/soccer").size());
  CHECK(result.out.find("0 failed, 0 invalid") != std::string::npos);
}

TEST_CASE("a path that is neither a test file nor a directory of them is a usage error",
          "[scenario]") {
  CHECK(run_cli("test no/such/dir").exit_code == 2);
  CHECK(run_cli("test docs").exit_code == 2);
}

TEST_CASE(
    "the JUnit XML is well-formed: a testcase per test file, named by its file and timed, a "
    "failure per failed expectation",
    "[scenario]") {
  const test::TempDir scratch;
  const fs::path xml = scratch.path() / "arbiter_scenario_junit.xml";
  fs::remove(xml);
  const auto result = run_cli(
      "test tests/data/scenarios/failing tests/scenarios/soccer --junit \"" + xml.string() + "\"");
  CHECK(result.exit_code == 1);
  const std::string text = test::read_text(xml);
  const auto files = scenarios_in(kScenarios / "failing").size() +
                     scenarios_in(kSourceDir / "tests/scenarios/soccer").size();
  CHECK(count(text, "<testcase ") == files);
  CHECK(count(text, "<failure ") == count(result.out, ": error[expectation]: expected "));
  CHECK(count(text, " time=\"") == files + 2);
  CHECK(text.find("<testcase name=\"machine_state\" "
                  "classname=\"tests/data/scenarios/failing/machine_state.test.yaml\"") !=
        std::string::npos);
  const auto lint = test::run_captured("xmllint --noout \"" + xml.string() + "\"");
  INFO(lint.err);
  CHECK(lint.exit_code == 0);
  fs::remove(xml);
}

TEST_CASE("the JUnit XML stays well-formed when a test's file name is not UTF-8 or holds U+FFFF",
          "[scenario]") {
  const test::TempDir scratch;
  // A file name is bytes: \xff is no UTF-8, and U+FFFF (EF BF BF) is no XML character.
  const fs::path file = scratch.path() / "odd\xff\xef\xbf\xbf.test.yaml";
  test::write_text(file, "arbiter_test: 1\nconfig: " +
                             (kSourceDir / "configs/paper/walk_and_kick.yaml").string() +
                             "\nexpect:\n  - {step: 1, active: [kick_ball]}\nsteps: 2\n");
  const fs::path xml = scratch.path() / "junit.xml";
  const auto result =
      run_cli("test \"" + scratch.path().string() + "\" --junit \"" + xml.string() + "\"");
  INFO(result.out << result.err);
  CHECK(result.exit_code == 1);
  const std::string text = test::read_text(xml);
  CHECK(text.find("odd\\xff\\uffff.test.yaml") != std::string::npos);
  const auto lint = test::run_captured("xmllint --noout \"" + xml.string() + "\"");
  INFO(lint.err);
  CHECK(lint.exit_code == 0);
}

TEST_CASE(
    "a --junit file that cannot be written is a usage error before any test runs, and leaves "
    "nothing behind",
    "[scenario]") {
  const test::TempDir scratch;
  fs::copy_file(kSourceDir / "configs/paper/walk_and_kick.yaml", scratch / "robot.yaml");
  const std::string config_text = test::read_text(scratch / "robot.yaml");
  const fs::path test_file = scratch / "robot.test.yaml";
  test::write_text(test_file, "arbiter_test: 1\nconfig: robot.yaml\nexpect: []\nsteps: 2\n");
  fs::create_directory(scratch / "a_directory");
  const auto listing = [&] {
    std::vector<std::string> names;
    for (const auto& entry : fs::recursive_directory_iterator(scratch.path())) {
      names.push_back(entry.path().lexically_relative(scratch.path()).string());
    }
    std::sort(names.begin(), names.end());
    return names;
  };
  const auto before = listing();
  const auto junit = [&](const fs::path& xml) {
    return run_cli("test \"" + test_file.string() + "\" --junit \"" + xml.string() + "\"");
  };

  std::vector<std::pair<fs::path, std::string>> unwritable = {
      {scratch / "no_such_dir" / "junit.xml", "No such file or directory"},
      {scratch / "a_directory", "Is a directory"},
  };
  // Root writes into a read-only directory all the same.
  if (::geteuid() != 0) {
    fs::create_directory(scratch / "read_only");
    fs::permissions(scratch / "read_only", fs::perms::owner_read | fs::perms::owner_exec);
    unwritable.emplace_back(scratch / "read_only" / "junit.xml", "Permission denied");
  }
  for (const auto& [xml, why] : unwritable) {
    INFO(xml.string());
    const auto result = junit(xml);
    CHECK(result.exit_code == 2);
    CHECK(result.err == "arbiter test: cannot write '" + xml.string() + "': " + why + "\n");
    // Refused before the tests: not one of them ran (no line for it, no counts).
    CHECK(result.out.empty());
  }
  if (::geteuid() != 0) fs::remove(scratch / "read_only");
  CHECK(listing() == before);

  // Refused after the tests ran, as the file is one a test names: the check made no file there.
  const auto refused = junit(scratch / "robot.yaml");
  CHECK(refused.exit_code == 2);
  CHECK(refused.err.find("writing it would destroy it") != std::string::npos);
  CHECK(test::read_text(scratch / "robot.yaml") == config_text);
  CHECK(listing() == before);

  CHECK(junit(scratch / "junit.xml").exit_code == 0);
  auto written = before;
  written.push_back("junit.xml");
  std::sort(written.begin(), written.end());
  CHECK(listing() == written);
  CHECK(test::read_text(scratch / "junit.xml").find("<testcase name=\"robot\"") !=
        std::string::npos);
}

TEST_CASE(
    "a failing test is explained from its run's trace, kept in a temporary file that goes "
    "with the test, or in memory where none can be made",
    "[scenario]") {
  // The trace of a test's run is kept for the explanations of what failed; a test of millions of
  // steps must not hold it in memory.
  const test::TempDir scratch;
  const std::string failing = "tests/data/scenarios/failing/substituted_kick.test.yaml";
  const std::string explained =
      "behaviour go_behind_ball (layer control) at step 10: active, activation 1";
  for (const fs::path& temp : {scratch.path(), scratch.path() / "no_such_dir"}) {
    INFO("TMPDIR=" << temp.string());
    const auto result = run_cli("test " + failing + " ", "TMPDIR=\"" + temp.string() + "\" ");
    CHECK(result.exit_code == 1);
    CHECK(result.out.find(explained) != std::string::npos);
  }
  CHECK(fs::is_empty(scratch.path()));
}
