#pragma once
// Shared by the tests of the tools around the engine (schema, dump, lint, explain, the CLI): the
// source tree's places, the golden files, the registries they load with, and the CLI run from the
// source directory.

#include <filesystem>
#include <string>
#include <vector>

#include "arbiter/diagnostics.hpp"
#include "arbiter/program.hpp"
#include "arbiter/registry.hpp"
#include "test_support.hpp"

namespace arbiter::test {

extern const std::filesystem::path kSourceDir;
extern const std::filesystem::path kDataDir;
extern const std::filesystem::path kGoldenDir;
extern const char* const kWalkAndKick;

/// Compares `actual` with the golden file `name` (or rewrites it in update mode).
void check_golden(const std::string& name, const std::string& actual);

/// The test registry plus the classes the invalid configs use (tests/data/invalid).
Registry tooling_registry();

Registry builtin_registry();

bool is_config(const std::filesystem::path& path);

/// Every config file under `dir`, recursively, sorted.
std::vector<std::filesystem::path> configs_under(const std::filesystem::path& dir);

/// Whether the plugins a config names are built here (a plugin with optional dependencies, such
/// as dds, may not be); tells the test log when one is not. Only dds may be missing.
bool plugins_built(const std::filesystem::path& config);

/// Runs `arbiter ARGUMENTS` in the source directory (paths relative to it), capturing both streams.
CliResult run_cli(const std::string& arguments);

/// `path` in double quotes, for a command line.
std::string quoted(const std::filesystem::path& path);

bool contains(const std::string& text, const std::string& part);

/// Loads a config as `arbiter` does (relative to the source directory), with the test classes.
Program load_config(const std::string& relative, Registry& registry, Diagnostics& diagnostics);

/// The trace of `steps` steps of a config, as `arbiter run --trace` writes it.
std::string trace_of(const std::string& relative, int steps);

}  // namespace arbiter::test
