// libFuzzer target over the trace reader: the input is a whole trace (JSON lines) or recording
// (MCAP, when it starts with MCAP's magic), read record by record as explain, view, plot, diff
// and replay read them, then compared with itself as `arbiter diff` compares runs.

#include <cstddef>
#include <cstdint>
#include <string>

#include "arbiter/diagnostics.hpp"
#include "arbiter/trace_diff.hpp"
#include "arbiter/trace_reader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto source =
      arbiter::trace_source(std::string(reinterpret_cast<const char*>(data), size), "fuzz");
  arbiter::Diagnostic error;
  const auto trace = arbiter::read_trace(*source, error);
  if (!trace) {
    static_cast<void>(arbiter::format(error));  // every error must format
    return 0;
  }
  const auto diff = arbiter::diff_traces(*trace, *trace);
  if (!diff.identical) __builtin_trap();  // a run is identical to itself
  static_cast<void>(arbiter::format_json(diff));
  return 0;
}
