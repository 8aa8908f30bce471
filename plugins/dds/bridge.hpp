#pragma once
// dds.Bridge: an interface layer that connects a behaviour system to DDS topics (docs/dds.md).
//
// An interface layer's actuators are written in the input pass from outside data, and its
// sensors are read in the output pass. So the bridge *subscribes* to a topic for each of its
// layer's actuators (a value received between two steps is written in the next step's input
// pass, for the sensors of other layers to read) and *publishes* each of its layer's sensors (the
// actuators of other layers) in the output pass.

#include <dds/dds.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "arbiter/behaviour.hpp"
#include "arbiter/registry.hpp"

namespace arbiter::dds {

class Domain;

/// dds.Bridge's params, a base of the class so that the functions that read them may name them.
struct BridgeParams {
  std::int64_t domain_id = 0;
  std::string cyclone_config;
  std::string qos;
  std::string reliability;
  std::string history;
  std::int64_t depth = 0;
  std::string durability;
  std::string topic_prefix;
  std::string ns;  ///< `namespace`
  Node topics;
  std::string publish_when;  ///< `publish`
};

class Bridge final : public Interface, public BridgeParams {
 public:
  Bridge();
  ~Bridge() override;
  Bridge(const Bridge&) = delete;
  Bridge& operator=(const Bridge&) = delete;

  void init(InitContext& ctx) override;
  /// Writes each actuator whose topic delivered since the last step with the newest sample;
  /// the others keep their value, unwritten.
  void input(WriteContext& ctx) override;
  /// Publishes each sensor (by default only those written this step). Never waits.
  void output(const StepContext& ctx) override;

  /// Counts since init, for tests and benchmarks; read them on the stepping thread.
  struct Stats {
    std::uint64_t samples_taken = 0;     ///< valid samples taken from the readers
    std::uint64_t values_written = 0;    ///< actuator writes in input passes
    std::uint64_t published = 0;         ///< samples written
    std::uint64_t publish_failures = 0;  ///< writes DDS refused (a full keep_all history)
  };
  const Stats& stats() const { return stats_; }

  std::size_t subscription_count() const { return subscriptions_.size(); }
  std::size_t publication_count() const { return publications_.size(); }
  /// The DDS topic name of an actuator (subscribed) or a sensor (published); empty if neither.
  std::string topic_of(const std::string& name) const;

  /// Blocks until every subscribed topic has a matched publisher and every published one a
  /// matched subscriber, or `timeout` passes. For tests and tools, not for a step.
  bool wait_for_peers(std::chrono::milliseconds timeout) const;
  /// Blocks until every subscribed topic has a sample waiting for the next input pass, or
  /// `timeout` passes. For tests and tools, not for a step.
  bool wait_for_data(std::chrono::milliseconds timeout) const;

  /// One subscribed or published topic; defined in bridge.cpp, where DDS listeners need them.
  struct Subscription;
  struct Publication;

 private:
  std::shared_ptr<Domain> domain_;  // outlives participant_, which ~Bridge deletes
  dds_entity_t participant_ = 0;
  std::vector<std::unique_ptr<Subscription>> subscriptions_;
  std::vector<std::unique_ptr<Publication>> publications_;
  bool publish_unwritten_ = false;
  Stats stats_;
};

void register_bridge(Registry& registry);

}  // namespace arbiter::dds
