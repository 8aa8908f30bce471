// What every subcommand shares: the registry, loading a config, reporting its diagnostics.

#include "commands/command.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <thread>
#include <utility>

#include "arbiter/lint.hpp"
#include "builtins.hpp"
#include "server/foxglove.hpp"
#include "server/serve.hpp"

namespace arbiter::cli {

bool use_color(const std::string& choice, std::FILE* stream) {
  if (choice != "auto") return choice == "always";
  const char* term = std::getenv("TERM");
  return isatty(fileno(stream)) != 0 && std::getenv("NO_COLOR") == nullptr && term != nullptr &&
         std::string_view(term) != "dumb";
}

arbiter::Registry make_registry() {
  arbiter::Registry registry;
  arbiter::register_builtin_behaviours(registry);
  return registry;
}

void print_diagnostics(const arbiter::Diagnostics& diagnostics, const Options& options) {
  if (options.format == "json") {
    std::cout << arbiter::format_json(diagnostics);
  } else {
    std::cerr << arbiter::format(diagnostics, options.diagnostic_format);
  }
}

arbiter::LoadOptions load_options_of(const Options& options) {
  arbiter::LoadOptions load_options;
  load_options.strict = options.strict;
  load_options.lint = arbiter::lint;
  load_options.plugins.path = options.plugin_path;
  if (options.max_file_bytes) load_options.limits.max_file_bytes = *options.max_file_bytes;
  return load_options;
}

std::optional<arbiter::Program> load_or_report(const std::string& path, arbiter::Registry& registry,
                                               const Options& options, arbiter::Diagnostics* kept) {
  arbiter::Diagnostics diagnostics;
  auto program = arbiter::load(path, registry, diagnostics, load_options_of(options));
  if (!diagnostics.empty()) std::cerr << arbiter::format(diagnostics, options.diagnostic_format);
  if (kept != nullptr) *kept = std::move(diagnostics);
  return program;
}

std::atomic<bool> interrupted{false};

namespace {
extern "C" void on_interrupt(int) {
  interrupted = true;
}
}  // namespace

void install_interrupt_handlers() {
  std::signal(SIGINT, on_interrupt);
  std::signal(SIGTERM, on_interrupt);
}

std::unique_ptr<FoxgloveServer> open_foxglove(const Options& options, std::string_view command,
                                              std::ostream& out, std::ostream& err) {
  std::string error;
  const auto address = ServeAddress::parse(options.foxglove, error);
  if (!error.empty()) {
    err << fmt::format("arbiter {}: --foxglove: {}\n", command, error);
    return nullptr;
  }
  auto server = FoxgloveServer::open(address.host, address.port, command,
                                     fmt::format("arbiter {}", kVersion), out, err);
  if (server) {
    server->set_scene_rate(options.foxglove_scene_rate);
    err << exposure_warning(address,
                            "watch the run: the Foxglove WebSocket protocol has no authentication");
  }
  return server;
}

void foxglove_after_run(FoxgloveServer& server, std::string_view command, std::ostream& out,
                        std::ostream& err) {
  const std::string summary = server.summary(command);
  err << summary;
  // Interrupted already (Ctrl-C during the steps, or after --serve's page), or no run started (a
  // replay that could not start): it stops at once.
  if (!interrupted && server.counts().started) {
    out << fmt::format("the {} is over; the Foxglove server stays at {} until Ctrl-C\n", command,
                       server.url())
        << std::flush;
    install_interrupt_handlers();
    while (!interrupted) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  server.stop();
}

}  // namespace arbiter::cli
