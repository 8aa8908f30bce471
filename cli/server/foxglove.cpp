#include "server/foxglove.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <nlohmann/json.hpp>

#include <asio/steady_timer.hpp>
#include <websocketpp/config/asio_no_tls.hpp>
#include <websocketpp/server.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <map>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

#include "arbiter/channels.hpp"
#include "arbiter/diagnostics.hpp"
#include "arbiter/document.hpp"
#include "arbiter/recording.hpp"
#include "arbiter/step_ring.hpp"
#include "arbiter/trace.hpp"

namespace arbiter::cli {

std::string foxglove_left_out() {
  return "";
}

namespace {

using WsServer = websocketpp::server<websocketpp::config::asio>;
using Handle = websocketpp::connection_hdl;
using Json = nlohmann::json;

constexpr const char* kSubprotocol = "foxglove.websocket.v1";
// How often the server's thread looks at the ring: a client sees a step at most this late.
constexpr auto kPoll = std::chrono::milliseconds(5);
// The Foxglove WebSocket protocol's status levels.
enum StatusLevel { kInfo = 0, kWarning = 1, kError = 2 };

// Who the server's own log messages are from.
constexpr const char* kServerName = "Foxglove server";

constexpr std::uint64_t kMaxWarnings = 20;
/// Logs the warning `what` the first kMaxWarnings times `count` counts, then `rest` (that the
/// others are not logged): a client sending garbage in a loop, or a port scanner failing
/// connection after connection, does not flood the log.
void warn_at_most(std::uint64_t& count, const std::string& what, const std::string& rest) {
  if (++count > kMaxWarnings) return;
  spdlog::warn("{}", what);
  if (count == kMaxWarnings) spdlog::warn("{}", rest);
}

/// A client with more than kClientBacklog bytes unsent reads too slowly: what would be queued for
/// it is dropped instead, so that what waits for it (and the server's memory) stays bounded.
bool reads_too_slowly(const WsServer::connection_ptr& connection) {
  return connection->get_buffered_amount() > FoxgloveServer::kClientBacklog;
}

}  // namespace

struct FoxgloveServer::Impl {
  struct Advertised {
    std::uint32_t id = 0;
    Channel channel;
  };
  struct Client {
    std::string name;                                      // its address, for the log
    std::map<std::uint32_t, std::uint32_t> subscriptions;  // subscription id -> channel id
    std::uint64_t dropped = 0;
    bool dropping = false;  // its last message was dropped: logged once per spell
    std::uint64_t warnings = 0;
  };

  WsServer server;
  std::thread thread;
  std::string url;
  std::string name;
  std::unique_ptr<asio::steady_timer> timer;
  std::atomic<bool> stopped{false};
  std::uint64_t failed_connections = 0;  // on the server's thread

  // The steps on their way from the stepping thread to the server's thread, which frees a slot
  // within its poll. What waits for it gives up once the server has stopped.
  struct Waiter : StepRing::Waiter {
    explicit Waiter(const std::atomic<bool>& stopped) : stopped(stopped) {}
    bool give_up() const override { return stopped.load(); }
    const std::atomic<bool>& stopped;
  };
  Waiter waiter{stopped};
  StepRing ring{kSlots, waiter};
  // Captures a step only while some client is subscribed to a channel that steps feed, and its
  // picture only while one is subscribed to the scene: every step's, or at the scene rate.
  StepFeed feed{ring};
  std::atomic<double> scene_rate{FoxgloveServer::kSceneRate};  // 0: every step's picture

