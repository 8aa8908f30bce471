// A shared library that is not an Arbiter plugin: it has no entry points.

extern "C" __attribute__((visibility("default"))) int something_else() {
  return 7;
}
