// The server of a binary built without the web app (-DARBITER_WEB=OFF, or no npm or esbuild, or
// the npm registry out of reach): it serves a page that says why, and how to get the app, and
// the CLI notes it. Linked with the assets web/bundle.cmake writes when the app is left out.
// And ARBITER_WEB_DIR, which serves the app's files from a directory instead, and the reasons
// the server gives for what it refuses by itself.

#include <arpa/inet.h>
#include <httplib.h>
#include <netinet/in.h>
#include <stdlib.h>
#include <sys/socket.h>
#include <unistd.h>

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

TEST_CASE("what the server refuses by itself is answered with the reason, not a bare status",
          "[web]") {
  WebServer server;
  std::string error;
  REQUIRE(server.start(ServeAddress{}, LiveAccess{"fallback-token", false}, error));
  const std::string url = server.url();
  const int port = std::stoi(url.substr(url.rfind(':') + 1));
  httplib::Client client("127.0.0.1", port);
  const httplib::Headers token{{"X-Arbiter-Token", "fallback-token"}};

  const auto missing = client.Get("/no-such-page", token);
  REQUIRE(missing);
  CHECK(missing->status == 404);
  CHECK(missing->body == "not found: /no-such-page is not a page of this server\n");

  const auto long_uri = client.Get("/" + std::string(9000, 'a'), token);
  REQUIRE(long_uri);
  CHECK(long_uri->status == 414);
  CHECK(contains(long_uri->body, "the request's URI is longer than 8192 bytes"));

  const auto form = client.Post("/control/pause", token, std::string(10000, 'a'),
                                "application/x-www-form-urlencoded");
  REQUIRE(form);
  CHECK(form->status == 413);
  CHECK(contains(form->body, "the request's body is too long"));

  // A request that is not HTTP: read over a plain socket.
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  REQUIRE(fd >= 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  REQUIRE(::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) == 0);
  const std::string garbage = "NOT HTTP AT ALL\r\n\r\n";
  REQUIRE(::write(fd, garbage.data(), garbage.size()) == static_cast<ssize_t>(garbage.size()));
  std::string reply;
  char buffer[4096];
  for (ssize_t got; (got = ::read(fd, buffer, sizeof buffer)) > 0;) reply.append(buffer, got);
  ::close(fd);
  CHECK(contains(reply, "HTTP/1.1 400"));
  CHECK(contains(reply, "bad request: not an HTTP request this server can read"));
  server.stop();
}