  // The server thread's.
  std::vector<Advertised> channels;
  std::uint32_t next_channel = 1;
  std::map<Handle, Client, std::owner_less<Handle>> clients;
  std::string header;  // the last /arbiter/header message, for clients that subscribe later
  std::uint64_t header_time = 0;
  // The log time last sent as the server's clock (the `time` capability): a client stamps what it
  // receives with it, so that its timeline is the run's own clock, as a recording's, and not the
  // browser's (which a run flat out or a replay would not follow).
  std::uint64_t clock_sent = 0;
  std::uint64_t wall_start = 0;
  bool paced = false;  // set before the run starts: the log times' clock (LogClock)
  std::uint64_t run_start = 0;
  LogClock clock;
  std::string record, inputs, log, scene, frame;
  // The scene messages carry what changed since the message before (channels.hpp); the next one
  // is the whole picture after a reload and when a client subscribes, which has seen none before.
  SceneUpdates scene_updates;
  bool scene_subscribed = false;
  std::chrono::steady_clock::time_point picture_due;  // when to ask for the next picture
  double run_rate_hz = 0.0;                           // the program's, from its header

  std::atomic<std::size_t> connected{0};
  std::atomic<std::uint64_t> opened{0}, sent{0}, dropped_for_clients{0};

  // The server's thread from here on.
  /// A warning about `client`: the first few (warn_at_most()).
  void log_client(Client& client, const std::string& what) {
    warn_at_most(
        client.warnings, fmt::format("foxglove client {}: {}", client.name, what),
        fmt::format("foxglove client {}: its further problems are not logged", client.name));
  }
  void send_text(Handle handle, const std::string& text) {
    std::error_code error;
    server.send(handle, text, websocketpp::frame::opcode::text, error);
  }
  void status(Handle handle, Client& client, StatusLevel level, const std::string& message) {
    log_client(client, message);
    // A client that sends and never reads would otherwise have its answers pile up without end
    // (one for each bad id of a message): as its data messages, they wait for it up to the
    // backlog, and are dropped beyond.
    std::error_code error;
    const auto connection = server.get_con_from_hdl(handle, error);
    if (error || reads_too_slowly(connection)) return;
    // The message quotes the client, whose text need not be UTF-8.
    send_text(handle, Json{{"op", "status"}, {"level", level}, {"message", message}}.dump(
                          -1, ' ', false, Json::error_handler_t::replace));
  }
  Json channel_json(const Advertised& advertised) const {
    return {{"id", advertised.id},
            {"topic", advertised.channel.topic},
            {"encoding", std::string(kMessageEncoding)},
            {"schemaName", advertised.channel.schema_name},
            {"schema", advertised.channel.schema},
            {"schemaEncoding", std::string(kSchemaEncoding)}};
  }
  std::string advertise(const std::vector<const Advertised*>& list) const {
    Json array = Json::array();
    for (const auto* advertised : list) array.push_back(channel_json(*advertised));
    return Json{{"op", "advertise"}, {"channels", std::move(array)}}.dump();
  }
  const Advertised* channel(std::uint32_t id) const {
    for (const auto& advertised : channels) {
      if (advertised.id == id) return &advertised;
    }
    return nullptr;
  }
  const Advertised* topic(const std::string& name) const {
    for (const auto& advertised : channels) {
      if (advertised.channel.topic == name) return &advertised;
    }
    return nullptr;
  }
  // Advertised in the order of channels(program).
  const Advertised* channel_at(ChannelIndex index) const {
    return index < channels.size() ? &channels[index] : nullptr;
  }
  void update_wanted() {
    const auto* step = channel_at(kStepChannel);
    const auto* in = channel_at(kInputsChannel);
    const auto* log_channel = channel_at(kLogChannel);
    const auto* scene_channel = channel_at(kSceneChannel);
    bool any = false;
    bool picture = false;
    for (const auto& [handle, client] : clients) {
      for (const auto& [subscription, id] : client.subscriptions) {
        for (const auto* fed : {step, in, log_channel, scene_channel})
          any = any || (fed != nullptr && id == fed->id);
        picture = picture || (scene_channel != nullptr && id == scene_channel->id);
      }
    }
    // A step captured before the stepping thread sees a new scene subscriber's flag reads as one
    // that drew nothing: the subscriber's first picture, whole, comes with the next.
    feed.want(any, picture && every_picture());
    if (picture && !scene_subscribed) picture_due = {};  // the first one at once
    scene_subscribed = picture;
    ask_for_picture();
  }
  // Every step's picture: asked for (rate 0), or a program whose rate_hz is no faster than the
  // scene rate, which then does not depend on this thread asking in time between two steps.
  bool every_picture() const {
    const double rate = scene_rate.load();
    return rate <= 0.0 || (run_rate_hz > 0.0 && run_rate_hz <= rate);
  }
  // At the scene rate, the next step captured carries its picture: a viewer draws the picture at
  // its screen's rate at most, and each scene message costs the link, the client and the stepping
  // thread (the copy of its picture) more than a step record.
  void ask_for_picture() {
    if (!scene_subscribed || every_picture()) return;
    const double rate = scene_rate.load();
    const auto now = std::chrono::steady_clock::now();
    if (now < picture_due) return;
    feed.want_next_picture();
    const auto period = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(1.0 / rate));
    // Kept to the rate on average over the polls, but not caught up after a pause.
    picture_due = now - picture_due > period ? now + period : picture_due + period;
  }

