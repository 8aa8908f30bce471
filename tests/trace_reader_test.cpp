#include <fmt/format.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <filesystem>
#include <optional>
#include <sstream>
#include <thread>

#include "arbiter/explain.hpp"
#include "arbiter/recording.hpp"
#include "arbiter/reload.hpp"
#include "arbiter/trace.hpp"
#include "arbiter/trace_diff.hpp"
#include "arbiter/trace_reader.hpp"
#include "core/record/step_record.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using namespace arbiter;
using namespace arbiter::test;

namespace {

const fs::path kBadTraces = fs::path(ARBITER_SOURCE_DIR) / "tests/data/bad_traces";

const std::string kHeader =
    R"({"arbiter_trace": 1, "name": "t", "layers": [{"name": "l", "order": ["a"]}]})";

std::string step_record(int step) {
  return R"({"step": )" + std::to_string(step) +
         R"(, "layers": {"l": {"a": {"requested": 1.0, "activation": 1.0, "active": true, )"
         R"("inhibited_by": []}}}, "actuators": {}, "controllers": {}})";
}

}  // namespace

// As `arbiter view`, `plot` and `explain` print them: with the record's line and the place
// underlined, as config errors are.
TEST_CASE("each malformed trace or recording gets its exact located error", "[trace_reader]") {
  const WorkingDirectory here(kBadTraces);
  std::size_t files = 0;
  const auto is_trace = [](const fs::path& path) { return path.extension() != ".err"; };
  for (const auto& path : files_in(kBadTraces, is_trace)) {
    const auto name = path.filename().string();
    ++files;
    DYNAMIC_SECTION(name) {
      Diagnostic error;
      const auto trace = read_trace(name, error);
      REQUIRE_FALSE(trace);
      const auto expected = path.string() + ".err";
      const std::string text = format(error, FormatOptions::readable());
      if (update_golden()) write_text(expected, text);
      CHECK(text == read_text(expected));
    }
  }
  CHECK(files >= 10);
}

TEST_CASE("a trace with a reload header is read as header, reloads and steps", "[trace_reader]") {
  const std::string reload =
      R"({"arbiter_trace": 1, "reload": 1, "after_step": 2, "name": "t", "layers": []})";
  std::istringstream in(kHeader + "\n" + step_record(1) + "\n\n" + step_record(2) + "\n" + reload +
                        "\n" + step_record(3) + "\n");
  const auto source = jsonl_trace_source(in, "run.jsonl");
  Diagnostic error;
  const auto trace = read_trace(*source, error);
  REQUIRE(trace);
  CHECK(trace->header.text == kHeader);
  REQUIRE(trace->steps.size() == 3);
  CHECK(trace->steps[2].step == 3);
  CHECK(trace->steps[2].location.line == 6);
  REQUIRE(trace->reloads.size() == 1);
  CHECK(trace->reloads[0].before == 2);
  CHECK(trace->reloads[0].header.step == 2);
  CHECK(trace->reloads[0].header.location.line == 5);
  CHECK(trace->truncated.empty());
}

TEST_CASE("a record the reader rejects stops reading there with its location", "[trace_reader]") {
  std::istringstream in(kHeader + "\n" + step_record(1) + "\nnonsense\n" + step_record(2) + "\n");
  const auto source = jsonl_trace_source(in, "run.jsonl");
  TraceRecord record;
  CHECK(source->next(record));
  CHECK(source->next(record));
  CHECK_FALSE(source->next(record));
  CHECK_FALSE(source->next(record));
  REQUIRE(source->error());
  CHECK(format(*source->error()) ==
        "run.jsonl:3:2: error: not JSON: syntax error while parsing value - invalid literal; "
        "last read: 'no'\n");
}

/// A stream that gives `text`, then fails to read, as a file does on a read error.
class FailingBuffer : public std::stringbuf {
 public:
  explicit FailingBuffer(const std::string& text) : std::stringbuf(text) {}

 protected:
  int_type underflow() override {
    const auto c = std::stringbuf::underflow();
    if (traits_type::eq_int_type(c, traits_type::eof())) throw std::runtime_error("read error");
    return c;
  }
};

TEST_CASE("a trace that cannot be read is an error, not an empty or shorter trace",
          "[trace_reader]") {
  const auto dir = fs::temp_directory_path() /
                   fmt::format("arbiter_dir_{}.jsonl",
                               std::chrono::steady_clock::now().time_since_epoch().count());
  fs::create_directories(dir);
  Diagnostic error;
  CHECK_FALSE(read_trace(dir.string(), error));
  CHECK(error.message == "cannot read the trace");
  fs::remove(dir);

  FailingBuffer buffer(kHeader + "\n" + step_record(1) + "\n");
  std::istream in(&buffer);
  const auto source = jsonl_trace_source(in, "run.jsonl");
  CHECK_FALSE(read_trace(*source, error));
  CHECK(format(error) == "run.jsonl:3:1: error: cannot read the trace\n");
}

