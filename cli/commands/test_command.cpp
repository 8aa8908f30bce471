#include "commands/test_command.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <optional>

#include "commands/command.hpp"
#include "commands/output_file.hpp"
#include "commands/xml.hpp"

namespace arbiter::cli {
namespace {

// A test failed: the same code as an invalid config elsewhere.
constexpr int kExitFailed = kExitInvalid;

// The test files a path names: itself, or every test file under a directory, sorted.
bool expand(const std::string& path, std::vector<std::string>& files, std::ostream& err) {
  namespace fs = std::filesystem;
  std::error_code error;
  if (fs::is_regular_file(path, error)) {
    files.push_back(path);
    return true;
  }
  if (!fs::is_directory(path, error)) {
    err << fmt::format("arbiter test: no such file or directory '{}'\n", path);
    return false;
  }
  std::vector<std::string> found;
  for (fs::recursive_directory_iterator it(path, error), end; !error && it != end;
       it.increment(error)) {
    if (it->is_regular_file(error) && is_scenario_file(it->path().filename().string())) {
      found.push_back(it->path().lexically_normal().string());
    }
  }
  if (error) {
    err << fmt::format("arbiter test: cannot read directory '{}': {}\n", path, error.message());
    return false;
  }
  if (found.empty()) {
    err << fmt::format(
        "arbiter test: no test files (*.test.yaml, *.test.yml, *.test.json) in '{}'\n", path);
    return false;
  }
  std::sort(found.begin(), found.end());
  files.insert(files.end(), found.begin(), found.end());
  return true;
}

}  // namespace

std::string junit_xml(const std::vector<ScenarioResult>& results) {
  std::size_t failures = 0;
  std::size_t errors = 0;
  for (const auto& result : results) {
    failures += result.failures.size();
    errors += result.status == ScenarioResult::Status::kInvalid ? 1 : 0;
  }
  std::string out = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  double seconds = 0.0;
  for (const auto& result : results) seconds += result.seconds;
  out += fmt::format(
      "<testsuites name=\"arbiter test\" tests=\"{}\" failures=\"{}\" errors=\"{}\" "
      "time=\"{:.3f}\">\n",
      results.size(), failures, errors, seconds);
  out += fmt::format(
      "  <testsuite name=\"arbiter test\" tests=\"{}\" failures=\"{}\" errors=\"{}\" "
      "time=\"{:.3f}\">\n",
      results.size(), failures, errors, seconds);
  for (const auto& result : results) {
    // CI systems group by classname: one group per test file, as a test file is one test.
    out += fmt::format("    <testcase name=\"{}\" classname=\"{}\" file=\"{}\" time=\"{:.3f}\"",
                       xml_escaped(result.name), xml_escaped(result.file), xml_escaped(result.file),
                       result.seconds);
    if (result.status == ScenarioResult::Status::kPassed) {
      out += "/>\n";
      continue;
    }
    out += ">\n";
    if (result.status == ScenarioResult::Status::kInvalid) {
      std::string first;
      for (const auto& item : result.diagnostics.items()) {
        if (item.severity == Severity::kError) {
          first = item.message;
          break;
        }
      }
      out += fmt::format("      <error message=\"{}\" type=\"invalid\">{}</error>\n",
                         xml_escaped(first), xml_escaped(format(result.diagnostics)));
    }
    for (const auto& failure : result.failures) {
      out += fmt::format("      <failure message=\"{}\" type=\"{}\">{}{}</failure>\n",
                         xml_escaped(failure.diagnostic.message), failure.diagnostic.code,
                         xml_escaped(format(failure.diagnostic)), xml_escaped(failure.explanation));
    }
    out += "    </testcase>\n";
  }
  out += "  </testsuite>\n</testsuites>\n";
  return out;
}

int run_tests(const TestCommand& command, Registry& registry, std::ostream& out,
              std::ostream& err) {
  std::vector<std::string> files;
  for (const auto& path : command.paths) {
    if (!expand(path, files, err)) return kExitUsage;
  }
  std::vector<CommandInput> read;
  for (const auto& file : files) read.push_back({file, "a test file"});
  const std::vector<CommandOutput> written = {{command.junit, "--junit"}};
  if (!outputs_allowed("test", written, read, err)) return kExitUsage;
  // Opened before the tests run, which can take minutes, so that a place it cannot be written is
  // said at once; put in place at the end, so that a refused run leaves no file there.
  std::optional<AtomicFile> xml;
  if (!command.junit.empty()) {
    xml.emplace(command.junit);
    if (!xml->open()) {
      err << fmt::format("arbiter test: {}\n", xml->error());
      return kExitUsage;
    }
  }
  std::vector<ScenarioResult> results;
  std::size_t passed = 0;
  std::size_t failed = 0;
  std::size_t invalid = 0;
  for (const auto& file : files) {
    ScenarioResult result = run_scenario_file(file, registry, command.options);
    switch (result.status) {
      case ScenarioResult::Status::kPassed:
        ++passed;
        out << fmt::format("PASS {} ({} expectations, {} steps)\n", printable(file),
                           result.expectations, result.steps);
        break;
      case ScenarioResult::Status::kFailed:
        ++failed;
        out << fmt::format("FAIL {} ({} of {} expectations failed)\n", printable(file),
                           result.failures.size(), result.expectations);
        break;
      case ScenarioResult::Status::kInvalid:
        ++invalid;
        out << fmt::format("INVALID {}\n", printable(file));
        break;
    }
    // Load warnings and the reasons a test could not run, as `arbiter validate` prints them, under
    // the test's line and in the same stream, so that they stay in order however it is read.
    out << format_failures(result, command.format);
    out.flush();
    results.push_back(std::move(result));
  }
  out << fmt::format("{} passed, {} failed, {} invalid\n", passed, failed, invalid);
  for (const auto& result : results) {
    for (const auto& named : result.named_files) {
      read.push_back({named, fmt::format("a file {} names", result.file)});
    }
  }
  if (!outputs_allowed("test", written, read, err)) return kExitUsage;
  if (xml) {
    // The report first: where both reach one file (`--junit /dev/stderr 2>&1`), it stays before
    // the XML.
    out.flush();
    if (!xml->write(junit_xml(results)) || !xml->commit()) {
      err << fmt::format("arbiter test: {}\n", xml->error());
      return kExitUsage;
    }
  }
  if (invalid > 0) return kExitUsage;
  return failed > 0 ? kExitFailed : kExitOk;
}

int test_command(Options& options) {
  auto registry = make_registry();
  options.test.options.plugins = load_options_of(options).plugins;
  options.test.options.limits = load_options_of(options).limits;
  // The report on standard error when standard output is taken by the JUnit file, as run's with
  // a trace there: `--junit /dev/stdout > results.xml` leaves XML alone in results.xml. Coloured
  // when where it goes is a terminal.
  const bool report_on_stderr = writes_standard_output({options.test.junit});
  options.test.format =
      FormatOptions::readable(use_color(options.color, report_on_stderr ? stderr : stdout));
  return run_tests(options.test, registry, report_on_stderr ? std::cerr : std::cout, std::cerr);
}

}  // namespace arbiter::cli
