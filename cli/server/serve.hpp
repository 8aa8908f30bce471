#pragma once
// The web view of a run (`arbiter run --serve`) and of a trace (`arbiter view`): an HTTP server
// that serves the page compiled into the binary, the compiled graph (the JSON dump) and the step
// records (the trace format), and answers `explain` for a behaviour at a step.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <thread>
#include <utility>
#include <vector>

#include "arbiter/breakpoint.hpp"
#include "arbiter/explain.hpp"
#include "arbiter/manager.hpp"
#include "arbiter/trace.hpp"

namespace httplib {
class Server;
struct Response;
}  // namespace httplib

namespace arbiter::cli {

class RunTiming;
class Studio;

/// Where to listen: `[ADDR:]PORT`; port 0 picks a free port.
struct ServeAddress {
  std::string host = "127.0.0.1";
  int port = 0;
  /// The address as given, or why it is not one (`error` non-empty).
  static ServeAddress parse(const std::string& text, std::string& error);
  bool loopback() const;
};

/// Who may use a server (docs/live_view.md): every request but the static page needs the
/// token, from the cookie the page gets when opened with `?token=`, the `token` parameter or an
/// `X-Arbiter-Token` header; the Host must be the bound address or localhost (against DNS
/// rebinding); a request that changes something (every POST: control of the run, the studio's
/// edits and saves) must come from the server's own origin, and none is served when read-only.
struct LiveAccess {
  std::string token;  ///< empty: open() picks a random one
  bool readonly = false;
};

/// Why `token` cannot be a serve token, or "" when it can (it travels in URLs and cookies).
std::string token_error(const std::string& token);
/// 32 hex digits from the system's random source.
std::string random_token();

/// The HTTP server both views share: the page and its assets, and a listening thread.
class WebServer {
 public:
  WebServer();
  ~WebServer();
  WebServer(const WebServer&) = delete;
  WebServer& operator=(const WebServer&) = delete;

  httplib::Server& http() { return *server_; }
  /// Binds and starts serving on a thread of its own, letting in only what `access` allows: every
  /// server Arbiter starts has this one door (docs/live_view.md). An empty token is replaced by a
  /// random one. False (and `error` says why) when the address cannot be bound; the URL to
  /// print is then page_url().
  bool start(const ServeAddress& address, const LiveAccess& access, std::string& error);
  /// Stops accepting and closes every connection; streams notice through `stopping()`.
  void stop();
  bool stopping() const { return stopping_; }
  const std::string& url() const { return url_; }
  /// url() with the token: what a user opens.
  std::string page_url() const { return url_ + "?token=" + token_; }

 private:
  /// Refuses, from now on, every request that `access` does not let in.
  void guard(const LiveAccess& access);

  std::unique_ptr<httplib::Server> server_;
  std::string host_;  // the address bound
  int port_ = 0;
  std::thread thread_;
  std::string url_;
  std::string token_;
  std::atomic<bool> stopping_{false};
  std::atomic<bool> listen_ended_{false};  // the listening thread returned
};

/// Live view of a running manager. As an observer (on the stepping thread) it copies each step
/// record into a ring of kRingSize preallocated slots, each with a lock of its own that a reader
/// holds only to copy that one record; each client's stream runs on a server thread that polls
/// the ring, so a slow or stuck client only falls behind (and skips to the last steps), never
/// delays a step. Pause, single step and resume come from the page; the run loop asks hold()
/// before each step.
class LiveView : public Observer {
 public:
  static constexpr std::size_t kRingSize = 1024;

  LiveView();
  ~LiveView() override;

  /// Serves on `address` (`[ADDR:]PORT`, checked by ServeAddress::parse) and prints the URL to
  /// `out`, or says to `err` why it cannot (nullptr then). With `paused`, the first step waits
  /// for the page's Step or Resume. With `studio` (`run --serve --edit`), the page is the
  /// studio and the server answers its API.
  static std::unique_ptr<LiveView> open(const std::string& address, bool paused,
                                        const LiveAccess& access, std::ostream& out,
                                        std::ostream& err, Studio* studio = nullptr);
  /// The run's timing, sent to the page about once a second (`paced`: with deadlines).
  void set_timing(const RunTiming* timing, bool paced) {
    timing_ = timing;
    paced_ = paced;
  }
  /// True when the next hold() will wait: the page has paused the run and asked for no step.
  bool will_hold() const { return paused_ && single_steps_ == 0; }
  /// A breakpoint (`run --break`) fired after `step`: the run pauses as the page's Pause pauses
  /// it, and the page's status names the breakpoint until the run goes on.
  void pause_at_break(std::uint64_t step, const char* breakpoint);
  /// The run's breakpoints, which the page lists, adds to and removes from (between two steps,
  /// on the stepping thread); not owned.
  void set_breakpoints(Breakpoints* breakpoints);

