// Hostile traces, recordings, scenario files and language server messages (docs/robustness.md):
// every reader bounds nesting before it builds anything that recursion walks, and answers with a
// located error, never a crash; every message that quotes input is printed escaped.

#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "core/record/mcap.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using namespace arbiter;
using test::CliResult;
using test::read_text;
using test::TempDir;

namespace {

const std::string kConfig = std::string(ARBITER_SOURCE_DIR) + "/configs/paper/walk_and_kick.yaml";
constexpr std::size_t kDeep = 100000;

CliResult run_cli(const std::string& arguments) {
  return test::run_captured("\"" + std::string(ARBITER_CLI) + "\" " + arguments);
}

std::string arg(const fs::path& path) {
  return "\"" + path.string() + "\"";
}

/// A JSON list nested `levels` deep.
std::string deep_list(std::size_t levels) {
  return std::string(levels, '[') + std::string(levels, ']');
}

/// `record` (a step record, one JSON object) with one more actuator whose value, and one more
/// state machine whose events, are nested `levels` deep: every tool reads actuator values, and
/// diff, replay and scenario tests compare both.
std::string with_deep_fields(std::string record, std::size_t levels) {
  const auto insert = [&](const std::string& key, const std::string& entry) {
    const auto at = record.find(key);
    REQUIRE(at != std::string::npos);
    record.insert(at + key.size(), entry + (record[at + key.size()] == '}' ? "" : ", "));
  };
  insert("\"actuators\": {", "\"deep\": {\"value\": " + deep_list(levels) + ", \"written\": true}");
  insert("\"controllers\": {", "\"deep\": {\"events\": " + deep_list(levels) + "}");
  return record;
}

/// The lines of `text`, without their line breaks.
std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::size_t start = 0;
  while (start < text.size()) {
    const auto end = std::min(text.find('\n', start), text.size());
    lines.push_back(text.substr(start, end - start));
    start = end + 1;
  }
  return lines;
}

/// A run of the paper's walk and kick config, 5 steps, traced to `trace` and recorded to `mcap`.
void record_run(const fs::path& trace, const fs::path& mcap) {
  const auto result = run_cli("run " + arg(kConfig) + " --steps 5 -q --trace " + arg(trace) +
                              " --record " + arg(mcap));
  INFO(result.err);
  REQUIRE(result.exit_code == 0);
}

/// Copies the recording `from` to `to` record by record, with `edit(topic, step, data)` applied
/// to each message (step: the how-manieth message on its topic, from 1).
template <typename Edit>
void rewrite_recording(const fs::path& from, const fs::path& to, Edit edit) {
  std::istringstream text(read_text(from));
  mcap::Reader reader(text);
  std::FILE* file = std::fopen(to.string().c_str(), "wb");
  REQUIRE(file != nullptr);
  {
    mcap::Writer writer(fileno(file));
    writer.header("", "test");
    std::map<std::string, std::uint16_t> channels;
    std::map<std::string, int> counts;
    mcap::Record record;
    while (reader.next(record)) {
      if (record.kind == mcap::Record::Kind::kMetadata) {
        writer.metadata(record.name, record.metadata);
        continue;
      }
      auto channel = channels.find(record.topic);
      if (channel == channels.end()) {
        const auto schema = writer.schema(record.topic, "jsonschema", "{}");
        channel =
            channels.emplace(record.topic, writer.channel(schema, record.topic, "json")).first;
      }
      edit(record.topic, ++counts[record.topic], record.data);
      writer.message(channel->second, record.log_time, record.data);
    }
    REQUIRE(reader.error().empty());
    writer.finish();
    REQUIRE(writer.ok());
  }
  std::fclose(file);
}

}  // namespace

