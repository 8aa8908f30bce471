// arbiter_bench takes Google Benchmark's flags as upstream documents them; the target table
// follows in every output format without breaking it.

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>

#include <unistd.h>

#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

// The smallest benchmark with a target (scl/replan5), as briefly as Google Benchmark allows; the
// table is printed, but a missed target (a debug build, a busy machine) does not fail the run.
const std::string kQuick =
    " --benchmark_filter=^scl/replan5$ --benchmark_min_time=0.001 --no-target-check ";

arbiter::test::CliResult bench(const std::string& arguments) {
  return arbiter::test::run_captured(std::string("\"") + ARBITER_BENCH + "\"" + arguments);
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

}  // namespace

TEST_CASE(
    "the JSON format (--benchmark_format=json) prints Google Benchmark's JSON and the targets on "
    "stderr",
    "[bench]") {
  const auto result = bench(kQuick + "--benchmark_format=json");
  INFO(result.err);
  CHECK(result.exit_code == 0);
  const Json report = Json::parse(result.out);
  CHECK(report.contains("context"));
  REQUIRE(report["benchmarks"].size() == 1);
  CHECK(report["benchmarks"][0]["name"] == "scl/replan5");
  CHECK(report["benchmarks"][0].contains("ns_per_step"));
  CHECK(contains(result.err, "scl/replan5: ns per step"));
  CHECK((contains(result.err, "target(s) missed\n") || contains(result.err, "every target")));
}

TEST_CASE("the CSV format (--benchmark_format=csv) prints CSV and the targets on stderr",
          "[bench]") {
  const auto result = bench(kQuick + "--benchmark_format=csv");
  CHECK(result.exit_code == 0);
  CHECK(contains(result.out, "name,iterations,real_time,cpu_time"));
  CHECK(contains(result.out, "\"scl/replan5\","));
  CHECK_FALSE(contains(result.out, "target"));
  CHECK(contains(result.err, "scl/replan5: ns per step"));
}

TEST_CASE("the console format keeps the target table after the results on stdout", "[bench]") {
  const auto result = bench(kQuick);
  CHECK(result.exit_code == 0);
  const auto row = result.out.find("scl/replan5 ");
  const auto table = result.out.find("scl/replan5: ns per step");
  REQUIRE(row != std::string::npos);
  REQUIRE(table != std::string::npos);
  CHECK(row < table);
}

TEST_CASE(
    "an output file (--benchmark_out) is written in --benchmark_out_format beside the display",
    "[bench]") {
  const fs::path out =
      fs::temp_directory_path() / ("arbiter_bench_out_" + std::to_string(::getpid()) + ".json");
  const auto result = bench(kQuick + "--benchmark_out=\"" + out.string() +
                            "\" --benchmark_out_format=json --benchmark_format=console");
  CHECK(result.exit_code == 0);
  CHECK(contains(result.out, "scl/replan5"));
  const Json report = Json::parse(arbiter::test::read_text(out));
  REQUIRE(report["benchmarks"].size() == 1);
  CHECK(report["benchmarks"][0]["name"] == "scl/replan5");
  fs::remove(out);
}

TEST_CASE("listing (--benchmark_list_tests) names the benchmarks the filter selects and runs none",
          "[bench]") {
  const auto result = bench(" --benchmark_list_tests --benchmark_filter=^scl/");
  CHECK(result.exit_code == 0);
  CHECK(contains(result.out, "scl/replan5\n"));
  CHECK_FALSE(contains(result.out, "step/"));
  CHECK_FALSE(contains(result.out, "target"));
}

TEST_CASE("an unknown flag is a usage error", "[bench]") {
  const auto result = bench(" --benchmark_no_such_flag");
  CHECK(result.exit_code == 2);
}