  /// Sends `payload` on `advertised` to every client subscribed to it, but to a client with
  /// more than kClientBacklog bytes unsent: that one's message is dropped.
  void broadcast(const Advertised* advertised, std::uint64_t time, const std::string& payload) {
    if (advertised == nullptr) return;
    for (auto& [handle, client] : clients) {
      for (const auto& [subscription, id] : client.subscriptions) {
        if (id != advertised->id) continue;
        send_data(handle, client, subscription, time, payload);
      }
    }
  }
  /// Sends `time` as the server's clock to every client, when it is later than the last sent: a
  /// clock that went back would make a client drop what it holds, as after a seek.
  void advance_clock(std::uint64_t time) {
    if (time <= clock_sent) return;
    clock_sent = time;
    for (auto& [handle, client] : clients) send_time(handle, time);
  }
  void send_time(Handle handle, std::uint64_t time) {
    std::error_code error;
    const auto connection = server.get_con_from_hdl(handle, error);
    if (error || reads_too_slowly(connection)) return;
    // Time: opcode 2 and the time (u64), little-endian.
    frame.assign(1, '\x02');
    for (int i = 0; i < 8; ++i) frame += static_cast<char>((time >> (8 * i)) & 0xff);
    connection->send(frame, websocketpp::frame::opcode::binary);
  }
  void send_data(Handle handle, Client& client, std::uint32_t subscription, std::uint64_t time,
                 const std::string& payload) {
    std::error_code error;
    const auto connection = server.get_con_from_hdl(handle, error);
    if (error) return;
    if (reads_too_slowly(connection)) {
      ++client.dropped;
      dropped_for_clients.fetch_add(1, std::memory_order_relaxed);
      if (!client.dropping) {
        log_client(client, "reads too slowly: its messages are dropped until it catches up");
      }
      client.dropping = true;
      return;
    }
    client.dropping = false;
    // Message Data: opcode 1, the subscription id (u32) and the log time (u64), little-endian.
    frame.assign(1, '\x01');
    for (int i = 0; i < 4; ++i) frame += static_cast<char>((subscription >> (8 * i)) & 0xff);
    for (int i = 0; i < 8; ++i) frame += static_cast<char>((time >> (8 * i)) & 0xff);
    frame += payload;
    connection->send(frame, websocketpp::frame::opcode::binary);
    sent.fetch_add(1, std::memory_order_relaxed);
  }