TEST_CASE("a trace record nested 100 000 levels deep is an error at its place, no crash",
          "[hostile]") {
  TempDir dir;
  record_run(dir / "run.jsonl", dir / "run.mcap");
  auto lines = lines_of(read_text(dir / "run.jsonl"));
  REQUIRE(lines.size() == 6);
  lines[2] = with_deep_fields(lines[2], kDeep);
  std::string text;
  for (const auto& line : lines) text += line + "\n";
  const auto deep = dir.write("deep.jsonl", text);
  // The '[' that opens level 201 (the list is inside three objects), its column counted in bytes
  // as trace columns are.
  const std::string value = "\"deep\": {\"value\": ";
  const auto column = lines[2].find(value) + value.size() + (ReadLimits().max_depth - 3) + 1;
  // `diff` prints the compact form, the others the form with codes and the source line.
  const auto located = [&](const CliResult& result) {
    INFO(result.err.substr(0, 400));
    const std::string where = "deep.jsonl:3:" + std::to_string(column) + ": error";
    CHECK(result.err.find(where) != std::string::npos);
    CHECK(result.err.find(": nesting deeper than 200 levels\n") != std::string::npos);
  };

  SECTION("diff") {
    const auto result = run_cli("diff " + arg(deep) + " " + arg(deep));
    CHECK_FALSE(result.signalled);
    CHECK(result.exit_code == 2);
    located(result);
  }
  SECTION("plot") {
    const auto result = run_cli("plot " + arg(deep) + " -o " + arg(dir / "deep.svg"));
    CHECK_FALSE(result.signalled);
    CHECK(result.exit_code == 1);
    located(result);
  }
  SECTION("explain") {
    const auto result =
        run_cli("explain " + arg(kConfig) + " --trace " + arg(deep) + " --step 3 kick_ball");
    CHECK_FALSE(result.signalled);
    CHECK(result.exit_code == 1);
    located(result);
  }
  SECTION("a scenario test that must repeat it") {
    const auto test = dir.write("deep.test.yaml", "arbiter_test: 1\nconfig: " + kConfig +
                                                      "\nsteps: 5\nexpect_trace: deep.jsonl\n");
    const auto result = run_cli("test " + arg(test));
    CHECK_FALSE(result.signalled);
    CHECK(result.exit_code == 2);
    INFO(result.out.substr(0, 400));
    CHECK(result.out.find("deep.test.yaml:4:15: error[unreadable-trace]: cannot compare with "
                          "trace 'deep.jsonl': nesting deeper than 200 levels\n") !=
          std::string::npos);
    CHECK(result.out.find("note: in the trace at " + (dir / "deep.jsonl").string() +
                          ":3:" + std::to_string(column) + "\n") != std::string::npos);
  }
}

TEST_CASE("a recording with a message nested 100 000 levels deep is an error, no crash",
          "[hostile]") {
  TempDir dir;
  record_run(dir / "run.jsonl", dir / "run.mcap");

  SECTION("a step message: replay and diff") {
    rewrite_recording(dir / "run.mcap", dir / "deep.mcap",
                      [](const std::string& topic, int count, std::string& data) {
                        if (topic == "/arbiter/step" && count == 2) {
                          data = with_deep_fields(data, kDeep);
                        }
                      });
    const auto deep = arg(dir / "deep.mcap");
    for (const auto& command : {"replay " + deep, "diff " + deep + " " + deep}) {
      INFO(command);
      const auto result = run_cli(command);
      CHECK_FALSE(result.signalled);
      CHECK(result.exit_code == (command.rfind("replay", 0) == 0 ? 1 : 2));
      INFO(result.err.substr(0, 400));
      CHECK(result.err.find("deep.mcap: error") != std::string::npos);
      CHECK(result.err.find(": at byte ") != std::string::npos);
      CHECK(result.err.find(": nesting deeper than 200 levels (at byte ") != std::string::npos);
    }
  }
  SECTION("an inputs message: replay") {
    rewrite_recording(dir / "run.mcap", dir / "deep.mcap",
                      [](const std::string& topic, int count, std::string& data) {
                        if (topic == "/arbiter/inputs" && count == 2) {
                          data =
                              "{\"step\": 2, \"inputs\": {\"x\": {\"value\": " + deep_list(kDeep) +
                              ", \"written\": true}}}";
                        }
                      });
    const auto result = run_cli("replay " + arg(dir / "deep.mcap"));
    CHECK_FALSE(result.signalled);
    CHECK(result.exit_code == 1);
    INFO(result.err.substr(0, 400));
    CHECK(result.err.find("deep.mcap: error: at byte ") != std::string::npos);
    CHECK(result.err.find(": an inputs message nests deeper than 200 levels") != std::string::npos);
  }
}

TEST_CASE("a recording's inputs for a step far beyond its steps are an error, not an allocation",
          "[hostile]") {
  TempDir dir;
  record_run(dir / "run.jsonl", dir / "run.mcap");
  rewrite_recording(dir / "run.mcap", dir / "far.mcap",
                    [](const std::string& topic, int count, std::string& data) {
                      if (topic == "/arbiter/inputs" && count == 3) {
                        data =
                            "{\"step\": 3000000000000, \"inputs\": {\"x\": {\"value\": 1, "
                            "\"written\": true}}}";
                      }
                    });
  const auto result = run_cli("replay " + arg(dir / "far.mcap"));
  CHECK_FALSE(result.signalled);
  CHECK(result.exit_code == 1);
  INFO(result.err);
  CHECK(result.err.find("far.mcap: error: at byte ") != std::string::npos);
  CHECK(result.err.find(": an inputs message for step 3000000000000, after the inputs of 2 steps "
                        "(and 0 dropped); each step's inputs follow those of the step before "
                        "it\n") != std::string::npos);
}

