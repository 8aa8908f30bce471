#include "server/serve.hpp"

#include <fmt/format.h>
#include <httplib.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <iterator>
#include <list>
#include <sstream>
#include <string_view>
#include <tuple>

#include "arbiter/channels.hpp"
#include "arbiter/dump.hpp"
#include "arbiter/explain.hpp"
#include "arbiter/trace.hpp"
#include "commands/timing.hpp"
#include "server/studio.hpp"
#include "server/web_assets.hpp"

namespace arbiter::cli {

namespace {

using namespace std::chrono_literals;

// Every open page holds one server thread for its stream; the few requests besides need a few
// more. Past this many pages a new one waits for a thread.
constexpr std::size_t kServerThreads = 32;
// Accepted connections waiting for a thread; past this many the listening thread stops
// accepting, and further clients wait in the kernel's backlog (or are refused by it).
constexpr std::size_t kMaxQueued = 256;
// A client that sends nothing for this long is dropped, freeing its thread.
constexpr int kReadTimeoutSeconds = 2;
// A page draws the last kBacklog steps; a client further behind skips to them.
constexpr std::uint64_t kBacklog = 300;
// At most this many frames in one write.
constexpr std::uint64_t kBatch = 64;
// How often a stream looks for new steps: at most this often a page gets a write.
constexpr auto kPoll = 20ms;

std::optional<std::uint64_t> parse_step(const std::string& text) {
  if (text.empty() || text.size() > 19 ||
      text.find_first_not_of("0123456789") != std::string::npos) {
    return std::nullopt;
  }
  return std::stoull(text);
}

void reply_text(httplib::Response& response, int status, const std::string& text) {
  response.status = status;
  response.set_content(printable(text, true), "text/plain; charset=utf-8");
}

/// httplib's thread pool with a bounded queue: enqueue() (on the listening thread) waits while
/// the queue is full, so a burst of connections costs a bounded amount of memory.
class BoundedPool : public httplib::TaskQueue {
 public:
  BoundedPool(std::size_t threads, const std::atomic<bool>& stopping) : stopping_(stopping) {
    for (std::size_t i = 0; i < threads; ++i) threads_.emplace_back([this] { work(); });
  }
  void enqueue(std::function<void()> fn) override {
    std::unique_lock lock(mutex_);
    // While stopping, the queue takes what the listening thread still has: it is drained.
    while (jobs_.size() >= kMaxQueued && !stopping_) room_.wait_for(lock, 50ms);
    jobs_.push_back(std::move(fn));
    lock.unlock();
    ready_.notify_one();
  }
  void shutdown() override {
    {
      std::lock_guard lock(mutex_);
      shutdown_ = true;
    }
    ready_.notify_all();
    for (auto& thread : threads_) thread.join();
  }

 private:
  void work() {
    while (true) {
      std::function<void()> fn;
      {
        std::unique_lock lock(mutex_);
        ready_.wait(lock, [&] { return !jobs_.empty() || shutdown_; });
        if (jobs_.empty()) return;
        fn = std::move(jobs_.front());
        jobs_.pop_front();
      }
      room_.notify_one();
      fn();
    }
  }

