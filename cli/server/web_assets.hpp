#pragma once
// The web app (web/), bundled and compiled into the binary at build time by web/bundle.cmake (see
// cli/CMakeLists.txt), so that the views need nothing from the network and no files beside the
// binary. A build that could not bundle it holds, instead, a page that says why.

#include <cstddef>

namespace arbiter::cli::web {

/// A file the server serves as it is, without the token.
struct Asset {
  const char* path;  ///< "/", "/app.js", ...
  const char* type;  ///< the Content-Type
  const unsigned char* data;
  std::size_t size;
};

extern const Asset kAssets[];
extern const std::size_t kAssetCount;
/// Why the web app is not in this binary (npm or esbuild missing, the registry out of reach,
/// -DARBITER_WEB=OFF), or "" when it is.
extern const char* const kLeftOut;

}  // namespace arbiter::cli::web
