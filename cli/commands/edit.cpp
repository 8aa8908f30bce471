// `arbiter edit CONFIG`: the studio (docs/studio.md), a browser editor of a config served until
// Ctrl-C.

#include <fmt/format.h>
#include <httplib.h>

#include <chrono>
#include <iostream>
#include <thread>

#include "commands/command.hpp"
#include "server/serve.hpp"
#include "server/studio.hpp"

namespace arbiter::cli {

int edit_command(const Options& options) {
  auto registry = make_registry();
  Studio studio(options.file, registry, load_options_of(options));
  WebServer server;
  studio.attach(server.http());
  server.http().Get("/info", [](const httplib::Request&, httplib::Response& response) {
    response.set_content(R"({"mode": "studio"})", "application/json");
  });
  std::string error;
  const auto address = ServeAddress::parse(options.edit_serve, error);
  LiveAccess access;
  access.token = options.serve_token;
  if (!error.empty() || !server.start(address, access, error)) {
    std::cerr << fmt::format("arbiter edit: --serve: {}\n", error);
    return kExitUsage;
  }
  std::cerr << web_app_note();
  std::cerr << exposure_warning(address, "read and change the config's files (with its token)");
  install_interrupt_handlers();
  std::cout << fmt::format("editing {} in the studio at {}\nCtrl-C stops.\n", options.file,
                           server.page_url())
            << std::flush;
  while (!interrupted) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  server.stop();
  return kExitOk;
}

}  // namespace arbiter::cli
