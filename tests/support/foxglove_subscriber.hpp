#pragma once
// A Foxglove WebSocket client on a thread of its own, for the tests and the benchmarks that serve
// a run live (`arbiter run --foxglove`): it subscribes to every channel the server advertises and
// reads every message, as a viewer that keeps up does, counting the steps' messages. One client,
// so that what counts as a received message is decided in one place.

#include <nlohmann/json.hpp>
#include <websocketpp/client.hpp>
#include <websocketpp/config/asio_no_tls_client.hpp>

#include <atomic>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <system_error>
#include <thread>
#include <vector>

namespace arbiter::test {

class FoxgloveSubscriber {
 public:
  /// Connects to `url` (a server's url()); connected() says whether the connection could start.
  /// Subscribes to every channel but the one on `left_out` (a topic), if any.
  explicit FoxgloveSubscriber(const std::string& url, const std::string& left_out = "") {
    client_.clear_access_channels(websocketpp::log::alevel::all);
    client_.clear_error_channels(websocketpp::log::elevel::all);
    client_.init_asio();
    client_.set_message_handler([this, left_out](websocketpp::connection_hdl handle,
                                                 Client::message_ptr message) {
      if (message->get_opcode() == websocketpp::frame::opcode::binary) {
        // Message Data (opcode 1), not the server's clock (Time, opcode 2).
        const auto& payload = message->get_payload();
        if (payload.front() != '\x01') return;
        ++received_;
        // Then the subscription id, a little-endian uint32.
        std::uint32_t subscription = 0;
        for (int i = 4; i >= 1 && payload.size() >= 5; --i) {
          subscription = subscription << 8 | static_cast<unsigned char>(payload[i]);
        }
        std::lock_guard<std::mutex> lock(mutex_);
        if (subscription < topics_.size()) ++by_topic_[topics_[subscription]];
        return;
      }
      const auto json = nlohmann::json::parse(message->get_payload(), nullptr, false);
      if (!json.is_object() || json.value("op", "") != "advertise") return;
      auto subscribe =
          nlohmann::json{{"op", "subscribe"}, {"subscriptions", nlohmann::json::array()}};
      for (const auto& channel : json["channels"]) {
        if (channel.value("topic", "") == left_out) continue;
        {
          std::lock_guard<std::mutex> lock(mutex_);
          topics_.resize(next_id_ + 1);
          topics_[next_id_] = channel.value("topic", "");
        }
        subscribe["subscriptions"].push_back({{"id", next_id_++}, {"channelId", channel["id"]}});
      }
      client_.send(handle, subscribe.dump(), websocketpp::frame::opcode::text);
    });
    std::error_code error;
    auto connection = client_.get_connection(url, error);
    if (error) return;
    connection->add_subprotocol("foxglove.websocket.v1");
    client_.connect(connection);
    thread_ = std::thread([this] { client_.run(); });
  }
  ~FoxgloveSubscriber() { stop(); }
  FoxgloveSubscriber(const FoxgloveSubscriber&) = delete;
  FoxgloveSubscriber& operator=(const FoxgloveSubscriber&) = delete;

  bool connected() const { return thread_.joinable(); }
  /// The Message Data frames received so far (a step's messages on each channel subscribed).
  std::uint64_t received() const { return received_; }
  /// Those on the channel of `topic`.
  std::uint64_t received(const std::string& topic) const {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto found = by_topic_.find(topic);
    return found == by_topic_.end() ? 0 : found->second;
  }
  /// Stops the client and waits for its thread.
  void stop() {
    client_.stop();
    if (thread_.joinable()) thread_.join();
  }

 private:
  using Client = websocketpp::client<websocketpp::config::asio_client>;
  Client client_;
  std::thread thread_;
  std::atomic<std::uint64_t> received_{0};
  std::uint32_t next_id_ = 0;  // the client's subscription ids
  mutable std::mutex mutex_;
  std::vector<std::string> topics_;  // by subscription id
  std::map<std::string, std::uint64_t> by_topic_;
};

}  // namespace arbiter::test