TEST_CASE("a diff stops where one trace fails, without reading the other to its end",
          "[trace_reader]") {
  std::istringstream bad(kHeader + "\n" + step_record(1) + "\nnonsense\n");
  std::string long_run = kHeader + "\n";
  for (int step = 1; step <= 1000; ++step) long_run += step_record(step) + "\n";
  std::istringstream good(long_run);
  for (const bool bad_first : {true, false}) {
    bad.clear();
    bad.seekg(0);
    good.clear();
    good.seekg(0);
    const auto bad_source = jsonl_trace_source(bad, "bad.jsonl");
    const auto good_source = jsonl_trace_source(good, "good.jsonl");
    Diagnostic error;
    const auto diff = bad_first ? diff_traces(*bad_source, *good_source, error)
                                : diff_traces(*good_source, *bad_source, error);
    CHECK_FALSE(diff);
    CHECK(error.location.file == "bad.jsonl");
    CHECK_FALSE(good.eof());  // the good trace was not read to its end
  }
}

TEST_CASE("explain reports an unreadable record where the reader found it", "[trace_reader]") {
  Registry registry = make_test_registry();
  const Program program = compile_text(
      "arbiter: 1\nname: t\nlayers:\n  - name: l\n    behaviours:\n      a: {type: scripted, "
      "params: {activation: 1.0}}\n",
      registry);
  std::istringstream in(kHeader + "\n" + step_record(1) + "\n{\"step\": 2,\n");
  const auto result = explain(program, in, 2, "a");
  CHECK(result.status == Explanation::Status::kBadTrace);
  REQUIRE(result.where);
  CHECK(result.where->line == 3);
  CHECK(result.text.rfind("not JSON: ", 0) == 0);
}

TEST_CASE("a recording reads as the trace of the same run, each step with its time",
          "[trace_reader]") {
  const auto dir = fs::path(ARBITER_SOURCE_DIR) / "tests/data/traces";
  Diagnostic error;
  const auto trace = read_trace((dir / "walk_and_kick.jsonl").string(), error);
  REQUIRE(trace);
  const auto recording = read_trace((dir / "walk_and_kick.mcap").string(), error);
  REQUIRE(recording);
  CHECK(recording->header.text == trace->header.text);
  REQUIRE(recording->steps.size() == trace->steps.size());
  for (std::size_t i = 0; i < trace->steps.size(); ++i) {
    std::string text = recording->steps[i].text;
    const auto t = text.find(", \"t\": ");
    REQUIRE(t != std::string::npos);
    text.erase(t, text.find(',', t + 1) - t);
    CHECK(text == trace->steps[i].text);
  }
  CHECK(recording->truncated.empty());
  CHECK(diff_traces(*trace, *recording).identical);
}

TEST_CASE("a recording cut anywhere reads up to its last whole chunk and says it was cut",
          "[trace_reader]") {
  const auto bytes =
      read_text(fs::path(ARBITER_SOURCE_DIR) / "tests/data/traces/walk_and_kick.mcap");
  REQUIRE(bytes.size() > 1000);
  for (std::size_t cut = 1; cut < bytes.size() - 8; cut += 97) {
    const auto source = trace_source(bytes.substr(0, cut), "cut.mcap");
    Diagnostic error;
    const auto trace = read_trace(*source, error);
    if (trace && trace->steps.size() < 12) {
      CHECK(trace->truncated.rfind("the recording was cut off while it was written", 0) == 0);
    } else if (!trace) {
      // Cut before its trace header: cut off, not empty.
      CHECK(format(error).rfind("cut.mcap: error: the recording was cut off while it was "
                                "written, before its trace header: it holds no step (it is "
                                "whole up to byte ",
                                0) == 0);
    }
  }
}

