// The server of a binary built without the web app (-DARBITER_WEB=OFF, or no npm or esbuild, or
// the npm registry out of reach): it serves a page that says why, and how to get the app, and
// the CLI notes it. Linked with the assets web/bundle.cmake writes when the app is left out.
// And ARBITER_WEB_DIR, which serves the app's files from a directory instead.

#include <httplib.h>
#include <stdlib.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <string>

#include "server/serve.hpp"

using namespace arbiter::cli;

namespace {

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

}  // namespace

TEST_CASE("a build without the web app serves a page that says so, and why", "[web]") {
  WebServer server;
  std::string error;
  REQUIRE(server.start(ServeAddress{}, LiveAccess{"fallback-token", false}, error));
  INFO(error);
  const std::string url = server.url();  // http://127.0.0.1:PORT/
  const int port = std::stoi(url.substr(url.rfind(':') + 1));
  httplib::Client client("127.0.0.1", port);

  const auto page = client.Get("/");
  REQUIRE(page);
  CHECK(page->status == 200);
  CHECK(contains(page->get_header_value("Content-Type"), "text/html"));
  CHECK(contains(page->body, "The web app was not built into this arbiter"));
  CHECK(contains(page->body, "the build was configured with -DARBITER_WEB=OFF"));
  CHECK(contains(page->body, "scripts/install-deps.sh"));
  // The app's script is not there: like any other path, it needs the token, and then is not found.
  CHECK(client.Get("/app.js")->status == 403);
  CHECK(client.Get("/app.js", {{"X-Arbiter-Token", "fallback-token"}})->status == 404);
  server.stop();

  // `arbiter run --serve` and `arbiter view` print this when they start serving.
  CHECK(web_app_note() ==
        "note: this arbiter was built without its web app (the build was configured with "
        "-DARBITER_WEB=OFF): the page says so, and docs/live_view.md tells how to build it\n");
}

TEST_CASE("ARBITER_WEB_DIR serves the web app's files from a directory, read at each request",
          "[web]") {
  const std::string dir = std::filesystem::temp_directory_path() / "arbiter-web-dir-test";
  std::filesystem::create_directories(dir);
  std::ofstream(dir + "/index.html") << "<p>first</p>";
  REQUIRE(setenv("ARBITER_WEB_DIR", dir.c_str(), 1) == 0);
  WebServer server;
  REQUIRE(unsetenv("ARBITER_WEB_DIR") == 0);
  std::string error;
  REQUIRE(server.start(ServeAddress{}, LiveAccess{"fallback-token", false}, error));
  const std::string url = server.url();
  httplib::Client client("127.0.0.1", std::stoi(url.substr(url.rfind(':') + 1)));
  CHECK(client.Get("/")->body == "<p>first</p>");
  // An edit (a bundler's watch mode writing the directory) shows at the next load.
  std::ofstream(dir + "/index.html") << "<p>second</p>";
  CHECK(client.Get("/")->body == "<p>second</p>");
  std::filesystem::remove_all(dir);
  const auto missing = client.Get("/");
  CHECK(missing->status == 404);
  CHECK(contains(missing->body, "ARBITER_WEB_DIR: cannot read " + dir + "/index.html"));
  server.stop();
}