  const std::atomic<bool>& stopping_;
  std::vector<std::thread> threads_;
  std::list<std::function<void()>> jobs_;
  bool shutdown_ = false;
  std::mutex mutex_;
  std::condition_variable ready_;
  std::condition_variable room_;
};

bool same_token(std::string_view given, std::string_view token) {
  // In time independent of where the first difference is.
  if (given.size() != token.size()) return false;
  unsigned char difference = 0;
  for (std::size_t i = 0; i < token.size(); ++i) {
    difference |= static_cast<unsigned char>(given[i] ^ token[i]);
  }
  return difference == 0;
}

/// The value of cookie `name` in a Cookie header, or "".
std::string cookie_value(const std::string& header, const std::string& name) {
  std::size_t at = 0;
  while (at < header.size()) {
    while (at < header.size() && (header[at] == ' ' || header[at] == ';')) ++at;
    const auto end = std::min(header.find(';', at), header.size());
    const std::string_view pair(header.data() + at, end - at);
    if (pair.size() > name.size() && pair.compare(0, name.size(), name) == 0 &&
        pair[name.size()] == '=') {
      return std::string(pair.substr(name.size() + 1));
    }
    at = end;
  }
  return "";
}

std::string lowercase(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

constexpr const char* kTokenNeeded =
    "this view needs its token: open the URL that arbiter printed when it started serving "
    "(http://HOST:PORT/?token=...), or pass the token as ?token=, as the X-Arbiter-Token header "
    "or with --serve-token / ARBITER_SERVE_TOKEN when you start it\n";

}  // namespace

std::string token_error(const std::string& token) {
  if (token.size() < 8 || token.size() > 128 ||
      token.find_first_not_of(
          "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_.") !=
          std::string::npos) {
    return "the token must be 8 to 128 letters, digits, '-', '_' or '.'";
  }
  return "";
}

std::string random_token() {
  std::ifstream random("/dev/urandom", std::ios::binary);
  unsigned char bytes[16] = {};
  random.read(reinterpret_cast<char*>(bytes), sizeof bytes);
  if (!random) throw std::runtime_error("cannot read /dev/urandom for the live view's token");
  std::string token;
  for (const unsigned char byte : bytes) token += fmt::format("{:02x}", byte);
  return token;
}

ServeAddress ServeAddress::parse(const std::string& text, std::string& error) {
  ServeAddress address;
  std::string port = text;
  if (!text.empty() && text.front() == '[') {  // [::1]:8080
    const auto close = text.find("]:");
    if (close == std::string::npos) {
      error = fmt::format("'{}' is not [ADDR]:PORT", text);
      return address;
    }
    address.host = text.substr(1, close - 1);
    port = text.substr(close + 2);
  } else if (const auto colon = text.rfind(':'); colon != std::string::npos) {
    address.host = text.substr(0, colon);
    port = text.substr(colon + 1);
  }
  if (address.host.empty()) {
    error = fmt::format("'{}' has an empty address; write PORT or ADDR:PORT", text);
    return address;
  }
  if (port.empty() || port.size() > 5 ||
      port.find_first_not_of("0123456789") != std::string::npos || std::stoi(port) > 65535) {
    error =
        fmt::format("'{}': the port must be a number from 0 to 65535 (0 picks a free one)", text);
    return address;
  }
  address.port = std::stoi(port);
  return address;
}

bool ServeAddress::loopback() const {
  return host == "localhost" || host == "::1" || host.rfind("127.", 0) == 0;
}

constexpr const char* kFavicon = "/favicon.ico";

WebServer::WebServer() : server_(std::make_unique<httplib::Server>()) {
  server_->new_task_queue = [this] { return new BoundedPool(kServerThreads, stopping_); };
  // Idle keep-alive connections hold a thread; a short timeout frees it (and speeds up stop()).
  server_->set_keep_alive_timeout(1);
  server_->set_read_timeout(kReadTimeoutSeconds);
  // What httplib refuses by itself (a request it cannot read, a URI or a form too long, a path
  // no handler serves) it answers with a status alone: the client is told why, as our own
  // refusals tell it.
  using Handled = httplib::Server::HandlerResponse;
  server_->set_error_handler(httplib::Server::HandlerWithResponse(
      [](const httplib::Request& request, httplib::Response& response) {
        if (!response.body.empty()) return Handled::Unhandled;
        std::string why;
        switch (response.status) {
          case 400:
            why = "bad request: not an HTTP request this server can read";
            break;
          case 404:
            why = fmt::format("not found: {} is not a page of this server", request.path);
            break;
          case 405:
            why = fmt::format("method {} is not allowed here", request.method);
            break;
          case 413:
            why = fmt::format(
                "refused: the request's body is too long (a form's is limited to {} bytes)",
                CPPHTTPLIB_FORM_URL_ENCODED_PAYLOAD_MAX_LENGTH);
            break;
          case 414:
            why = fmt::format("refused: the request's URI is longer than {} bytes",
                              CPPHTTPLIB_REQUEST_URI_MAX_LENGTH);
            break;
          default:
            why = fmt::format("the request failed with status {}", response.status);
            break;
        }
        reply_text(response, response.status, why + "\n");
        return Handled::Handled;
      }));
  // To develop the web app: its files from a directory, read at every request (docs/live_view.md).
  const char* dir = std::getenv("ARBITER_WEB_DIR");
  const std::string web_dir = dir != nullptr ? dir : "";
  // The page declares no icon, but a browser asks for one all the same (opening the bare URL,
  // or a bookmark): an empty answer rather than an error in its console and network log.
  server_->Get(kFavicon, [](const httplib::Request&, httplib::Response& response) {
    response.status = 204;
    response.set_header("Cache-Control", "max-age=86400");
  });
  for (std::size_t i = 0; i < web::kAssetCount; ++i) {
    const web::Asset& asset = web::kAssets[i];
    // The embedded files carry a validator, so that the browser keeps them and asks again with it
    // (answered 304): a script kept so keeps its compiled code too (V8's code cache hangs on the
    // cached response), and ELK's worker, 1.6 MB, is not compiled again each time a page opens.
    // Files read from ARBITER_WEB_DIR are sent whole every time, as they may have changed.
    std::string etag;
    if (web_dir.empty()) {
      const std::string_view content(reinterpret_cast<const char*>(asset.data), asset.size);
      etag = fmt::format("\"{:016x}\"", std::hash<std::string_view>{}(content));
    }
    server_->Get(asset.path, [&asset, web_dir, etag](const httplib::Request& request,
                                                     httplib::Response& response) {
      response.set_header("Cache-Control", "no-cache");
      if (!etag.empty()) {
        response.set_header("ETag", etag);
        if (request.get_header_value("If-None-Match") == etag) {
          response.status = 304;
          return;
        }
      }
      std::string_view body(reinterpret_cast<const char*>(asset.data), asset.size);
      std::shared_ptr<std::string> file_body;
      if (!web_dir.empty()) {
        const std::string path =
            web_dir + (std::string_view(asset.path) == "/" ? "/index.html" : asset.path);
        std::ifstream file(path, std::ios::binary);
        if (!file) {
          reply_text(response, 404, fmt::format("ARBITER_WEB_DIR: cannot read {}\n", path));
          return;
        }
        file_body = std::make_shared<std::string>(std::istreambuf_iterator<char>(file),
                                                  std::istreambuf_iterator<char>());
        body = *file_body;
      }
      // From a content provider, as it is: httplib would compress a body set whole, and its
      // Brotli takes seconds for the bundle (ELK is 1.5 MB).
      response.set_content_provider(
          body.size(), asset.type,
          [body, file_body](std::size_t offset, std::size_t length, httplib::DataSink& sink) {
            return sink.write(body.data() + offset, length);
          });
    });
  }
}

WebServer::~WebServer() {
  stop();
}

bool WebServer::start(const ServeAddress& address, const LiveAccess& given, std::string& error) {
  LiveAccess access = given;
  if (access.token.empty()) access.token = random_token();
  token_ = access.token;
  errno = 0;
  int port = address.port;
  bool bound = false;
  if (port == 0) {
    port = server_->bind_to_any_port(address.host);
    bound = port > 0;
  } else {
    bound = server_->bind_to_port(address.host, port);
  }
  if (!bound) {
    error = fmt::format(
        "cannot listen on {}:{}: {}", address.host, address.port,
        errno != 0 ? std::strerror(errno) : "not an address of this machine, or the port is taken");
    return false;
  }
  const bool v6 = address.host.find(':') != std::string::npos;
  url_ = fmt::format(v6 ? "http://[{}]:{}/" : "http://{}:{}/", address.host, port);
  host_ = address.host;
  port_ = port;
  guard(access);
  thread_ = std::thread([this] {
    server_->listen_after_bind();
    listen_ended_ = true;
  });
  return true;
}

void WebServer::stop() {
  stopping_ = true;
  // httplib's stop() does nothing before the listening thread has started to listen, and that
  // thread would then listen for ever: a stop right after start() (a SIGTERM while the server
  // starts) waits for it first.
  if (thread_.joinable()) {
    while (!server_->is_running() && !listen_ended_) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }
  server_->stop();
  if (thread_.joinable()) thread_.join();
}

void WebServer::guard(const LiveAccess& access) {
  server_->set_pre_routing_handler([this, access](const httplib::Request& request,
                                                  httplib::Response& response) {
    using Handled = httplib::Server::HandlerResponse;
    // DNS rebinding: a page of another site whose name now resolves to this machine still says
    // its own name in Host. A wildcard bind has no one name: the token guards it alone.
    const std::string host = lowercase(request.get_header_value("Host"));
    if (host_ != "0.0.0.0" && host_ != "::") {
      const std::string port = fmt::format(":{}", port_);
      const bool v6 = host_.find(':') != std::string::npos;
      const std::string bound = lowercase(v6 ? "[" + host_ + "]" : host_);
      bool known = false;
      for (const std::string& name :
           {bound, std::string("localhost"), std::string("127.0.0.1"), std::string("[::1]")}) {
        known = known || host == name || host == name + port;
      }
      if (!known) {
        reply_text(response, 403,
                   fmt::format("refused: Host '{}' is not this server's address ({}{}) or "
                               "localhost\n",
                               request.get_header_value("Host"), bound, port));
        return Handled::Handled;
      }
    }
    const std::string cookie = fmt::format("arbiter_token_{}", port_);
    std::string given = request.get_param_value("token");
    if (given.empty()) given = request.get_header_value("X-Arbiter-Token");
    if (given.empty()) given = cookie_value(request.get_header_value("Cookie"), cookie);
    const bool authorised = same_token(given, access.token);
    bool page = request.path == kFavicon;
    for (std::size_t i = 0; i < web::kAssetCount; ++i) {
      page = page || request.path == web::kAssets[i].path;
    }
    if (page) {
      // The page loads without the token (it then says that one is needed); opened with it, it
      // keeps it in a cookie that only this origin sends, and no script reads.
      if (authorised && request.has_param("token")) {
        response.set_header("Set-Cookie", fmt::format("{}={}; Path=/; HttpOnly; SameSite=Strict",
                                                      cookie, access.token));
      }
      return Handled::Unhandled;
    }
    if (!authorised) {
      reply_text(response, 403, kTokenNeeded);
      return Handled::Handled;
    }
    // Every POST changes something: the run (/control/) or a config (/studio/).
    if (request.method != "GET" && request.method != "HEAD") {
      if (access.readonly) {
        reply_text(response, 403, "refused: the live view is read-only (--serve-readonly)\n");
        return Handled::Handled;
      }
      // A page of another origin may send a form POST with the cookie's help (where the cookie
      // is not SameSite) but cannot forge Origin: only this server's own page may change things.
      const std::string origin = request.get_header_value("Origin");
      if ((!origin.empty() && lowercase(origin) != "http://" + host) ||
          request.get_header_value("Sec-Fetch-Site") == "cross-site") {
        reply_text(response, 403,
                   fmt::format("refused: a control request from origin '{}', not from this "
                               "server's page\n",
                               origin));
        return Handled::Handled;
      }
    }
    return Handled::Unhandled;
  });
}

std::pair<int, std::string> explanation_reply(const Explanation& explanation) {
  using Status = Explanation::Status;
  // Its names and the behaviour asked about are the client's and the trace's.
  if (explanation.status == Status::kOk) return {200, printable(explanation.text, true)};
  std::string text = explanation.text + "\n";
  for (const auto& note : explanation.notes) text += "note: " + note.text + "\n";
  return {explanation.status == Status::kNotFound ? 404 : 422, printable(text, true)};
}

std::string web_app_note() {
  if (*web::kLeftOut == '\0') return "";
  return fmt::format(
      "note: this arbiter was built without its web app ({}): the page says so, and "
      "docs/live_view.md tells how to build it\n",
      web::kLeftOut);
}

std::string exposure_warning(const ServeAddress& address, std::string_view what) {
  if (address.loopback()) return "";
  return fmt::format("serving on {}, not only to this machine: anyone who can reach it can {}\n",
                     address.host, what);
}

std::string sse_frame(std::string_view event, std::uint64_t id, std::string_view data) {
  std::string out = fmt::format("event: {}\n", event);
  if (id != 0) out += fmt::format("id: {}\n", id);
  // A data line may not hold a newline: each line of the payload gets its own "data:".
  std::size_t begin = 0;
  while (true) {
    const auto end = data.find('\n', begin);
    out += "data: ";
    out += data.substr(begin, end == std::string_view::npos ? end : end - begin);
    out += '\n';
    if (end == std::string_view::npos || end + 1 == data.size()) break;
    begin = end + 1;
  }
  out += '\n';
  return out;
}

std::unique_ptr<LiveView> LiveView::open(const std::string& text, bool paused,
                                         const LiveAccess& access, std::ostream& out,
                                         std::ostream& err, Studio* studio) {
  std::string error;
  const auto address = ServeAddress::parse(text, error);
  auto live = std::make_unique<LiveView>();
  live->readonly_ = access.readonly;
  if (studio != nullptr) {
    // Before the server starts: its routes are read by every server thread.
    studio->attach(live->server_.http());
    live->info_ = R"({"mode": "studio", "live": true})";
  } else if (access.readonly) {
    live->info_ = R"({"mode": "live", "readonly": true})";
  }
  if (error.empty() && !live->server_.start(address, access, error)) {
    err << fmt::format("arbiter run: --serve: {}\n", error);
    return nullptr;
  }
  if (!error.empty()) {
    err << fmt::format("arbiter run: --serve: {}\n", error);
    return nullptr;
  }
  err << web_app_note();
  err << exposure_warning(address, access.readonly ? "watch the run (with its token)"
                                                   : "watch, pause and step the run (with its "
                                                     "token)");
  live->paused_ = paused;
  live->out_ = &out;
  out << fmt::format("serving the {} at {}{}{}\n", studio ? "studio" : "live view",
                     live->server_.page_url(), access.readonly ? " (read-only)" : "",
                     paused ? " (paused: press Step or Resume on the page)" : "")
      << std::flush;
  return live;
}

LiveView::LiveView() : ring_(std::make_unique<Slot[]>(kRingSize)) {
  auto& http = server_.http();
  http.Get("/info", [this](const httplib::Request&, httplib::Response& response) {
    response.set_content(info_, "application/json");
  });
  http.Get("/events", [this](const httplib::Request& request, httplib::Response& response) {
    struct Cursor {
      std::uint64_t next = 0;
      std::uint64_t graph_seen = 0;
      std::uint64_t status_seen = 0;
      std::uint64_t safe_seen = 0;
      std::chrono::steady_clock::time_point timing_sent{};
    };
    auto cursor = std::make_shared<Cursor>();
    // EventSource sends the last id it saw when it reconnects: resume after it.
    if (const auto last = parse_step(request.get_header_value("Last-Event-ID"))) {
      cursor->next = *last + 1;
    }
    // A snapshot (the page's ?snapshot, docs/live_view.md) is the run as it is now: the stream
    // ends, with an "end" event, once it has sent the steps up to this one. A stream that never
    // ends keeps a headless browser from ever taking its screenshot.
    const bool snapshot = request.has_param("snapshot");
    const std::uint64_t last_step = newest_;
    response.set_header("Cache-Control", "no-cache");
    response.set_chunked_content_provider(
        "text/event-stream",
        [this, cursor, snapshot, last_step](std::size_t, httplib::DataSink& sink) {
          const auto write = [&sink](const std::string& text) {
            return sink.write(text.data(), text.size());
          };
          if (!stream(cursor->next, cursor->graph_seen, cursor->status_seen, cursor->safe_seen,
                      cursor->timing_sent, write)) {
            return false;
          }
          if (snapshot && cursor->graph_seen != 0 && cursor->status_seen != 0 &&
              (last_step == 0 || cursor->next > last_step) && cursor->safe_seen == safe_version_) {
            if (!write(sse_frame("end", 0, fmt::format(R"({{"step": {}}})", last_step)))) {
              return false;
            }
            sink.done();
          }
          return true;
        });
  });
  const auto control = [this](const char* path, bool pause, bool single_step) {
    server_.http().Post(
        path, [this, pause, single_step](const httplib::Request&, httplib::Response& response) {
          if (single_step) ++single_steps_;
          paused_ = pause;
          if (!pause || single_step) {
            std::lock_guard lock(mutex_);
            break_text_.clear();  // the run goes on from the break
          }
          publish_status();
          response.set_content(R"({"ok": true})", "application/json");
        });
  };
  control("/control/pause", true, false);
  control("/control/resume", false, false);
  // A single step pauses a running engine after that step.
  control("/control/step", true, true);
  http.Get("/explain", [this](const httplib::Request& request, httplib::Response& response) {
    const auto step = parse_step(request.get_param_value("step"));
    const std::string target = request.get_param_value("target");
    if (!step || *step == 0 || target.empty()) {
      reply_text(response, 400, "explain needs ?step=N (from 1) and &target=BEHAVIOUR\n");
      return;
    }
    ExplainRequest pending;
    pending.step = *step;
    pending.target = target;
    submit(pending, response);
  });
  // Breakpoints set and removed from the page: conditions as `run --break` takes them, checked
  // against the running program by the stepping thread.
  http.Post("/control/break", [this](const httplib::Request& request, httplib::Response& response) {
    ExplainRequest pending;
    const bool add = request.has_param("add");
    if (add == request.has_param("remove")) {
      reply_text(response, 400, "break needs ?add=CONDITION or ?remove=CONDITION\n");
      return;
    }
    pending.kind = add ? ExplainRequest::Kind::kAddBreak : ExplainRequest::Kind::kRemoveBreak;
    pending.target = request.get_param_value(add ? "add" : "remove");
    submit(pending, response);
  });
}

void LiveView::submit(ExplainRequest& pending, httplib::Response& response) {
  {
    std::unique_lock lock(mutex_);
    requests_.push_back(&pending);
    changed_.notify_all();
    // The stepping thread answers between two steps; a stepping thread that never comes back
    // (a behaviour stuck in a step) must not hold this client forever.
    if (!answered_.wait_for(lock, 5s, [&] { return pending.done || server_.stopping(); })) {
      requests_.erase(std::find(requests_.begin(), requests_.end(), &pending));
      reply_text(response, 503, "the engine did not answer: it is inside a step\n");
      return;
    }
    if (!pending.done) {
      requests_.erase(std::find(requests_.begin(), requests_.end(), &pending));
      reply_text(response, 503, "the server is stopping\n");
      return;
    }
  }
  reply_text(response, pending.status, pending.answer);
}

LiveView::~LiveView() {
  // Stream threads read this object: they must be gone before it is.
  server_.stop();
}

void LiveView::publish_graph(const Manager& manager) {
  std::string graph = dump_json(manager.program());
  std::string header = trace_header(manager.program());
  {
    std::lock_guard lock(mutex_);
    graph_ = std::move(graph);
    header_ = std::move(header);
  }
  ++graph_version_;
}

void LiveView::pause_at_break(std::uint64_t step, const char* breakpoint) {
  {
    std::lock_guard lock(mutex_);
    break_text_ = breakpoint;
    break_step_ = step;
  }
  paused_ = true;
  publish_status();
}

void LiveView::publish_status() {
  ++status_version_;
  std::lock_guard lock(mutex_);  // so that a hold() about to wait does not miss the change
  changed_.notify_all();
}

void LiveView::on_start(const Manager& manager) {
  publish_graph(manager);
  // Sized from the record of step 0 with room to grow, so that copying a record into its slot
  // does not allocate.
  records_.reset(manager.program());
  scratch_.clear();
  records_.append(manager, scratch_);
  for (std::size_t i = 0; i < kRingSize; ++i) {
    std::lock_guard lock(ring_[i].mutex);
    ring_[i].record.reserve(2 * scratch_.size() + 256);
    ring_[i].scene.reserve(2 * manager.scene_primitive_count() + 16);
    ring_[i].scene_points.reserve(2 * manager.scene().point_count + 64);
    ring_[i].scene_strings.reserve(2 * manager.scene().string_size + 64);
  }
  rate_hz_ = manager.program().rate_hz;
  {
    std::lock_guard lock(mutex_);
    safe_record_.reserve(2 * scratch_.size() + 256);
  }
  ++status_version_;
}

void LiveView::on_safe(const Manager& manager) {
  scratch_.clear();
  records_.append(manager, scratch_);  // with "safe": true
  {
    std::lock_guard lock(mutex_);
    safe_record_.assign(scratch_);
  }
  ++safe_version_;
}

void LiveView::on_reload(const Manager& manager) {
  records_.reset(manager.program());
  rate_hz_ = manager.program().rate_hz;
  publish_graph(manager);
}

void LiveView::on_step(const Manager& manager) {
  scratch_.clear();
  records_.append(manager, scratch_);
  const auto step = manager.steps();
  {
    Slot& slot = ring_[step % kRingSize];
    std::lock_guard lock(slot.mutex);
    slot.step = step;
    slot.record.assign(scratch_);
    const auto& scene = manager.scene();
    slot.scene.assign(scene.primitives, scene.primitives + manager.scene_primitive_count());
    slot.scene_points.assign(scene.points, scene.points + scene.point_count);
    slot.scene_strings.assign(scene.strings, scene.strings + scene.string_size);
    slot.scene_dropped = scene.dropped;
  }
  newest_ = step;
}

void LiveView::on_finish(const Manager&) {
  finished_ = true;
  ++status_version_;
}

bool LiveView::copy_record(std::uint64_t step, std::string& out) {
  Slot& slot = ring_[step % kRingSize];
  std::lock_guard lock(slot.mutex);
  if (slot.step != step) return false;  // overwritten by a later step
  out += slot.record;
  return true;
}

bool LiveView::copy_scene(std::uint64_t step, std::string& out) {
  thread_local std::vector<ScenePrimitive> primitives;
  thread_local std::vector<ScenePoint> points;
  thread_local std::vector<char> strings;
  std::size_t dropped = 0;
  {
    Slot& slot = ring_[step % kRingSize];
    std::lock_guard lock(slot.mutex);
    if (slot.step != step || (slot.scene.empty() && slot.scene_dropped == 0)) return false;
    primitives = slot.scene;
    points = slot.scene_points;
    strings = slot.scene_strings;
    dropped = slot.scene_dropped;
  }
  const auto time_ns = static_cast<std::uint64_t>(static_cast<double>(step) * 1e9 / rate_hz_);
  append_scene_update(
      time_ns, {primitives.data(), primitives.size(), points.data(), strings.data(), dropped}, out);
  return true;
}

void LiveView::answer_requests(const Manager& manager) {
  std::unique_lock lock(mutex_);
  if (requests_.empty()) return;
  while (!requests_.empty()) {
    ExplainRequest& request = *requests_.front();
    requests_.pop_front();
    if (request.kind != ExplainRequest::Kind::kExplain) {
      change_breakpoints(manager, request);
      request.done = true;
      continue;
    }
    const std::uint64_t newest = newest_;
    const std::uint64_t oldest = newest >= kRingSize ? newest - kRingSize + 1 : 1;
    if (request.step > newest || request.step < oldest) {
      request.status = 404;
      request.answer = newest == 0 ? "no step has run yet\n"
                                   : fmt::format("steps {} to {} are kept, not step {}\n", oldest,
                                                 newest, request.step);
    } else {
      // explain() reads a trace: this one is the header and the records around the step.
      std::string trace = header_ + "\n";
      for (auto step = std::max(request.step - 1, oldest);
           step <= std::min(request.step + 1, newest); ++step) {
        if (copy_record(step, trace)) trace += "\n";
      }
      std::istringstream in(trace);
      std::tie(request.status, request.answer) =
          explanation_reply(explain(manager.program(), in, request.step, request.target));
    }
    request.done = true;
  }
  lock.unlock();
  answered_.notify_all();
}

void LiveView::change_breakpoints(const Manager& manager, ExplainRequest& request) {
  if (breakpoints_ == nullptr) {
    request.status = 404;
    request.answer = "this run takes no breakpoints\n";
    return;
  }
  if (request.kind == ExplainRequest::Kind::kRemoveBreak) {
    if (!breakpoints_->remove(request.target)) {
      request.status = 404;
      request.answer = fmt::format("no breakpoint '{}' is set\n", request.target);
      return;
    }
  } else {
    std::string error;
    auto breakpoint = make_breakpoint(manager.program(), request.target, "break",
                                      FormatOptions::readable(), error);
    if (!breakpoint) {
      request.status = 400;
      request.answer = std::move(error);
      return;
    }
    breakpoints_->add(std::move(*breakpoint));
  }
  request.status = 200;
  request.answer = "ok\n";
  list_breakpoints();
  ++status_version_;
}

void LiveView::list_breakpoints() {
  breakpoints_json_ = "[";
  for (const auto& breakpoint : breakpoints_->items()) {
    if (breakpoints_json_.size() > 1) breakpoints_json_ += ", ";
    detail::append_json_string(breakpoint.condition.text, breakpoints_json_);
  }
  breakpoints_json_ += "]";
}

void LiveView::set_breakpoints(Breakpoints* breakpoints) {
  breakpoints_ = breakpoints;
  std::lock_guard lock(mutex_);
  list_breakpoints();
}

bool LiveView::hold(const Manager& manager, const std::atomic<bool>& interrupted) {
  answer_requests(manager);
  if (!paused_) return false;
  while (!interrupted) {
    if (!paused_) break;
    if (single_steps_ > 0) {
      --single_steps_;
      break;
    }
    answer_requests(manager);
    std::unique_lock lock(mutex_);
    changed_.wait_for(lock, 50ms);
  }
  return true;
}

void LiveView::serve_until(const Manager& manager, const std::atomic<bool>& interrupted) {
  // Interrupted, the run ends and so does the server: no promise that it stays.
  if (interrupted) return;
  if (out_ != nullptr) {
    *out_ << fmt::format("the run is over; the live view stays at {} until Ctrl-C\n",
                         server_.page_url())
          << std::flush;
  }
  while (!interrupted) {
    answer_requests(manager);
    std::unique_lock lock(mutex_);
    changed_.wait_for(lock, 50ms);
  }
}

bool LiveView::stream(std::uint64_t& next, std::uint64_t& graph_seen, std::uint64_t& status_seen,
                      std::uint64_t& safe_seen, std::chrono::steady_clock::time_point& timing_sent,
                      const std::function<bool(const std::string&)>& write) {
  // Polled rather than woken by each step: the stepping thread then shares no lock with the
  // streams but a slot's, and a fast engine's steps reach a page in batches.
  const auto news = [&] {
    return graph_version_ != graph_seen || status_version_ != status_seen ||
           safe_version_ != safe_seen || (newest_ > 0 && next <= newest_);
  };
  for (int i = 0; i < 50 && !server_.stopping(); ++i) {
    std::this_thread::sleep_for(kPoll);
    if (news()) break;
  }
  if (server_.stopping()) return false;
  std::string out;
  if (const std::uint64_t version = graph_version_; version != graph_seen) {
    std::lock_guard lock(mutex_);
    out += sse_frame("graph", 0, graph_);
    graph_seen = version;
  }
  const std::uint64_t newest = newest_;
  if (newest > 0 && next <= newest) {
    if (next + kBacklog <= newest) next = newest - kBacklog + 1;
    if (next == 0) next = 1;
    std::string record;
    for (std::uint64_t sent = 0; next <= newest && sent < kBatch; ++next) {
      record.clear();
      if (!copy_record(next, record)) continue;
      out += sse_frame("step", next, record);
      // Right after its step: the page attaches it to the record it just received.
      record.clear();
      if (copy_scene(next, record)) out += sse_frame("scene", next, record);
      ++sent;
    }
  }
  // After the steps: the safe pass follows the step it belongs to.
  if (const std::uint64_t version = safe_version_; version != safe_seen && next > newest) {
    std::lock_guard lock(mutex_);
    if (!safe_record_.empty()) out += sse_frame("safe", 0, safe_record_);
    safe_seen = version;
  }
  if (const std::uint64_t version = status_version_; version != status_seen) {
    std::string status =
        fmt::format(R"({{"paused": {}, "finished": {}, "step": {})", paused_ ? "true" : "false",
                    finished_ ? "true" : "false", newest_.load());
    {
      std::lock_guard lock(mutex_);
      if (!breakpoints_json_.empty()) status += R"(, "breakpoints": )" + breakpoints_json_;
      if (!break_text_.empty()) {
        status += fmt::format(R"(, "break": {{"step": {}, "condition": )", break_step_);
        detail::append_json_string(break_text_, status);
        status += "}";
      }
    }
    out += sse_frame("status", 0, status + "}");
    status_seen = version;
  }
  if (const auto now = std::chrono::steady_clock::now();
      timing_ != nullptr && newest > 0 && now - timing_sent >= 1s) {
    out += sse_frame("timing", 0, timing_->json(paced_));
    timing_sent = now;
  }
  // A comment line keeps the connection alive and finds out when the client has gone.
  if (out.empty()) out = ": idle\n\n";
  return write(out);
}

}  // namespace arbiter::cli