  /// Advertises `generation`'s channels: on a reload, those whose schema changed are
  /// unadvertised and advertised anew under a new id (a subscription to the old one ends).
  void take_channels(const std::vector<Channel>& program_channels) {
    std::vector<Advertised> next;
    for (const auto& channel : program_channels) {
      const Advertised* known = topic(channel.topic);
      if (known != nullptr && known->channel.schema == channel.schema &&
          known->channel.schema_name == channel.schema_name) {
        next.push_back(*known);
      } else {
        next.push_back({next_channel++, channel});
      }
    }
    std::vector<std::uint32_t> gone;
    for (const auto& old : channels) {
      if (std::none_of(next.begin(), next.end(),
                       [&](const Advertised& kept) { return kept.id == old.id; })) {
        gone.push_back(old.id);
      }
    }
    std::vector<const Advertised*> fresh;
    for (const auto& advertised : next) {
      if (std::none_of(channels.begin(), channels.end(),
                       [&](const Advertised& old) { return old.id == advertised.id; })) {
        fresh.push_back(&advertised);
      }
    }
    channels = std::move(next);
    for (auto& [handle, client] : clients) {
      for (auto it = client.subscriptions.begin(); it != client.subscriptions.end();) {
        const bool ended = std::find(gone.begin(), gone.end(), it->second) != gone.end();
        it = ended ? client.subscriptions.erase(it) : std::next(it);
      }
      if (!gone.empty()) {
        send_text(handle, Json{{"op", "unadvertise"}, {"channelIds", gone}}.dump());
      }
      if (!fresh.empty()) send_text(handle, advertise(fresh));
    }
    update_wanted();
  }

  void pump() {
    for (auto next = ring.next(); next != StepRing::Next::kNothing; next = ring.next()) {
      if (next == StepRing::Next::kHeader) {
        // The run's first header is the program's as it is, a reload's says which and when (the
        // header schema has `reload` >= 1), as in a recording.
        const auto reload = ring.header_reload();
        header =
            reload == 0 ? ring.header() : reload_header(ring.header(), reload, ring.header_step());
        if (reload == 0) {
          run_start = ring.header_wall_time();
          clock = LogClock(paced, run_start, ring.rate_hz());
          header_time = run_start;
        } else {
          header_time = clock.reload(ring.header_step(), ring.header_wall_time(), ring.rate_hz());
        }
        run_rate_hz = ring.rate_hz();
        take_channels(ring.channels());
        scene_updates.restart();
        advance_clock(header_time);
        broadcast(channel_at(kHeaderChannel), header_time, header);
      } else if (next == StepRing::Next::kStep) {
        send_step(ring.step());
      }
      ring.release();
    }
  }
  void send_step(const RingStep& step) {
    const auto wall =
        step.timed() ? run_start + static_cast<std::uint64_t>(step.time() * 1e9) : wall_clock_ns();
    const auto time = clock.time(step.step(), wall);
    advance_clock(time);
    const auto* log_channel = channel_at(kLogChannel);
    if (const auto gap = step.dropped_before(); gap > 0) {
      log.clear();
      append_dropped_log(time, kServerName, gap, step.step() > gap ? step.step() - gap - 1 : 0,
                         "its thread fell behind the steps", log);
      broadcast(log_channel, time, log);
    }
    if (const auto* advertised = channel_at(kStepChannel)) {
      record.clear();
      step.append_step_record(record);
      broadcast(advertised, time, record);
    }
    if (const auto* advertised = channel_at(kInputsChannel);
        advertised != nullptr && !step.safe()) {
      inputs.clear();
      step.append_inputs_record(inputs);
      broadcast(advertised, time, inputs);
    }
    // Only steps that drew, as in a recording: a viewer keeps showing the last picture.
    if (const auto* advertised = channel_at(kSceneChannel); advertised != nullptr && step.drew()) {
      scene.clear();
      step.append_scene(scene_updates, time, scene);
      broadcast(advertised, time, scene);
    }
    for (std::size_t r = 0; r < step.report_count(); ++r) {
      log.clear();
      step.append_report_log(r, time, log);
      broadcast(log_channel, time, log);
    }
  }
  void schedule() {
    timer->expires_after(kPoll);
    timer->async_wait([this](const std::error_code& error) {
      if (error || stopped) return;
      pump();
      ask_for_picture();
      schedule();
    });
  }