TEST_CASE("an inputs message that a recorder does not write stops a replay, not blamed on the run",
          "[hostile]") {
  TempDir dir;
  record_run(dir / "run.jsonl", dir / "run.mcap");
  const auto replaced = [&](const std::string& name, const std::string& text) {
    rewrite_recording(dir / "run.mcap", dir / name,
                      [&](const std::string& topic, int count, std::string& data) {
                        if (topic == "/arbiter/inputs" && count == 3) data = text;
                      });
    return run_cli("replay " + arg(dir / name));
  };
  SECTION("not JSON, with no step number") {
    const auto result = replaced("garbage.mcap", "GARBAGE");
    CHECK_FALSE(result.signalled);
    CHECK(result.exit_code == 1);
    INFO(result.err);
    CHECK(result.err.find("garbage.mcap: error: at byte ") != std::string::npos);
    CHECK(result.err.find(": an inputs message without its \"step\" number, not one a recorder "
                          "writes") != std::string::npos);
    CHECK(result.err.find("not deterministic") == std::string::npos);
  }
  SECTION("a step number, but not JSON") {
    const auto result = replaced("broken.mcap", "{\"step\": 3, \"inputs\": {\"x\": ");
    CHECK_FALSE(result.signalled);
    CHECK(result.exit_code == 1);
    INFO(result.err);
    CHECK(result.err.find("broken.mcap: error: the /arbiter/inputs message of step 3: not a JSON "
                          "object with an \"inputs\" object") != std::string::npos);
    CHECK(result.err.find("not deterministic") == std::string::npos);
  }
}

TEST_CASE("a scenario file nested 100 000 levels deep is an error at its place, no crash",
          "[hostile]") {
  TempDir dir;
  const std::string head = "arbiter_test: 1\nconfig: " + kConfig + "\nsteps: 3\nexpect: ";
  const auto yaml = dir.write("deep.test.yaml", head + deep_list(kDeep) + "\n");
  const auto json =
      dir.write("deep.test.json", "{\"arbiter_test\": 1, \"config\": \"" + kConfig +
                                      "\", \"steps\": 3, \"expect\": " + deep_list(kDeep) + "}\n");
  for (const auto& [file, where] :
       {std::pair{yaml, std::string(":4:208: ")},
        std::pair{json, ":1:" + std::to_string(kConfig.size() + 256) + ": "}}) {
    INFO(file);
    const auto result = run_cli("test " + arg(file));
    CHECK_FALSE(result.signalled);
    CHECK(result.exit_code == 2);
    INFO(result.out.substr(0, 400));
    CHECK(result.out.find(where + std::string("error[too-deep]: nesting deeper than 200 levels")) !=
          std::string::npos);
  }
}

TEST_CASE("a language server message nested 100 000 levels deep is a parse error, no crash",
          "[hostile]") {
  TempDir dir;
  const std::string body =
      "{\"jsonrpc\": \"2.0\", \"id\": 1, \"method\": \"initialize\", "
      "\"params\": " +
      deep_list(kDeep) + "}";
  const auto input =
      dir.write("in.txt", "Content-Length: " + std::to_string(body.size()) + "\r\n\r\n" + body);
  const auto result = run_cli("lsp < " + arg(input));
  CHECK_FALSE(result.signalled);
  CHECK(result.out.find("\"message\":\"parse error: nesting deeper than 200 levels at byte ") !=
        std::string::npos);
}

namespace {

/// Whether `text` holds a byte a terminal could act on or garble: a control character other than
/// the line feed (the CLI prints no colours to a file), or a byte that is not ASCII and not part of
/// "é" (the one non-ASCII character these tests write).
bool raw_bytes_in(const std::string& text) {
  for (std::size_t i = 0; i < text.size(); ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c == '\n') continue;
    if (c < 0x20 || c == 0x7f) return true;
    if (c >= 0x80) {
      if (text.compare(i, 2, "é") != 0) return true;
      ++i;
    }
  }
  return false;
}

}  // namespace

