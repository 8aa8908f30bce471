// A file of its own: it asserts with Catch, and the DDS benchmark links the test support without
// Catch's runner, so only the test binaries that call it pull it in.
#include <catch2/catch.hpp>

#include "arbiter/trace_reader.hpp"
#include "test_support.hpp"

namespace arbiter::test {

Trace read_whole_trace(const std::string& path) {
  Diagnostic error;
  auto trace = read_trace(path, error);
  INFO(format(error));
  REQUIRE(trace);
  return std::move(*trace);
}

}  // namespace arbiter::test