  void on_open(Handle handle) {
    std::error_code error;
    const auto connection = server.get_con_from_hdl(handle, error);
    if (error) return;
    Client& client = clients[handle];
    client.name = connection->get_remote_endpoint();
    opened.fetch_add(1, std::memory_order_relaxed);
    connected.store(clients.size());
    spdlog::info("foxglove client {} connected ({} connected)", client.name, clients.size());
    send_text(handle, Json{{"op", "serverInfo"},
                           {"name", name},
                           {"capabilities", Json::array({"time"})},
                           {"supportedEncodings", Json::array()},
                           {"metadata", Json::object()},
                           {"sessionId", std::to_string(wall_start)}}
                          .dump());
    std::vector<const Advertised*> all;
    for (const auto& advertised : channels) all.push_back(&advertised);
    if (!all.empty()) send_text(handle, advertise(all));
    if (clock_sent > 0) send_time(handle, clock_sent);
  }
  void on_close(Handle handle) {
    const auto found = clients.find(handle);
    if (found == clients.end()) return;
    std::error_code error;
    const auto connection = server.get_con_from_hdl(handle, error);
    if (!error) {
      // Closed by the server for what the client sent (a frame too big, not WebSocket), or by
      // the client or its network, which is no fault.
      using namespace websocketpp::close::status;
      const auto code = connection->get_local_close_code();
      const bool faulted = code == protocol_error || code == unsupported_data ||
                           code == invalid_payload || code == policy_violation ||
                           code == message_too_big;
      if (faulted) {
        spdlog::warn("foxglove: closed the connection of client {}: {}", found->second.name,
                     connection->get_local_close_reason());
      }
    }
    if (found->second.dropped > 0) {
      spdlog::warn("foxglove client {}: left; {} messages to it were dropped (it read too slowly)",
                   found->second.name, found->second.dropped);
    }
    spdlog::info("foxglove client {} left ({} connected)", found->second.name, clients.size() - 1);
    clients.erase(found);
    connected.store(clients.size());
    update_wanted();
  }
  void on_message(Handle handle, const WsServer::message_ptr& message) {
    const auto found = clients.find(handle);
    if (found == clients.end()) return;
    Client& client = found->second;
    if (message->get_opcode() != websocketpp::frame::opcode::text) {
      status(handle, client, kError,
             "a binary message: this server takes no client messages but subscribe and "
             "unsubscribe (it has no clientPublish capability)");
      return;
    }
    const std::string& text = message->get_payload();
    // Printing or copying a JSON tree recurses once per level: a message nested 30 000 deep
    // would overflow the stack of the server's thread, and end the run.
    if (const auto deep = find_too_deep_json(text)) {
      status(handle, client, kError,
             fmt::format("a message nested deeper than {} levels (at byte {}): ignored",
                         ReadLimits().max_depth, *deep));
      return;
    }
    const Json request = Json::parse(text, nullptr, false);
    const auto op = request.is_object() ? request.find("op") : request.end();
    if (!request.is_object() || op == request.end() || !op->is_string()) {
      status(handle, client, kError,
             fmt::format("a malformed message: expected a JSON object with a string \"op\", got "
                         "'{}'",
                         printable(text.substr(0, 80))));
      return;
    }
    const auto list = [&](const char* key) {
      const auto it = request.find(key);
      return it != request.end() && it->is_array() ? &*it : nullptr;
    };
    // An id is an unsigned 32-bit number; -1: not one.
    const auto id_of = [](const Json& value) -> std::int64_t {
      if (!value.is_number_unsigned() || value.get<std::uint64_t>() > 0xffffffffu) return -1;
      return value.get<std::int64_t>();
    };
    const auto member_id = [&](const Json& item, const char* key) -> std::int64_t {
      return item.is_object() && item.contains(key) ? id_of(item[key]) : -1;
    };
    if (*op == "subscribe") {
      const Json* subscriptions = list("subscriptions");
      if (subscriptions == nullptr) {
        status(handle, client, kError, "subscribe: expected \"subscriptions\": [{id, channelId}]");
        return;
      }
      for (const auto& item : *subscriptions) {
        const auto id_value = member_id(item, "id");
        const auto channel_value = member_id(item, "channelId");
        if (id_value < 0 || channel_value < 0) {
          status(handle, client, kError,
                 fmt::format("subscribe: expected {{\"id\": N, \"channelId\": N}} with "
                             "unsigned 32-bit numbers, got {}",
                             printable(item.dump().substr(0, 80))));
          continue;
        }
        const auto id = static_cast<std::uint32_t>(id_value);
        const auto channel_id = static_cast<std::uint32_t>(channel_value);
        const Advertised* advertised = channel(channel_id);
        if (advertised == nullptr) {
          status(handle, client, kWarning,
                 fmt::format("subscribe: no channel has the id {}", channel_id));
          continue;
        }
        if (client.subscriptions.count(id) > 0) {
          status(handle, client, kError,
                 fmt::format("subscribe: the subscription id {} is in use", id));
          continue;
        }
        client.subscriptions[id] = channel_id;
        if (advertised == channel_at(kHeaderChannel) && !header.empty()) {
          send_data(handle, client, id, header_time, header);
        }
        if (advertised == channel_at(kSceneChannel)) scene_updates.restart();
      }
      update_wanted();
    } else if (*op == "unsubscribe") {
      const Json* ids = list("subscriptionIds");
      if (ids == nullptr) {
        status(handle, client, kError, "unsubscribe: expected \"subscriptionIds\": [N, ...]");
        return;
      }
      for (const auto& item : *ids) {
        const auto id = id_of(item);
        if (id < 0 || client.subscriptions.erase(static_cast<std::uint32_t>(id)) == 0) {
          status(handle, client, kWarning,
                 fmt::format("unsubscribe: no subscription has the id {}",
                             printable(item.dump().substr(0, 40))));
        }
      }
      update_wanted();
    } else {
      status(handle, client, kWarning,
             fmt::format("the operation '{}' is not supported by this server",
                         printable(op->get<std::string>().substr(0, 40))));
    }
  }

