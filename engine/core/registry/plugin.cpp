#include "arbiter/plugin.hpp"

#include <dlfcn.h>
#include <fmt/format.h>

#include <cstdlib>
#include <filesystem>
#include <functional>
#include <memory>

#include "arbiter/state.hpp"

namespace arbiter {

namespace fs = std::filesystem;

namespace {

// The directory of the engine library itself, whence its own plugins are found both in a build
// tree (build/engine/libarbiter.so → build/plugins) and when installed (lib/libarbiter.so →
// lib/arbiter/plugins).
std::vector<std::string> default_plugin_dirs() {
  Dl_info info{};
  if (dladdr(reinterpret_cast<void*>(&default_plugin_dirs), &info) == 0 ||
      info.dli_fname == nullptr) {
    return {};
  }
  std::error_code error;
  const fs::path library = fs::weakly_canonical(info.dli_fname, error);
  const fs::path dir = library.parent_path();
  std::vector<std::string> dirs;
  for (const fs::path& candidate : {dir / "arbiter" / "plugins", dir.parent_path() / "plugins"}) {
    if (fs::is_directory(candidate, error)) dirs.push_back(candidate.lexically_normal().string());
  }
  return dirs;
}

std::string file_name_of(const std::string& name) {
  return "arbiter_" + name + ".so";
}

bool is_path(const std::string& name) {
  return name.find('/') != std::string::npos ||
         (name.size() > 3 && name.compare(name.size() - 3, 3, ".so") == 0);
}

struct LibraryCloser {
  void operator()(void* handle) const {
    if (handle != nullptr) dlclose(handle);
  }
};

/// A plugin's factory together with its library. Destroying a std::function runs code of the
/// library that made it, so each factory keeps its library loaded itself: a ClassInfo, wherever
/// it is and in whatever order its owner destroys its members, never outlives that code.
template <typename Result>
struct LibraryFactory {
  std::shared_ptr<void> library;  // declared first: released after the factory
  std::function<Result()> factory;
  Result operator()() const { return factory(); }
};

template <typename Result>
void hold_library(std::function<Result()>& factory, const std::shared_ptr<void>& library) {
  if (factory) factory = LibraryFactory<Result>{library, std::move(factory)};
}

}  // namespace

std::vector<std::string> plugin_search_path(const PluginOptions& options) {
  std::vector<std::string> dirs = options.path;
  if (options.use_environment) {
    if (const char* variable = std::getenv("ARBITER_PLUGIN_PATH")) {
      std::string list = variable;
      std::size_t start = 0;
      while (start <= list.size()) {
        const std::size_t end = std::min(list.find(':', start), list.size());
        if (end > start) dirs.push_back(list.substr(start, end - start));
        start = end + 1;
      }
    }
  }
  if (options.use_default_path) {
    for (auto& dir : default_plugin_dirs()) dirs.push_back(std::move(dir));
  }
  return dirs;
}

bool load_plugin(const std::string& name, const SourceLocation& where,
                 const std::string& relative_to, const PluginOptions& options, Registry& registry,
                 Diagnostics& diagnostics) {
  std::error_code error;
  fs::path file;
  if (is_path(name)) {
    file = fs::path(relative_to).parent_path() / name;
    if (!fs::is_regular_file(file, error)) {
      diagnostics.error(where, "plugin-not-found",
                        fmt::format("plugin file '{}' not found (looked for {})", name,
                                    file.lexically_normal().string()));
      return false;
    }
  } else {
    const auto dirs = plugin_search_path(options);
    for (const auto& dir : dirs) {
      const fs::path candidate = fs::path(dir) / file_name_of(name);
      if (fs::is_regular_file(candidate, error)) {
        file = candidate;
        break;
      }
    }
    if (file.empty()) {
      auto& diagnostic = diagnostics.error(
          where, "plugin-not-found",
          fmt::format("plugin '{}' not found: no {} on the plugin path", name, file_name_of(name)));
      for (const auto& dir : dirs) diagnostic.notes.push_back("looked in " + dir);
      if (dirs.empty()) diagnostic.notes.push_back("the plugin path is empty");
      diagnostic.notes.push_back(
          "add directories with --plugin-path DIR or ARBITER_PLUGIN_PATH, or name the file "
          "relative to the config ('./libs/arbiter_x.so')");
      return false;
    }
  }
  const std::string path = fs::weakly_canonical(file, error).string();
  if (registry.has_library(path)) return true;

  dlerror();
  std::shared_ptr<void> library(dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL), LibraryCloser{});
  if (!library) {
    const char* reason = dlerror();
    diagnostics.error(where, "plugin-load-failed",
                      fmt::format("cannot load plugin '{}' ({}): {}", name, path,
                                  reason != nullptr ? reason : "unknown dlopen error"));
    return false;
  }
  // The version comes first: a plugin built for another API version may have other entry points,
  // and its registration function may expect another Registry.
  using VersionFunction = int (*)();
  using RegisterFunction = const char* (*)(Registry*);
  auto lacks = [&](const char* entry_point) {
    diagnostics
        .error(where, "not-a-plugin",
               fmt::format("'{}' ({}) is not an Arbiter plugin: it lacks the entry point {}", name,
                           path, entry_point))
        .notes.push_back("a plugin defines its entry points with ARBITER_PLUGIN(registry) { ... }");
    return false;
  };
  auto version =
      reinterpret_cast<VersionFunction>(dlsym(library.get(), "arbiter_plugin_api_version"));
  if (version == nullptr) return lacks("arbiter_plugin_api_version");
  if (const int built_for = version(); built_for != ARBITER_PLUGIN_API_VERSION) {
    diagnostics
        .error(where, "plugin-api-mismatch",
               fmt::format("plugin '{}' ({}) was built for plugin API version {}; this Arbiter "
                           "has version {}",
                           name, path, built_for, ARBITER_PLUGIN_API_VERSION))
        .notes.push_back("rebuild the plugin against this Arbiter's headers");
    return false;
  }
  auto register_classes =
      reinterpret_cast<RegisterFunction>(dlsym(library.get(), "arbiter_plugin_register"));
  if (register_classes == nullptr) return lacks("arbiter_plugin_register");
  Registry fresh;
  fresh.set_origin(fmt::format("plugin {} ({})", name, path));
  if (const char* failure = register_classes(&fresh)) {
    diagnostics.error(
        where, "plugin-register-failed",
        fmt::format("plugin '{}' ({}) failed to register its classes: {}", name, path, failure));
    return false;
  }
  for (const auto& entry : fresh.classes()) {
    // `fresh` is ours: its classes may be changed. Each is the library's ClassBinder<T>, whose
    // destructor is the library's code: a plain ClassInfo takes its place, so that the class
    // may outlive the library's registry (registration is over; nothing binds members now).
    auto& slot = const_cast<std::unique_ptr<ClassInfo>&>(entry.second);
    slot = std::make_unique<ClassInfo>(std::move(*slot));
    ClassInfo& info = *slot;
    hold_library(info.make_behaviour, library);
    hold_library(info.make_interface, library);
    hold_library(info.make_state, library);
  }
  const std::size_t errors = diagnostics.error_count();
  registry.merge(std::move(fresh), where, diagnostics);
  // Classes merged from the library (even when some clashed) run its code: keep it loaded.
  registry.keep_loaded(path, std::move(library));
  return diagnostics.error_count() == errors;
}

