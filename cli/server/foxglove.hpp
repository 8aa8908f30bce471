#pragma once
// `arbiter run --foxglove` and `arbiter replay --foxglove`: the run served live over the Foxglove
// WebSocket protocol (foxglove.websocket.v1), on the channels and with the schemas of a
// recording (channels(), arbiter/channels.hpp), so that one Foxglove or Lichtblick layout works
// live and on a recording (docs/foxglove.md, "Connect live").

#include <cstdint>
#include <memory>
#include <ostream>
#include <string>
#include <string_view>

#include "arbiter/manager.hpp"

namespace arbiter::cli {

/// Why this arbiter has no Foxglove server (built without websocketpp, or with
/// -DARBITER_FOXGLOVE=OFF), or "" when it has one.
std::string foxglove_left_out();

/// What a server counted, for the end of the run.
struct FoxgloveCounts {
  std::uint64_t clients = 0;  ///< connections opened, in all
  std::uint64_t sent = 0;     ///< messages sent to clients
  /// Messages not sent to a client that had more than kClientBacklog bytes still to read.
  std::uint64_t dropped_for_slow_clients = 0;
  /// Steps the stepping thread found no free slot for: the server fell behind the steps.
  std::uint64_t dropped_steps = 0;
  /// A run started (on_start): there was something to serve.
  bool started = false;
};

/// The server. Its observer (observer()) only copies each step into a ring of slots laid out when
/// the run starts (StepRing, the recorder's), and only while a client is subscribed; the server's
/// own thread formats the step records and sends them. The stepping thread never waits for a
/// client: a step finding the ring full is dropped, and a client that reads too slowly misses
/// messages (both counted, the second also logged) rather than holding anything up.
class FoxgloveServer {
 public:
  /// Steps that may wait for the server's thread.
  static constexpr std::size_t kSlots = 256;
  /// Bytes a client may leave unread before its messages are dropped.
  static constexpr std::size_t kClientBacklog = std::size_t{1} << 20;
  /// Largest message a client may send: its requests are small JSON objects.
  static constexpr std::size_t kMaxClientMessage = std::size_t{64} << 10;
  /// Pictures a second on `/arbiter/scene` (set_scene_rate()), unless told otherwise.
  static constexpr double kSceneRate = 30.0;

  /// Serves on `host` (an IP address, or localhost) and `port` (0: a free one) and prints the
  /// URL to `out`; or says to `err`, as `command` (run, replay), why it cannot, and returns
  /// nullptr. `name` goes in the serverInfo.
  static std::unique_ptr<FoxgloveServer> open(const std::string& host, int port,
                                              std::string_view command, const std::string& name,
                                              std::ostream& out, std::ostream& err);
  ~FoxgloveServer();
  FoxgloveServer(const FoxgloveServer&) = delete;
  FoxgloveServer& operator=(const FoxgloveServer&) = delete;

  /// ws://HOST:PORT, the port the one bound.
  std::string url() const;
  FoxgloveCounts counts() const;
  /// The end-of-run line of `command` when something was dropped, else "".
  std::string summary(std::string_view command) const;
  /// The run keeps to its rate in real time: its messages are logged at the wall-clock time of
  /// their step, else at the run's simulated time, as a recording's (RecordingInfo::paced). Before
  /// the run starts.
  void set_paced(bool paced);
  /// Sends a step's picture on `/arbiter/scene` at most `pictures_per_second` times a second
  /// (the picture of the next step after each period), or every step's when 0 or when the
  /// program's rate_hz is no faster. The other channels carry every step. Before a client
  /// subscribes.
  void set_scene_rate(double pictures_per_second);
  /// Stops serving and closes every connection (the destructor does it too).
  void stop();

  /// What to add to the manager (Manager::add_observer()) for the server to see its steps: a
  /// StepFeed, the library's, so that a served step does not call into this code.
  Observer& observer();

  struct Impl;

 private:
  FoxgloveServer();
  std::unique_ptr<Impl> impl_;
};

}  // namespace arbiter::cli