  bool start(const std::string& host, int port, std::string& error) {
    server.clear_access_channels(websocketpp::log::alevel::all);
    server.clear_error_channels(websocketpp::log::elevel::all);
    std::error_code ec;
    server.init_asio(ec);
    if (ec) {
      error = ec.message();
      return false;
    }
    server.set_reuse_addr(true);
    server.set_max_message_size(kMaxClientMessage);
    server.set_validate_handler([this](Handle handle) {
      const auto connection = server.get_con_from_hdl(handle);
      for (const auto& protocol : connection->get_requested_subprotocols()) {
        if (protocol == kSubprotocol) {
          connection->select_subprotocol(kSubprotocol);
          return true;
        }
      }
      spdlog::warn(
          "foxglove: refused a connection from {} that did not ask for the {} "
          "subprotocol",
          connection->get_remote_endpoint(), kSubprotocol);
      return false;
    });
    server.set_open_handler([this](Handle handle) { on_open(handle); });
    server.set_close_handler([this](Handle handle) { on_close(handle); });
    server.set_fail_handler([this](Handle handle) {
      if (stopped) return;  // a handshake cut short by the end of the run
      std::error_code error;
      const auto connection = server.get_con_from_hdl(handle, error);
      if (error) return;
      // websocketpp says "Unknown" when the socket was gone before its address was read.
      const std::string from = connection->get_remote_endpoint();
      warn_at_most(failed_connections,
                   fmt::format("foxglove: a connection from {} failed: {}",
                               from == "Unknown" ? "an address no longer known" : from,
                               connection->get_ec().message()),
                   fmt::format("foxglove: {} connections have failed; further failures are not "
                               "logged",
                               kMaxWarnings));
    });
    server.set_message_handler(
        [this](Handle handle, WsServer::message_ptr message) { on_message(handle, message); });
    asio::ip::tcp::endpoint endpoint;
    const auto ip = asio::ip::make_address(host == "localhost" ? "127.0.0.1" : host, ec);
    if (ec) {
      error = fmt::format("'{}' is not an IP address", host);
      return false;
    }
    endpoint = {ip, static_cast<unsigned short>(port)};
    server.listen(endpoint, ec);
    if (ec) {
      error = fmt::format("cannot listen on {}:{}: {}", host, port, ec.message());
      return false;
    }
    server.start_accept(ec);
    const auto local = server.get_local_endpoint(ec);
    if (ec) {
      error = ec.message();
      return false;
    }
    const bool v6 = local.address().is_v6();
    url = fmt::format("ws://{}{}{}:{}", v6 ? "[" : "", local.address().to_string(), v6 ? "]" : "",
                      local.port());
    timer = std::make_unique<asio::steady_timer>(server.get_io_service());
    schedule();
    thread = std::thread([this] {
      // A handler that throws ends that call only: the server goes on.
      while (!stopped) {
        try {
          server.run();
          break;
        } catch (const std::exception& failure) {
          spdlog::error("foxglove server: {}", failure.what());
        }
      }
    });
    return true;
  }