namespace {

/// A `{python: MODULE}` plugin is Python code (python_plugin_library()): imported by the Python
/// module's hook, and reported, at the module's name, anywhere else (the CLI).
bool load_python_plugin(const Node& module, const std::string& config, const PluginOptions& options,
                        Registry& registry, Diagnostics& diagnostics) {
  if (!module.is_scalar() || module.text().empty()) return true;  // validation reports it
  if (registry.has_library(python_plugin_library(module.text()))) return true;
  if (options.import_python) return options.import_python(module, config, registry, diagnostics);
  diagnostics
      .error(module.location(), "python-plugin-unavailable",
             fmt::format("plugin '{}' is a Python module: its classes exist only when the config "
                         "is loaded from Python",
                         module.text()))
      .notes.push_back("load it with the Python module: arbiter.load(\"CONFIG\") (docs/python.md)");
  return false;
}

}  // namespace

bool load_plugins(const Node& root, const PluginOptions& options, Registry& registry,
                  Diagnostics& diagnostics) {
  const Node* plugins = root.is_mapping() ? root.find("plugins") : nullptr;
  if (plugins == nullptr || !plugins->is_sequence()) return true;  // validation reports the rest
  bool ok = true;
  for (const auto& item : plugins->items()) {
    if (const Node* module = item.is_mapping() ? item.find("python") : nullptr) {
      ok = load_python_plugin(*module, root.location().file, options, registry, diagnostics) && ok;
      continue;
    }
    if (!item.is_scalar() || item.text().empty()) continue;
    ok = load_plugin(item.text(), item.location(), root.location().file, options, registry,
                     diagnostics) &&
         ok;
  }
  return ok;
}

}  // namespace arbiter
