// The Foxglove server of a build without websocketpp (cli/CMakeLists.txt): --foxglove says why
// it is not there.

#include <fmt/format.h>

#include "server/foxglove.hpp"

#ifndef ARBITER_FOXGLOVE_LEFT_OUT
#define ARBITER_FOXGLOVE_LEFT_OUT "it was left out of the build"
#endif

namespace arbiter::cli {

std::string foxglove_left_out() {
  return ARBITER_FOXGLOVE_LEFT_OUT;
}

struct FoxgloveServer::Impl {
  struct Nothing : Observer {
    void on_step(const Manager&) override {}
  } nothing;
};

FoxgloveServer::FoxgloveServer() : impl_(std::make_unique<Impl>()) {}
FoxgloveServer::~FoxgloveServer() = default;

std::unique_ptr<FoxgloveServer> FoxgloveServer::open(const std::string&, int,
                                                     std::string_view command, const std::string&,
                                                     std::ostream&, std::ostream& err) {
  err << fmt::format(
      "arbiter {}: --foxglove: this arbiter was built without the Foxglove WebSocket server ({}); "
      "docs/foxglove.md tells how to build it\n",
      command, foxglove_left_out());
  return nullptr;
}

std::string FoxgloveServer::url() const {
  return "";
}
FoxgloveCounts FoxgloveServer::counts() const {
  return {};
}
std::string FoxgloveServer::summary(std::string_view) const {
  return "";
}
void FoxgloveServer::set_paced(bool) {}
void FoxgloveServer::set_scene_rate(double) {}
void FoxgloveServer::stop() {}
Observer& FoxgloveServer::observer() {
  return impl_->nothing;
}

}  // namespace arbiter::cli