TEST_CASE("a recording whose end is not whole reads every step and says what is wrong there",
          "[trace_reader]") {
  const auto bytes =
      read_text(fs::path(ARBITER_SOURCE_DIR) / "tests/data/traces/walk_and_kick.mcap");
  Diagnostic error;
  const auto whole = read_trace(*trace_source(bytes, "run.mcap"), error);
  REQUIRE(whole);
  CHECK(whole->damaged.empty());
  // The footer: opcode, length, summary_start, summary_offset_start, summary_crc; then the magic.
  const std::size_t footer = bytes.size() - 8 - 29;
  std::uint64_t summary_start = 0;
  for (int i = 7; i >= 0; --i) {
    summary_start = summary_start << 8 | static_cast<unsigned char>(bytes[footer + 9 + i]);
  }
  REQUIRE(summary_start > 13);
  const auto flipped = [&](std::size_t at) {
    auto copy = bytes;
    copy[at] = static_cast<char>(copy[at] ^ 0x5a);
    return copy;
  };
  const std::pair<std::string, std::string> damages[] = {
      {bytes.substr(0, bytes.size() - 8),
       "the file does not end with MCAP's magic bytes after its footer"},
      {flipped(bytes.size() - 1), "the file does not end with MCAP's magic bytes after its footer"},
      {flipped(footer + 9 + 16), "the footer's summary CRC does not match the summary"},
      {flipped(footer + 9), "the footer puts the summary at byte "},
      {flipped(summary_start - 4), "the data end record's CRC does not match the data section"},
      {bytes.substr(0, footer + 5), "the file ends in its summary, before its footer"},
      {bytes.substr(0, summary_start + 20), "the file ends in its summary, before its footer"},
  };
  for (const auto& [damaged, what] : damages) {
    INFO(what);
    const auto trace = read_trace(*trace_source(damaged, "run.mcap"), error);
    REQUIRE(trace);
    CHECK(trace->steps.size() == whole->steps.size());
    CHECK(trace->truncated.empty());
    CHECK(trace->damaged.rfind("the end of the recording is not whole: at byte ", 0) == 0);
    CHECK(trace->damaged.find(": " + what) != std::string::npos);
  }
}

namespace {

class ManualClock : public StepClock {
 public:
  double now() override { return t += 0.004; }
  double t = 0.0;
};

/// A layer wide enough that a recording copies its levels and values by the chunks that changed
/// (more than SnapshotShape::kWhole bytes each): behaviours whose scripted levels change at
/// different steps, each writing one of somewhat fewer numbers; with `strings`, a string too,
/// beyond the small-string buffer.
std::string wide_config(bool strings) {
  constexpr int kNumbers = detail::SnapshotShape::kWhole / sizeof(double) + 20;
  constexpr int kBehaviours = kNumbers + 20;
  std::string text = "arbiter: 1\nname: wide\nrate_hz: 100\nlayers:\n  - name: wide\n";
  text += "    actuators:\n      sum: {type: double, aggregate: true}\n";
  if (strings) text += "      mode: {type: string}\n";
  for (int v = 0; v < kNumbers; ++v) text += fmt::format("      v{}: {{type: double}}\n", v);
  text += "    behaviours:\n";
  for (int b = 0; b < kBehaviours; ++b) {
    std::string levels;
    for (int step = 0; step < 60; ++step) {
      const int held = step / (b % 5 + 1);  // behaviour b changes level every b % 5 + 1 steps
      levels += fmt::format("{}{}", step == 0 ? "" : ", ", ((held * (b + 3)) % 11) / 10.0);
    }
    text += fmt::format(
        "      b{}: {{type: scripted, params: {{activation: [{}], writes: {{sum: {}, v{}: {}", b,
        levels, b, b % kNumbers, b * 0.25);
    if (strings) text += fmt::format(", mode: \"behaviour {} of the wide layer, writing\"", b);
    text += "}}}\n";
  }
  return text;
}

/// With `reloaded`, the run reloads it at step 200 and `original` again at step 300.
void check_recording_matches_trace(const fs::path& config, const std::string& original,
                                   const std::optional<std::string>& reloaded = std::nullopt) {
  const bool reload = reloaded.has_value();
  // A ring of two slots drops steps whenever the writer lags, so that steps copied whole (after
  // a drop) and steps copied by what changed are both recorded. Each of two hot reloads to a
  // program of another shape brings a ring laid out for it while the writer may still read the
  // one before; the second frees the first replaced program, which the writer's last steps of
  // it point into.
  Registry registry = make_test_registry();
  write_text(config, original);
  Reloader reloader(registry);
  Diagnostics diagnostics;
  auto program = reloader.load(config.string(), diagnostics);
  INFO(format(diagnostics));
  REQUIRE(program);
  Manager manager(std::move(*program));
  ManualClock clock;
  manager.set_clock(&clock);
  std::ostringstream trace_text;
  TraceWriter trace(trace_text);
  manager.add_observer(trace);
  const auto path = config.parent_path() / "run.mcap";
  std::uint64_t dropped = 0;
  {
    Recorder recorder(path.string(), RecordingInfo{{{config.string(), original}}, {}, "test"}, 2);
    REQUIRE(recorder.ok());
    manager.add_observer(recorder);
    for (int i = 0; i < 400; ++i) {
      if (reload && (i == 200 || i == 300)) {
        write_text(config, i == 200 ? *reloaded : original);
        const auto result = reloader.reload(manager);
        INFO(format(result.diagnostics));
        REQUIRE(result.staged);
      }
      manager.step();
      if (i % 7 == 0) recorder.drain();
    }
    manager.finish();
    dropped = recorder.dropped();
  }
  Diagnostic error;
  std::istringstream text(trace_text.str());
  const auto traced = read_trace(*jsonl_trace_source(text, "trace"), error);
  REQUIRE(traced);
  const auto recorded = read_trace(path.string(), error);
  INFO(format(error));
  REQUIRE(recorded);
  CHECK(recorded->reloads.size() == (reload ? 2 : 0));
  CHECK(recorded->steps.size() + dropped == traced->steps.size());
  CHECK(recorded->steps.size() > 20);
  std::size_t t = 0;
  for (const auto& step : recorded->steps) {
    while (t < traced->steps.size() && traced->steps[t].step != step.step) ++t;
    REQUIRE(t < traced->steps.size());
    CHECK(step.text == traced->steps[t].text);
  }
}

}  // namespace

