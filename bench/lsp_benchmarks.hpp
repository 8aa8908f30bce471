#pragma once

namespace arbiter::bench {

/// Registers lsp/change/<N>: diagnostics after an edit, through the language server's handlers.
void register_lsp_benchmarks();

}  // namespace arbiter::bench
