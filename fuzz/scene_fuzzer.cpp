// libFuzzer target over the picture a replay draws again from a recording (RecordedScene): the
// input is a run of `/arbiter/scene` messages, one a line, each applied as a replay applies a
// recording's. After each one taken, a step draws the picture through the plugin drawing API into
// the manager's room for it, and the step's message is written as a replay's recording and
// Foxglove server write it (SceneUpdates). What is written must read back: a message the writer
// gives that the reader refuses is a crash here.

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "arbiter/channels.hpp"
#include "arbiter/manager.hpp"
#include "arbiter/recorded_scene.hpp"
#include "test_support.hpp"

namespace {

// A step's picture is what the input applied so far shows.
arbiter::RecordedScene& shown() {
  static arbiter::RecordedScene scene;
  return scene;
}

class Drawer final : public arbiter::Interface {
 public:
  void input(arbiter::WriteContext& ctx) override { shown().draw(ctx); }
};

struct Fixture {
  arbiter::Registry registry = arbiter::test::make_test_registry();
  arbiter::Manager manager;

  Fixture() : manager(compile(registry)) {}
  static arbiter::Program compile(arbiter::Registry& registry) {
    registry.add_interface<Drawer>("fuzz.Draw");
    return arbiter::test::compile_text(
        "arbiter: 1\nname: scene\nlayers:\n  - name: world\n    interface: fuzz.Draw\n", registry);
  }
};

Fixture& fixture() {
  static Fixture instance;
  return instance;
}

constexpr std::size_t kMaxMessages = 16;

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Fixture& f = fixture();
  shown().clear();
  arbiter::SceneUpdates updates;
  arbiter::RecordedScene read_back;
  std::string_view input(reinterpret_cast<const char*>(data), size);
  std::string error, written;
  std::uint64_t time = 0;
  for (std::size_t i = 0; i < kMaxMessages && !input.empty(); ++i) {
    const auto end = input.find('\n');
    const std::string message(input.substr(0, end));
    input = end == std::string_view::npos ? std::string_view() : input.substr(end + 1);
    if (!shown().apply(message, error)) continue;
    f.manager.step();
    written.clear();
    updates.append(time, f.manager.scene().picture(), written);
    time += 66'666'667;
    if (!read_back.apply(written, error)) __builtin_trap();
  }
  return 0;
}
