#pragma once
// Config files on disk, for the tests that load them whole: a scratch directory, and the whole
// load pipeline run on a file with every message checked to print.

#include <filesystem>
#include <string>
#include <vector>

#include "arbiter/diagnostics.hpp"
#include "arbiter/load.hpp"
#include "test_support.hpp"

namespace arbiter::test {

struct Outcome {
  Diagnostics diagnostics;
  bool loaded = false;
};

/// The whole pipeline (read, plugins, validate, compile) on a file, with the test classes.
Outcome load_file(const std::filesystem::path& path, const LoadOptions& options = {});

/// The codes of the errors reported, in order.
std::vector<std::string> error_codes(const Diagnostics& diagnostics);

}  // namespace arbiter::test
