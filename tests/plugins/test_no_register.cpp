// Has the right API version but no registration entry point.

#include "arbiter/plugin.hpp"

ARBITER_PLUGIN_EXPORT int arbiter_plugin_api_version() {
  return ARBITER_PLUGIN_API_VERSION;
}
