// Apart from dds_support.cpp: the benchmark links that and runs without Catch.

#include <catch2/catch.hpp>

#include "dds_support.hpp"

namespace arbiter::dds_test {

void check_exit(Child& child, std::chrono::milliseconds timeout) {
  const auto status = child.wait(timeout);
  INFO(child.output_file() << ":\n" << child.output());
  REQUIRE(status);
  CHECK(*status == 0);
}

}  // namespace arbiter::dds_test
