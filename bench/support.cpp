#include "support.hpp"

#include <malloc.h>
#include <time.h>

#include <algorithm>
#include <iostream>
#include <vector>

#include "arbiter/init_context.hpp"
#include "arbiter/plugin.hpp"
#include "arbiter/state.hpp"
#include "builtins.hpp"

namespace arbiter::bench {

namespace {

/// Proceeds after every execution; appends `append` when it does. Costs the engine nothing
/// beyond the transition and the queue edits, so the SCL benchmark measures the controller.
class Proceed final : public State {
 public:
  void init(StateInitContext& ctx) override {
    for (const auto& state : append_names_) {
      PlannedState planned;
      if (ctx.plan_state(state, nullptr, ctx.param_location(&Proceed::append_names_), planned)) {
        append_.push_back(std::move(planned));
      }
    }
  }

  StateResult execute(StateContext& ctx) override {
    for (const auto& planned : append_) ctx.plan().append(planned);
    return StateResult::kProceed;
  }

 private:
  friend Registry arbiter::bench::make_registry();
  std::vector<std::string> append_names_;
  std::vector<PlannedState> append_;
};

/// Requests a fixed level; while active, writes half its input plus one to its output. The
/// ports are optional: unbound, they cost one branch.
class Trivial final : public Behaviour {
 public:
  double activation(const StepContext&) override { return level_; }
  void execute(ExecuteContext& ctx) override { ctx.write(out_, 0.5 * ctx.read(in_) + 1.0); }

 private:
  friend Registry arbiter::bench::make_registry();
  double level_ = 0.0;
  Input<double> in_;
  Output<double> out_;
};

}  // namespace

Registry make_registry() {
  Registry registry;
  register_builtin_behaviours(registry);
  auto& trivial = registry.add_behaviour<Trivial>("bench.Trivial")
                      .describe("Requests a fixed level; writes 0.5 * in + 1 to out while active.");
  trivial.param("activation", &Trivial::level_).range(0.0, 1.0).describe("the requested level");
  trivial.port("in", &Trivial::in_).make_optional().describe("read while active");
  trivial.port("out", &Trivial::out_).make_optional().describe("written while active");
  add_state_class<Proceed>(registry, "bench.Proceed")
      .describe("Proceeds after every execution, appending `append` to the plan when it does.")
      .param("append", &Proceed::append_names_)
      .defaults_to(std::vector<std::string>{})
      .state_level()
      .describe("states to append when proceeding");
  return registry;
}

Program compile_text(const std::string& text, Registry& registry, const std::string& file) {
  Overlay overlay;
  overlay.set(file, text);
  LoadOptions options;
  options.source = &overlay;
  return load_program(file, registry, options);
}

std::size_t heap_in_use() {
#if defined(__GLIBC__) && (__GLIBC__ > 2 || (__GLIBC__ == 2 && __GLIBC_MINOR__ >= 33))
  const struct mallinfo2 info = mallinfo2();
  return info.uordblks + info.hblkhd;  // small chunks in use + mmapped ones
#else
  return 0;
#endif
}

std::optional<Program> load_timed(const std::string& path, Registry& registry,
                                  const LoadOptions& options, LoadTimes& times) {
  Diagnostics diagnostics;
  const auto report = [&] {
    diagnostics.sort();
    std::cerr << format(diagnostics);
    return std::nullopt;
  };
  auto start = std::chrono::steady_clock::now();
  auto document = read_document(path, diagnostics, options.limits);
  times.parse_ms = milliseconds_since(start);
  if (!document) return report();

  start = std::chrono::steady_clock::now();
  load_plugins(*document, options.plugins, registry, diagnostics);
  const Model model = build_model(*document, registry, diagnostics, options.limits);
  times.validate_ms = milliseconds_since(start);
  if (diagnostics.has_errors()) return report();

  start = std::chrono::steady_clock::now();
  auto program = compile(model, registry, diagnostics);
  times.compile_ms = milliseconds_since(start);
  if (!program) return report();
  return program;
}

double fastest(const std::vector<double>& values) {
  return values.empty() ? 0.0 : *std::min_element(values.begin(), values.end());
}

double cpu_seconds() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + static_cast<double>(now.tv_nsec) * 1e-9;
}

}  // namespace arbiter::bench
