// The load pipeline (engine/src/load.cpp) as the language server and reload use it.

#include <catch2/catch.hpp>
#include <filesystem>
#include <string>
#include <vector>

#include "arbiter/load.hpp"
#include "test_support.hpp"

using namespace arbiter;

TEST_CASE("load_config reads texts held in memory before the disk, for included files too",
          "[load]") {
  const auto dir = std::filesystem::temp_directory_path() / "arbiter_overlay_test";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string main = (dir / "main.yaml").string();
  const std::string part = (dir / "part.yaml").string();
  test::write_text(main,
                   "arbiter: 1\nname: m\ninclude: [part.yaml]\nlayers:\n  - name: control\n"
                   "    behaviours:\n      a: {type: scripted, params: {activation: 1}}\n");
  test::write_text(part, "arbiter: 1\nlayers:\n  - name: other\n");
  Registry registry = test::make_test_registry();

  Overlay overlay;
  overlay.set(part, "arbiter: 1\nlayers:\n  - name: other\n    sensors: [sped]\n");
  LoadOptions options;
  options.source = &overlay;
  Loaded loaded = load_config(main, registry, options);
  REQUIRE_FALSE(loaded.program);
  REQUIRE(loaded.diagnostics.items().size() == 1);
  CHECK(loaded.diagnostics.items()[0].location.file == part);
  CHECK(loaded.diagnostics.items()[0].location.line == 4);
  REQUIRE(loaded.files.files().size() == 2);
  CHECK(loaded.files.files()[1]->text == *overlay.find(part));
  REQUIRE(loaded.model);
  CHECK(loaded.model->files == std::vector<std::string>{main, part});

  overlay.erase(part);  // the disk again
  Loaded fixed = load_config(main, registry, options);
  CHECK(fixed.program);
  CHECK(fixed.diagnostics.empty());
  CHECK(fixed.document() != nullptr);
  std::filesystem::remove_all(dir);
}