  void stop() {
    if (!thread.joinable()) return;
    asio::post(server.get_io_service(), [this] {
      stopped = true;
      timer->cancel();
      std::error_code error;
      server.stop_listening(error);
      for (const auto& [handle, client] : clients) {
        server.close(handle, websocketpp::close::status::going_away, "the run is over", error);
      }
    });
    // Connections close within the handshake's timeout; after it, the loop is stopped.
    for (int i = 0; i < 50 && connected.load() > 0; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    server.stop();
    thread.join();
  }
};

FoxgloveServer::FoxgloveServer() : impl_(std::make_unique<Impl>()) {}

FoxgloveServer::~FoxgloveServer() {
  stop();
}

std::unique_ptr<FoxgloveServer> FoxgloveServer::open(const std::string& host, int port,
                                                     std::string_view command,
                                                     const std::string& name, std::ostream& out,
                                                     std::ostream& err) {
  std::unique_ptr<FoxgloveServer> server(new FoxgloveServer());
  server->impl_->name = name;
  server->impl_->wall_start = wall_clock_ns();
  std::string error;
  if (!server->impl_->start(host, port, error)) {
    err << fmt::format("arbiter {}: --foxglove: {}\n", command, error);
    return nullptr;
  }
  out << fmt::format(
             "serving the Foxglove WebSocket protocol at {} (in Foxglove or Lichtblick: "
             "Open connection, Foxglove WebSocket)\n",
             server->url())
      << std::flush;
  return server;
}

std::string FoxgloveServer::url() const {
  return impl_->url;
}

FoxgloveCounts FoxgloveServer::counts() const {
  FoxgloveCounts counts;
  counts.clients = impl_->opened.load();
  counts.sent = impl_->sent.load();
  counts.dropped_for_slow_clients = impl_->dropped_for_clients.load();
  counts.dropped_steps = impl_->ring.dropped();
  counts.started = impl_->feed.started();
  return counts;
}

std::string FoxgloveServer::summary(std::string_view command) const {
  const auto counted = counts();
  if (counted.dropped_for_slow_clients == 0 && counted.dropped_steps == 0) return "";
  return fmt::format(
      "arbiter {}: --foxglove: {} messages were dropped for clients that read too slowly, and {} "
      "steps for a server that fell behind ({} sent, to {} connections)\n",
      command, counted.dropped_for_slow_clients, counted.dropped_steps, counted.sent,
      counted.clients);
}

void FoxgloveServer::set_paced(bool paced) {
  impl_->paced = paced;
}

void FoxgloveServer::set_scene_rate(double pictures_per_second) {
  impl_->scene_rate.store(pictures_per_second);
}

void FoxgloveServer::stop() {
  impl_->stop();
}

Observer& FoxgloveServer::observer() {
  return impl_->feed;
}

}  // namespace arbiter::cli
