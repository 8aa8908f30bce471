// The main of every Catch2 test binary: Catch2's own, with two warnings always on, as errors.
// NoTests: a test name (as CTest passes it) that matches no test fails instead of passing.
// NoAssertions: a test or section that asserts nothing fails, since it could not catch a
// regression. Catch2 2 takes only one --warn on its command line, so they are set here.
#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>

int main(int argc, char* argv[]) {
  Catch::Session session;
  if (const int error = session.applyCommandLine(argc, argv)) return error;
  auto& config = session.configData();
  config.warnings = static_cast<Catch::WarnAbout::What>(
      config.warnings | Catch::WarnAbout::NoTests | Catch::WarnAbout::NoAssertions);
  return session.run();
}
