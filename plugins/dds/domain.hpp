#pragma once
// The DDS domains this process has opened. Cyclone DDS allows one configuration per domain id in
// a process, so bridges on the same domain id share one Domain, and must ask for the same
// configuration.

#include <dds/dds.h>

#include <cstdint>
#include <memory>
#include <string>

namespace arbiter::dds {

class Domain {
 public:
  /// Opens domain `id`. `config` is Cyclone DDS XML; empty means Cyclone's defaults (or the file
  /// that the CYCLONEDDS_URI environment variable names). `origin` says where the config came
  /// from, for messages. A domain another bridge of this process opened is shared when the
  /// config is the same. On failure returns nullptr and explains in `error`, with what Cyclone
  /// DDS logged.
  static std::shared_ptr<Domain> open(std::uint32_t id, const std::string& config,
                                      const std::string& origin, std::string& error);

  Domain(const Domain&) = delete;
  Domain& operator=(const Domain&) = delete;
  /// Deletes the domain and everything in it; its bridges are gone by then.
  ~Domain();

  std::uint32_t id() const { return id_; }

 private:
  Domain(std::uint32_t id, std::string config, std::string origin, dds_entity_t handle)
      : id_(id), config_(std::move(config)), origin_(std::move(origin)), handle_(handle) {}

  std::uint32_t id_;
  std::string config_;
  std::string origin_;
  dds_entity_t handle_;  // 0: created implicitly by the first participant, deleted with the last
};

/// Cyclone DDS's name for a return code, "DDS_RETCODE_TIMEOUT".
std::string retcode_name(dds_return_t code);

}  // namespace arbiter::dds
