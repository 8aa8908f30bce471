// libFuzzer target over the load pipeline (load_config: document → model → program → lints),
// then a few steps of the compiled program. The first input byte picks the format (even: YAML, odd:
// JSON); the rest is the file's text. Classes: the built-ins and the test classes.

#include <spdlog/sinks/null_sink.h>
#include <spdlog/spdlog.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "arbiter/diagnostics.hpp"
#include "arbiter/document.hpp"
#include "arbiter/lint.hpp"
#include "arbiter/load.hpp"
#include "arbiter/manager.hpp"
#include "test_support.hpp"

namespace {

struct Fixture {
  arbiter::Registry registry = arbiter::test::make_test_registry();
  std::shared_ptr<spdlog::logger> logger =
      std::make_shared<spdlog::logger>("fuzz", std::make_shared<spdlog::sinks::null_sink_mt>());
  // Includes are read relative to the config; naming it inside tests/data/valid lets the
  // seeds' includes resolve.
  std::string yaml_file = ARBITER_FUZZ_ROOT "/fuzz_input.yaml";
  std::string json_file = ARBITER_FUZZ_ROOT "/fuzz_input.json";
  arbiter::LoadOptions options;

  Fixture() {
    // The default node limit (about a million, after alias expansion) takes seconds under the
    // sanitizers; a lower one keeps every input well inside the fuzzer's timeout.
    options.limits.max_nodes = 1u << 16;
    // No plugin is loaded from an input's `plugins:` except by a relative path.
    options.plugins.use_environment = false;
    options.plugins.use_default_path = false;
    options.lint = arbiter::lint;
  }
};

Fixture& fixture() {
  static Fixture instance;
  return instance;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  Fixture& f = fixture();
  const bool json = (data[0] & 1u) != 0;
  const std::string_view text(reinterpret_cast<const char*>(data + 1), size - 1);
  const std::string& file = json ? f.json_file : f.yaml_file;

  arbiter::Overlay overlay;
  overlay.set(file, std::string(text));
  arbiter::LoadOptions options = f.options;
  options.source = &overlay;
  arbiter::Loaded loaded = arbiter::load_config(file, f.registry, options);
  if (loaded.program) {
    arbiter::Manager manager(std::move(*loaded.program), f.logger);
    for (int step = 0; step < 3; ++step) manager.step();
    manager.finish();
  }
  const arbiter::Diagnostics& diagnostics = loaded.diagnostics;
  // Every diagnostic must format, as text and as JSON.
  static_cast<void>(arbiter::format(diagnostics));
  static_cast<void>(arbiter::format_json(diagnostics));
  arbiter::test::Pose::seen_x().clear();
  return 0;
}
