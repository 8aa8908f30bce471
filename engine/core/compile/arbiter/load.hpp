#pragma once
// The load pipeline as one call: read → document → model → program, then the lints when the caller
// brings them. What every caller needs comes back together: the files read (text and tree), the
// model, the program and the diagnostics.

#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "arbiter/diagnostics.hpp"
#include "arbiter/document.hpp"
#include "arbiter/model.hpp"
#include "arbiter/plugin.hpp"
#include "arbiter/program.hpp"
#include "arbiter/registry.hpp"

namespace arbiter {

/// Options for the whole pipeline.
struct LoadOptions {
  ReadLimits limits;
  PluginOptions plugins;
  bool strict = false;  ///< warnings are errors
  /// Where files are read from (must outlive the call); nullptr: the disk.
  const FileSource* source = nullptr;
  /// Changes the validated model before it is compiled, when validation found no error: how
  /// scenario tests and replay put other classes in. Reports into the diagnostics it is given
  /// and returns false, after reporting an error, to stop the load before compile.
  std::function<bool(Model&, Diagnostics&)> edit_model;
  /// Runs on the compiled program when no stage reported an error; what it reports joins the
  /// diagnostics. The lints are in the tools library, not in the core one a robot runs:
  /// `options.lint = arbiter::lint` (arbiter/lint.hpp, arbiter::tools) lints; empty, no lints.
  std::function<void(const Model&, const Program&, Diagnostics&)> lint;
};

/// What one load produced.
struct Loaded {
  /// Every file read, the config first, with its text and (when it parsed) its tree.
  SourceFiles files;
  /// Set once the config was read far enough to be validated; meaningful only without errors.
  /// Shared with the program (Program::model).
  std::shared_ptr<Model> model;
  /// Set when no stage reported an error.
  std::optional<Program> program;
  /// Every stage's errors, warnings and lints, sorted (warnings promoted under `strict`).
  Diagnostics diagnostics;

  /// The config's tree, or nullptr when it could not be read or parsed.
  const Node* document() const;
};

/// read the file → load the plugins it names into `registry` → build_model → compile → the lint
/// step of `options`.
/// Every stage that can run does, so that one load reports every problem.
Loaded load_config(const std::string& path, Registry& registry, const LoadOptions& options = {});

/// The program of load_config(), reporting into `diagnostics`; nullopt when any stage failed.
std::optional<Program> load(const std::string& path, Registry& registry, Diagnostics& diagnostics,
                            const LoadOptions& options = {});

/// The same, throwing one ConfigError carrying every diagnostic.
Program load_program(const std::string& path, Registry& registry, const LoadOptions& options = {});

}  // namespace arbiter
