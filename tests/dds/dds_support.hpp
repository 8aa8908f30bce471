#pragma once
// Shared by the DDS bridge's tests and benchmark: domain ids that no concurrent test uses,
// temporary config files, child processes with bounded waits, traces.

#include <sys/types.h>

#include <chrono>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "arbiter/load.hpp"
#include "arbiter/manager.hpp"
#include "arbiter/program.hpp"
#include "arbiter/registry.hpp"
#include "bridge.hpp"
#include "test_support.hpp"

namespace arbiter::dds_test {

/// A DDS domain id that no other holder on this machine has while this lives (a file lock per
/// id, in [100, 230)), so that tests and test runs in parallel never hear each other.
class DomainLease {
 public:
  DomainLease();
  ~DomainLease();
  DomainLease(const DomainLease&) = delete;
  DomainLease& operator=(const DomainLease&) = delete;
  int id() const { return id_; }

 private:
  int id_ = -1;
  int fd_ = -1;
};

using test::TempDir;

/// The Cyclone DDS configuration of the tests and the split demo: loopback only.
std::string loopback_xml();

using Values = std::vector<std::pair<std::string, std::string>>;

/// `text` with every "{key}" replaced by its value, key by key in order (so a value may hold
/// keys that come after it).
std::string fill(std::string text, const Values& values);

/// A child process with its stdout and stderr in a file; killed (SIGKILL) and reaped when the
/// object goes, if it still runs.
class Child {
 public:
  /// Starts `argv` in `directory` (empty: this one).
  Child(const std::vector<std::string>& argv, const std::string& output,
        const std::string& directory = {});
  ~Child();
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  void signal(int signal);
  /// The exit code once it exits within `timeout` (128 + signal when killed); nullopt otherwise.
  std::optional<int> wait(std::chrono::milliseconds timeout);
  /// signal(signal), then wait(timeout).
  std::optional<int> stop(int signal, std::chrono::milliseconds timeout);
  const std::string& output_file() const { return output_; }
  std::string output() const;
  /// Whether `text` appears in the output within `timeout` (false at once if the child exits
  /// without it).
  bool wait_for_output(const std::string& text, std::chrono::milliseconds timeout);

 private:
  pid_t pid_ = -1;
  std::optional<int> status_;
  std::string output_;
};

/// `arbiter run FILE --realtime --steps N --trace TRACE --quiet`, with the test plugins on the
/// plugin path.
std::vector<std::string> arbiter_run(const std::string& config, std::uint64_t steps,
                                     const std::string& trace, bool quiet = true);

/// Checks (Catch) that `child` exited within `timeout` (fatal when not) and with 0, with its
/// output as context.
void check_exit(Child& child, std::chrono::milliseconds timeout);

/// The step records of a trace in file order, the safe-value passes among them.
std::vector<nlohmann::json> read_trace(const std::string& path);

/// The test registry (built-ins and test classes), dds.* and probe.Stamp.
Registry make_registry();

/// Loads a config file; throws ConfigError with its diagnostics.
Program load_file(const std::string& path, Registry& registry);

/// What a DDS test starts from: a domain id of its own, a folder for its configs and a registry.
struct Setup {
  explicit Setup(Registry registry = make_registry()) : registry(std::move(registry)) {}

  DomainLease domain;
  TempDir dir;
  Registry registry;

  /// {domain} (this domain's id) and {xml} (the loopback configuration).
  Values values() const;
  /// Writes `text` as `name`, with `more` and then values() filled in; returns its path.
  std::string write(const std::string& name, const std::string& text, const Values& more = {});
  /// write(), then load_file() with the registry.
  Program load(const std::string& name, const std::string& text, const Values& more = {});
  /// Writes `self`.yaml, one of a pair of sides, named `self` and stepping at `rate`: its
  /// `layers`, which place the link layer (kSideLink below) as {link}. `cli` sides, run by
  /// `arbiter run`, load the plugins themselves.
  std::string side(const std::string& layers, const std::string& self, const std::string& other,
                   int rate, bool cli);
};

/// The dds.Bridge layer `link` of one side of a pair: probe.Stamp's values (flag, count, level,
/// point, vector, text) published under the namespace {self}, the other side's received as
/// actuators {other}_flag, ... .
extern const char* const kSideLink;

/// The bridge of interface layer `layer`.
dds::Bridge& bridge_of(const Manager& manager, const std::string& layer);

/// Steps `manager` at its rate_hz (sleeping between steps) until `done()` holds after a step,
/// or `timeout` passes. Returns whether `done()` held.
bool step_until(Manager& manager, const std::function<bool()>& done,
                std::chrono::milliseconds timeout);

/// An actuator's current value as JSON, as a trace shows it.
nlohmann::json value_of(const Manager& manager, const std::string& actuator);
bool written(const Manager& manager, const std::string& actuator);

}  // namespace arbiter::dds_test
