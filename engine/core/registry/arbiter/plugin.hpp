#pragma once
// Shared-library plugins: a MODULE library with two C entry points, made by ARBITER_PLUGIN:
//   arbiter_plugin_api_version()  the plugin API version it was built against, checked first;
//   arbiter_plugin_register(r)    fills a fresh registry, merged into the engine's afterwards.
// A plugin named `soccer` is the file `arbiter_soccer.so` on the plugin path.

#include <cstdio>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "arbiter/diagnostics.hpp"
#include "arbiter/document.hpp"
#include "arbiter/registry.hpp"

/// Bumped whenever a change to the engine's headers breaks plugins built against older ones.
#define ARBITER_PLUGIN_API_VERSION 8

#define ARBITER_PLUGIN_EXPORT extern "C" __attribute__((visibility("default")))

/// Defines a plugin's entry points; the body registers its classes:
///   ARBITER_PLUGIN(registry) { registry.add_behaviour<KickBall>("soccer.KickBall"); }
/// An exception thrown by the body is reported at the config line that named the plugin.
#define ARBITER_PLUGIN(registry)                                                            \
  static void arbiter_plugin_register_classes(::arbiter::Registry& registry);               \
  ARBITER_PLUGIN_EXPORT int arbiter_plugin_api_version() {                                  \
    return ARBITER_PLUGIN_API_VERSION;                                                      \
  }                                                                                         \
  ARBITER_PLUGIN_EXPORT const char* arbiter_plugin_register(::arbiter::Registry* to) {      \
    /* A plain buffer: a thread_local std::string would keep the library from unloading. */ \
    static char failure[1024];                                                              \
    try {                                                                                   \
      arbiter_plugin_register_classes(*to);                                                 \
      return nullptr;                                                                       \
    } catch (const std::exception& error) {                                                 \
      std::snprintf(failure, sizeof failure, "%s", error.what());                           \
    } catch (...) {                                                                         \
      std::snprintf(failure, sizeof failure, "%s", "unknown exception");                    \
    }                                                                                       \
    return failure;                                                                         \
  }                                                                                         \
  static void arbiter_plugin_register_classes(::arbiter::Registry& registry)

namespace arbiter {

struct PluginOptions {
  /// Searched first, in order (`--plugin-path`).
  std::vector<std::string> path;
  /// Then the directories of ARBITER_PLUGIN_PATH (colon-separated), when set.
  bool use_environment = true;
  /// Last, the plugins that came with this engine (found next to the engine library).
  bool use_default_path = true;
  /// Imports a `{python: MODULE}` plugin (`module` is its name's node, `config` the file that
  /// names it) and registers its classes under python_plugin_library(), reporting what fails at
  /// the module's name; false when it failed. Set by the Python module, the one place where
  /// Python classes can exist: without it such a plugin is reported as unavailable.
  std::function<bool(const Node& module, const std::string& config, Registry& registry,
                     Diagnostics& diagnostics)>
      import_python;
};

/// The directories a plugin name is looked up in, in order.
std::vector<std::string> plugin_search_path(const PluginOptions& options);

/// Loads a plugin (a name on the search path, or a path relative to `relative_to`'s directory
/// when it contains '/' or ends in ".so") and merges its classes into `registry`. A library
/// already loaded into the registry is not loaded again. Every failure is reported at `where`.
bool load_plugin(const std::string& name, const SourceLocation& where,
                 const std::string& relative_to, const PluginOptions& options, Registry& registry,
                 Diagnostics& diagnostics);

/// The library name under which the classes of a `{python: MODULE}` plugin are registered
/// (Registry::keep_loaded) by PluginOptions::import_python; load_plugins() imports a module once.
inline std::string python_plugin_library(std::string_view module) {
  return "python:" + std::string(module);
}

/// Loads every plugin a parsed config's `plugins:` names.
bool load_plugins(const Node& root, const PluginOptions& options, Registry& registry,
                  Diagnostics& diagnostics);

}  // namespace arbiter
