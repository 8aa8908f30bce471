// probe.Stamp as a plugin, for `arbiter run` in the two-process tests.

#include "arbiter/plugin.hpp"
#include "probe.hpp"

ARBITER_PLUGIN(registry) {
  arbiter::dds_test::register_probe(registry);
}