  void on_start(const Manager& manager) override;
  void on_step(const Manager& manager) override;
  void on_reload(const Manager& manager) override;
  void on_finish(const Manager& manager) override;
  /// The safe-value pass of a pausing engine: the page shows what the engine output then, not
  /// the last step's commands, until the next step.
  void on_safe(const Manager& manager) override;

  /// Called by the run loop before each step, on the stepping thread. Returns at once while the
  /// page has not paused the run; while paused, waits until the page resumes it or asks for a
  /// single step, or `interrupted` becomes true. Also answers the page's explain requests, which
  /// need the manager's program. True when it waited (so a paced loop restarts its clock).
  bool hold(const Manager& manager, const std::atomic<bool>& interrupted);
  /// After the run: keeps serving (and answering explain requests) until `interrupted`.
  void serve_until(const Manager& manager, const std::atomic<bool>& interrupted);

 private:
  struct Slot {
    std::mutex mutex;
    std::uint64_t step = 0;
    std::string record;
    // What the step drew (StepContext::scene), formatted by the stream that sends it.
    std::vector<ScenePrimitive> scene;
    std::vector<ScenePoint> scene_points;
    std::vector<char> scene_strings;
    std::size_t scene_dropped = 0;
  };
  /// A request the stepping thread answers, as it reads the program: an explanation, or a
  /// breakpoint set or removed from the page.
  struct ExplainRequest {
    enum class Kind { kExplain, kAddBreak, kRemoveBreak };
    Kind kind = Kind::kExplain;
    std::uint64_t step = 0;
    std::string target;
    std::string answer;
    int status = 0;
    bool done = false;
  };

  void publish_graph(const Manager& manager);
  void publish_status();
  void answer_requests(const Manager& manager);
  /// Queues `request` for the stepping thread and replies with its answer (or why none came).
  void submit(ExplainRequest& request, httplib::Response& response);
  void change_breakpoints(const Manager& manager, ExplainRequest& request);
  /// breakpoints_json_ from breakpoints_; the caller holds mutex_.
  void list_breakpoints();
  /// Appends the record of `step` to `out`; false when the ring no longer holds it.
  bool copy_record(std::uint64_t step, std::string& out);
  /// Appends the foxglove.SceneUpdate of what `step` drew to `out`; false when it drew nothing
  /// or the ring no longer holds it.
  bool copy_scene(std::uint64_t step, std::string& out);
  bool stream(std::uint64_t& next, std::uint64_t& graph_seen, std::uint64_t& status_seen,
              std::uint64_t& safe_seen, std::chrono::steady_clock::time_point& timing_sent,
              const std::function<bool(const std::string&)>& write);

  WebServer server_;
  std::ostream* out_ = nullptr;  // where open() printed the URL
  std::unique_ptr<Slot[]> ring_;
  std::atomic<std::uint64_t> newest_{0};  // the step of the newest record in the ring; 0: none
  std::atomic<std::uint64_t> graph_version_{0};
  std::atomic<std::uint64_t> status_version_{0};
  std::atomic<std::uint64_t> safe_version_{0};
  std::atomic<bool> finished_{false};
  StepRecordFormatter records_;
  std::string scratch_;  // the stepping thread's record, built before taking a slot's lock
  std::atomic<double> rate_hz_{1.0};  // of the running program: a scene's time is its step's
  std::mutex mutex_;                  // guards what follows; held only to copy, never across I/O
  std::condition_variable changed_;   // control from the page, explain requests, stopping
  std::string graph_;                 // the dump JSON of the current program
  std::string header_;                // the trace header of the current program
  std::string safe_record_;           // the record of the last safe-value pass
  std::deque<ExplainRequest*> requests_;
  std::condition_variable answered_;
  std::atomic<bool> paused_{false};
  Breakpoints* breakpoints_ = nullptr;
  std::string breakpoints_json_;  // by mutex_: their conditions, a JSON array
  std::string break_text_;        // by mutex_: the breakpoint the run is paused at, "" when none
  std::uint64_t break_step_ = 0;  // by mutex_
  std::atomic<std::uint64_t> single_steps_{0};
  const RunTiming* timing_ = nullptr;
  bool paced_ = false;
  bool readonly_ = false;
  std::string info_ = R"({"mode": "live"})";  // the page's /info: which view it starts
};

/// The text of an SSE frame: `event`, optional `id`, and `data` split into `data:` lines.
std::string sse_frame(std::string_view event, std::uint64_t id, std::string_view data);

/// The page's explain answer: the HTTP status, and the text (with the notes of a failure).
std::pair<int, std::string> explanation_reply(const Explanation& explanation);

/// The warning for an address other machines can reach, or "" for a loopback one.
std::string exposure_warning(const ServeAddress& address, std::string_view what);
/// A note for the user when this binary was built without the web app (cli/server/web_assets.hpp),
/// else "".
std::string web_app_note();

}  // namespace arbiter::cli