TEST_CASE("a malformed trace line is printed escaped, its valid UTF-8 kept", "[hostile]") {
  TempDir dir;
  record_run(dir / "run.jsonl", dir / "run.mcap");
  const auto lines = lines_of(read_text(dir / "run.jsonl"));
  const auto write = [&](const std::string& bad) {
    return dir.write("bad.jsonl", lines[0] + "\n" + lines[1] + "\n" + bad + "\n");
  };
  const std::map<std::string, std::string> commands = {
      {"plot", "plot " + arg(dir / "bad.jsonl") + " -o " + arg(dir / "bad.svg")},
      {"explain",
       "explain " + arg(kConfig) + " --trace " + arg(dir / "bad.jsonl") + " --step 2 kick_ball"}};
  for (const auto& [name, command] : commands) {
    DYNAMIC_SECTION(name << ": escape and bell characters (terminal escape injection)") {
      write("\x1b]0;owned\x07{\"step\": 2, \"x\": \"\x1b[31mré\"}");
      const auto result = run_cli(command);
      CHECK(result.exit_code == 1);
      CHECK(result.err.find("bad.jsonl:3:1: error[bad-trace]: not JSON: ") != std::string::npos);
      CHECK(result.err.find("\n3 | \\x1b]0;owned\\x07{\"step\": 2, \"x\": \"\\x1b[31mré\"}\n"
                            "  | ^~~~\n") != std::string::npos);
      CHECK_FALSE(raw_bytes_in(result.err));
    }
    DYNAMIC_SECTION(name << ": invalid UTF-8") {
      write("{\"step\": 2, \"x\": caf\xe9 \xff\xfe}");
      const auto result = run_cli(command);
      CHECK(result.exit_code == 1);
      // The plain scalar from the column on is underlined, escapes and all.
      CHECK(result.err.find("bad.jsonl:3:18: error[bad-trace]: not JSON: ") != std::string::npos);
      CHECK(result.err.find("\n3 | {\"step\": 2, \"x\": caf\\xe9 \\xff\\xfe}\n  | " +
                            std::string(17, ' ') + "^" + std::string(15, '~') + "\n") !=
            std::string::npos);
      CHECK_FALSE(raw_bytes_in(result.err));
    }
  }
}

TEST_CASE("a config excerpt with control characters is printed escaped", "[hostile]") {
  TempDir dir;
  const auto config =
      dir.write("control.yaml",
                "arbiter: 1\nname: x\nlayers:\n  - name: l\n    behaviours:\n"
                "      a: {type: scripted, \"b\x1b[2J\x07\xc2\x9b\": 1, \"é\": 2}\n");
  const auto result = run_cli("validate " + arg(config));
  CHECK(result.exit_code == 1);
  INFO(result.err);
  // The underlines span the escapes: the first marks the key, the second is shifted by them.
  const std::string excerpt =
      "\n6 |       a: {type: scripted, \"b\\x1b[2J\\x07\\u009b\": 1, \"é\": 2}\n  | ";
  CHECK(result.err.find(":6:27: error[unknown-key]: unknown key 'b\\x1b[2J\\x07\\u009b' in "
                        "behaviour 'a'" +
                        excerpt + std::string(26, ' ') + "^" + std::string(19, '~') + "\n") !=
        std::string::npos);
  CHECK(result.err.find(":6:41: error[unknown-key]: unknown key 'é' in behaviour 'a'" + excerpt +
                        std::string(51, ' ') + "^~~\n") != std::string::npos);
  CHECK_FALSE(raw_bytes_in(result.err));
}

TEST_CASE("diagnostics as JSON stay JSON when a file name is not UTF-8", "[hostile]") {
  TempDir dir;
  const auto result = run_cli("validate --format json " + arg(dir / "bad\xff\x1b.yaml"));
  CHECK(result.exit_code == 1);
  INFO(result.out << result.err);
  CHECK(result.out.find("bad\xef\xbf\xbd\\u001b.yaml\",") != std::string::npos);
  CHECK(result.out.find_first_of("\xff\x1b") == std::string::npos);
}

TEST_CASE("printable() escapes control characters and invalid UTF-8 and nothing else",
          "[hostile]") {
  CHECK(printable("plain é, ü and 😀\tkept") == "plain é, ü and 😀\tkept");
  CHECK(printable("\x1b[31m\x07\x7f\r") == "\\x1b[31m\\x07\\x7f\\x0d");
  CHECK(printable("a\nb") == "a\\x0ab");
  CHECK(printable("a\nb", true) == "a\nb");
  CHECK(printable("\xc2\x85 \xc2\x9b") == "\\u0085 \\u009b");
  // A lone continuation byte, Latin-1, an overlong '/', an encoded surrogate, a cut sequence.
  CHECK(printable("\x80 caf\xe9 \xc0\xaf \xed\xa0\x80 \xe2\x82") ==
        "\\x80 caf\\xe9 \\xc0\\xaf \\xed\\xa0\\x80 \\xe2\\x82");
}
