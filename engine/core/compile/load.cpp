#include "arbiter/load.hpp"

#include "core/compile/layer_order.hpp"

namespace arbiter {

const Node* Loaded::document() const {
  const auto& read = files.files();
  return read.empty() || !read.front()->root ? nullptr : &*read.front()->root;
}

Loaded load_config(const std::string& path, Registry& registry, const LoadOptions& options) {
  Loaded loaded{SourceFiles(options.source ? *options.source : disk(), options.limits), {}, {}, {}};
  Diagnostics& diagnostics = loaded.diagnostics;
  if (const Node* document = loaded.files.read(path, diagnostics)) {
    // Plugins first: their classes are what the model is checked against. A plugin that fails
    // still lets validation run, so that every other problem is reported too.
    load_plugins(*document, options.plugins, registry, diagnostics);
    loaded.model =
        std::make_shared<Model>(build_model(*document, registry, diagnostics, loaded.files));
    Model& model = *loaded.model;
    if (diagnostics.has_errors()) {
      detail::check_inhibition_cycles(model, diagnostics);  // a cycle is reported in the same pass
    } else if (!options.edit_model || options.edit_model(model, diagnostics)) {
      loaded.program = compile(model, registry, diagnostics);
      if (loaded.program) loaded.program->model = loaded.model;
      if (loaded.program && options.lint) options.lint(model, *loaded.program, diagnostics);
    }
  }
  if (options.strict) diagnostics.promote_warnings();
  diagnostics.sort();
  if (diagnostics.has_errors()) loaded.program.reset();
  return loaded;
}

std::optional<Program> load(const std::string& path, Registry& registry, Diagnostics& diagnostics,
                            const LoadOptions& options) {
  Loaded loaded = load_config(path, registry, options);
  if (diagnostics.empty()) {
    diagnostics = std::move(loaded.diagnostics);
  } else {
    diagnostics.append(loaded.diagnostics);
    diagnostics.sort();
  }
  return std::move(loaded.program);
}

Program load_program(const std::string& path, Registry& registry, const LoadOptions& options) {
  Diagnostics diagnostics;
  auto program = load(path, registry, diagnostics, options);
  if (!program) throw ConfigError(std::move(diagnostics));
  return std::move(*program);
}

}  // namespace arbiter
