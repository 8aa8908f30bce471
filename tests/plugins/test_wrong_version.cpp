// A plugin built against a newer plugin API than this engine's. The entry points are written by
// hand to claim another version; the registration must never be called.

#include <cstdlib>

#include "arbiter/plugin.hpp"

ARBITER_PLUGIN_EXPORT int arbiter_plugin_api_version() {
  return ARBITER_PLUGIN_API_VERSION + 1;
}

ARBITER_PLUGIN_EXPORT const char* arbiter_plugin_register(arbiter::Registry*) {
  std::abort();
}