TEST_CASE("a recording's step records are the trace's lines of the same run, byte for byte",
          "[trace_reader][record]") {
  TempDir dir;
  SECTION("state machines, and hot reloads to a wide layer and back") {
    // Streamed blocks, then chunked ones, then streamed again.
    check_recording_matches_trace(
        dir.path() / "goalie_plan.yaml",
        read_text(fs::path(ARBITER_SOURCE_DIR) / "configs/paper/goalie_plan.yaml"),
        wide_config(false));
  }
  SECTION("levels and values copied by the chunks that changed") {
    check_recording_matches_trace(dir.path() / "wide.yaml", wide_config(false));
  }
  SECTION("a string value among them") {
    check_recording_matches_trace(dir.path() / "wide.yaml", wide_config(true));
  }
}

namespace {

/// A manager of configs/paper/goalie_plan.yaml, a run with state machines to record; a config
/// that does not load fails the test.
Manager goalie_plan(Registry& registry) {
  Diagnostics diagnostics;
  auto program = load(std::string(ARBITER_SOURCE_DIR) + "/configs/paper/goalie_plan.yaml", registry,
                      diagnostics);
  INFO(format(diagnostics));
  REQUIRE(program);
  return Manager(std::move(*program));
}

}  // namespace

TEST_CASE("a recorder asked for no slots keeps one, and records a run it is drained in",
          "[trace_reader][record]") {
  // Without a slot every step would drop, and the end of the recording would wait for room
  // forever.
  TempDir dir;
  Registry registry = make_test_registry();
  Manager manager = goalie_plan(registry);
  const auto path = dir / "run.mcap";
  {
    Recorder recorder(path.string(), RecordingInfo{{}, {}, "test"}, 0);
    REQUIRE(recorder.ok());
    manager.add_observer(recorder);
    for (int i = 0; i < 30; ++i) {
      manager.step();
      recorder.drain();
    }
    manager.finish();
    CHECK(recorder.dropped() == 0);
  }
  CHECK(read_whole_trace(path.string()).steps.size() == 30);
}

TEST_CASE("a recording that cannot be written ends, not the run, and says why once",
          "[trace_reader][record]") {
  if (!fs::exists("/dev/full")) {
    WARN("no /dev/full here: skipped");
    return;
  }
  Registry registry = make_test_registry();
  Manager manager = goalie_plan(registry);
  std::ostringstream log;
  auto logger = std::make_shared<spdlog::logger>(
      "recording", std::make_shared<spdlog::sinks::ostream_sink_st>(log));
  logger->set_pattern("%l: %v");
  Recorder recorder("/dev/full", RecordingInfo{{}, {}, "test"}, 4, RingFull::kWaitForWriter);
  REQUIRE(recorder.ok());  // it opens: the disk is found full at the first write
  recorder.set_logger(logger);
  manager.add_observer(recorder);
  for (int i = 0; i < 30; ++i) manager.step();
  manager.finish();
  CHECK(manager.steps() == 30);
  CHECK(recorder.failed());
  CHECK_FALSE(recorder.ok());
  CHECK(recorder.error() == "No space left on device (at the start)");
  CHECK(log.str() ==
        "error: recording '/dev/full': a write failed: No space left on device (at the start); "
        "the run goes on unrecorded, the file keeps what was written before\n");
}
