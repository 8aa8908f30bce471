// A plugin from a future plugin API whose registration entry point has another name: the version
// alone must be enough to tell why it cannot be loaded.

#include "arbiter/plugin.hpp"

ARBITER_PLUGIN_EXPORT int arbiter_plugin_api_version() {
  return ARBITER_PLUGIN_API_VERSION + 1;
}

ARBITER_PLUGIN_EXPORT const char* arbiter_plugin_register_v2(arbiter::Registry*, int) {
  return nullptr;
}
