#pragma once
// engine/tools/lint: a Model and its Program in; warnings out, each with a code and a place, for a
// config that runs but probably does not do what was meant.
//
// Lints: warnings about a config that loads and runs but probably does not do what was meant.
// They run after compile, on the model (what was written, and where) and the program (the
// chaining closure and the actuator wiring). Each has a stable code (docs/lints.md) and can be
// silenced in the config with `lint: {ignore: [code, ...]}`, at the top level for the whole
// config or in a layer for that layer.

#include <string_view>
#include <vector>

#include "arbiter/diagnostics.hpp"
#include "arbiter/model.hpp"
#include "arbiter/program.hpp"

namespace arbiter {

struct LintCode {
  std::string_view code;     ///< stable, kebab-case
  std::string_view summary;  ///< one line, for `--help` and docs
};

/// Every lint, in the order docs/lints.md describes them.
const std::vector<LintCode>& lint_codes();

/// Reports the lints of a compiled config as warnings, except those the config silences. A code
/// in `lint: {ignore: ...}` that names no lint is itself reported (`unknown-lint`).
/// `program` must be compiled from `model`.
void lint(const Model& model, const Program& program, Diagnostics& diagnostics);

}  // namespace arbiter
