#pragma once
// The page of the web view, compiled into the binary from cli/web/ (see cli/CMakeLists.txt), so
// that it needs nothing from the network.

namespace arbiter::cli::web {

extern const char* const kIndexHtml;
extern const char* const kAppJs;
extern const char* const kStyleCss;

}  // namespace arbiter::cli::web
