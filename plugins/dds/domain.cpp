#include "domain.hpp"

#include <fmt/format.h>

#include <map>
#include <mutex>
#include <regex>

namespace arbiter::dds {
namespace {

struct Domains {
  std::recursive_mutex mutex;  // ~Domain takes it, maybe inside open()
  std::map<std::uint32_t, std::weak_ptr<Domain>> open;
};

// Process-wide, as Cyclone DDS's domains are.
Domains& domains() {
  static Domains instance;
  return instance;
}

/// Collects what Cyclone DDS logs while a domain is created: its reasons for rejecting a config.
class LogCapture {
 public:
  LogCapture() { dds_set_log_sink(&LogCapture::write, this); }
  ~LogCapture() { dds_set_log_sink(nullptr, nullptr); }
  LogCapture(const LogCapture&) = delete;
  LogCapture& operator=(const LogCapture&) = delete;

  const std::string& text() const { return text_; }

 private:
  static void write(void* self, const dds_log_data_t* data) {
    auto& text = static_cast<LogCapture*>(self)->text_;
    std::string line(data->message + data->hdrsize, data->size - data->hdrsize);
    while (!line.empty() && (line.back() == '\n' || line.back() == ' ')) line.pop_back();
    const auto start = line.find_first_not_of(": ");
    line.erase(0, start == std::string::npos ? line.size() : start);
    if (line.empty()) return;
    if (!text.empty()) text += "; ";
    text += line;
  }

  std::string text_;
};

}  // namespace

std::shared_ptr<Domain> Domain::open(std::uint32_t id, const std::string& config,
                                     const std::string& origin, std::string& error) {
  Domains& all = domains();
  std::lock_guard<std::recursive_mutex> lock(all.mutex);
  if (auto existing = all.open[id].lock()) {
    if (existing->config_ == config) return existing;
    error = fmt::format(
        "domain {} is already open in this process with {}; bridges on one domain must use the "
        "same Cyclone DDS configuration",
        id, existing->origin_.empty() ? "Cyclone DDS's default configuration" : existing->origin_);
    return nullptr;
  }
  dds_entity_t handle = 0;
  if (!config.empty()) {
    LogCapture log;
    handle = dds_create_domain(id, config.c_str());
    if (handle < 0) {
      // Cyclone DDS calls the text it was given CYCLONEDDS_URI; the line is what helps.
      static const std::regex kWhere(R"((.*) \(CYCLONEDDS_URI\+\d+ line (\d+)\))");
      const std::string why = std::regex_replace(log.text(), kWhere, "line $2: $1");
      error = handle == DDS_RETCODE_PRECONDITION_NOT_MET
                  ? fmt::format("domain {} is already open in this process (not by a bridge)", id)
                  : fmt::format("Cyclone DDS rejects {}{}{}",
                                origin.empty() ? "the configuration" : origin,
                                why.empty() ? "" : ": ", why);
      return nullptr;
    }
  }
  std::shared_ptr<Domain> domain(new Domain(id, config, origin, handle));
  all.open[id] = domain;
  return domain;
}

Domain::~Domain() {
  // Under the lock, so that no bridge creates the domain again while it is being deleted.
  std::lock_guard<std::recursive_mutex> lock(domains().mutex);
  if (handle_ > 0) dds_delete(handle_);
}

std::string retcode_name(dds_return_t code) {
  const char* name = dds_strretcode(code);
  return name != nullptr ? name : fmt::format("return code {}", code);
}

}  // namespace arbiter::dds
