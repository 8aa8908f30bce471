// A bad DDS parameter is a config error at its file:line:col. Each config in tests/dds/invalid is
// validated by the CLI (which loads the dds plugin) and its output compared with the approved
// `<case>.expected` beside it; ARBITER_UPDATE_GOLDEN=1 rewrites them (review the diff by eye).

#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "dds_support.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using namespace arbiter::dds_test;
using namespace std::chrono_literals;

namespace {

const fs::path kInvalidDir = fs::path(ARBITER_SOURCE_DIR) / "tests" / "dds" / "invalid";

using arbiter::test::files_in;
using arbiter::test::read_text;
using arbiter::test::update_golden;

}  // namespace

TEST_CASE("a bad DDS parameter is a config error at its file, line and column", "[dds]") {
  const auto cases =
      files_in(kInvalidDir, [](const fs::path& path) { return path.extension() == ".yaml"; });
  REQUIRE(cases.size() >= 8);
  TempDir dir;
  for (const auto& path : cases) {
    const std::string name = path.filename().string();
    DYNAMIC_SECTION(name) {
      Child validate({ARBITER_CLI, "validate", name}, dir.file("output.txt"), kInvalidDir.string());
      const auto status = validate.wait(60s);
      REQUIRE(status);
      CHECK(*status == 1);
      const std::string actual = validate.output();
      const fs::path expected = fs::path(path).replace_extension(".expected");
      if (update_golden()) {
        std::ofstream(expected, std::ios::binary | std::ios::trunc) << actual;
        WARN("rewrote " << expected.filename().string());
      } else {
        CHECK(actual == read_text(expected));
      }
    }
  }
}
