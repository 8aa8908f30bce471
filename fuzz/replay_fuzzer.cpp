// libFuzzer target over `arbiter replay`: the input is a recording (MCAP), replayed as the CLI
// replays it. Its config, inputs and reloads are read, and its steps; the recorded config is loaded
// with the recorded inputs in place of its interface layers and stepped; the run is compared with
// the recording bit for bit. Classes: the built-ins (a recording names no plugin the fuzzer has).

#include <spdlog/sinks/null_sink.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>

#include "builtins.hpp"
#include "commands/record.hpp"

namespace {

struct Fixture {
  arbiter::Registry registry;
  arbiter::cli::ReplayOptions options;

  Fixture() {
    arbiter::register_builtin_behaviours(registry);
    // Run-time warnings of a replayed config go nowhere.
    spdlog::set_default_logger(
        std::make_shared<spdlog::logger>("fuzz", std::make_shared<spdlog::sinks::null_sink_mt>()));
    // Replay reads a recording from a file: one per fuzzing process, in memory where there is
    // /dev/shm.
    const std::filesystem::path dir = std::filesystem::is_directory("/dev/shm")
                                          ? "/dev/shm"
                                          : std::filesystem::temp_directory_path();
    options.recording =
        (dir / ("arbiter_fuzz_replay_" + std::to_string(::getpid()) + ".mcap")).string();
    // A recording may claim any number of steps: a few are enough to compare.
    options.steps = 20;
    options.load.limits.max_nodes = 1u << 16;  // as the config fuzzer, for the recorded config
    options.load.plugins.use_environment = false;
    options.load.plugins.use_default_path = false;
    options.version = "fuzz";
  }
  ~Fixture() { std::remove(options.recording.c_str()); }
};

Fixture& fixture() {
  static Fixture instance;
  return instance;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Fixture& f = fixture();
  std::FILE* file = std::fopen(f.options.recording.c_str(), "wb");
  if (file == nullptr) __builtin_trap();
  const bool written = std::fwrite(data, 1, size, file) == size;
  if (std::fclose(file) != 0 || !written) __builtin_trap();
  std::ostringstream out;
  std::ostringstream err;
  static_cast<void>(arbiter::cli::replay(f.options, f.registry, out, err));
  return 0;
}
