#include "crunch/serve/live_view.h"

#include <httplib.h>
#include <sys/socket.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <string>
#include <thread>
#include <utility>

#include <nlohmann/json.hpp>

#include "serve/live_page.h"

namespace crunch::serve {

namespace {

using Clock = std::chrono::steady_clock;

std::chrono::milliseconds millis(double s) {
  return std::chrono::milliseconds(static_cast<long long>(s * 1000.0));
}

// "127.0.0.1:8080", "localhost:8080", "[::1]:8080" (and the same without the port): the Host
// headers a browser on this machine sends to a loopback server.
bool loopbackHost(const std::string& host, int port) {
  const std::string p = ":" + std::to_string(port);
  for (const char* name : {"127.0.0.1", "localhost", "[::1]"}) {
    if (host == name || host == std::string(name) + p) return true;
  }
  return false;
}

}  // namespace

Status LiveView::Options::validate() const {
  if (max_event_clients < 1 || max_event_clients > 64) {
    return Error{"live view: max_event_clients " + std::to_string(max_event_clients) +
                 " is out of range 1-64"};
  }
  if (!(heartbeat_s > 0.0 && heartbeat_s <= 60.0)) {
    return Error{"live view: heartbeat_s must be in (0, 60]"};
  }
  if (!(write_timeout_s > 0.0 && write_timeout_s <= 60.0)) {
    return Error{"live view: write_timeout_s must be in (0, 60]"};
  }
  return okStatus();
}

struct LiveView::Impl {
  Options options;
  httplib::Server server;
  std::thread thread;
  bool stopped = false;  // under stop_mutex
  std::mutex stop_mutex;

  // The slot the run publishes into.
  std::mutex mutex;
  std::condition_variable cv;
  std::shared_ptr<const LiveState> latest;  // under mutex
  std::uint64_t seq = 0;                    // under mutex
  bool stopping = false;                    // under mutex

  // The document of the newest snapshot, built by the first server thread that needs it.
  std::mutex text_mutex;
  std::uint64_t text_seq = ~std::uint64_t{0};     // under text_mutex
  std::shared_ptr<const std::string> text;        // under text_mutex

  std::atomic<std::uint64_t> published{0}, requests{0}, events_sent{0}, refused{0};
  std::atomic<int> event_clients{0};

  // The newest document and its seq.
  std::pair<std::uint64_t, std::shared_ptr<const std::string>> document() {
    std::shared_ptr<const LiveState> state;
    std::uint64_t s = 0;
    {
      std::lock_guard<std::mutex> lock(mutex);
      state = latest;
      s = seq;
    }
    std::lock_guard<std::mutex> lock(text_mutex);
    if (text_seq != s || !text) {
      LiveState empty;
      empty.stage = "starting";
      text = std::make_shared<const std::string>(liveStateJson(state ? *state : empty, s));
      text_seq = s;
    }
    return {s, text};
  }

  void refuse(httplib::Response& res, int status, const std::string& why) {
    ++refused;
    res.status = status;
    res.set_content(why + "\n", "text/plain; charset=utf-8");
  }

  void routes();
  void events(httplib::Response& res);
};

void LiveView::Impl::routes() {
  const bool loopback = options.address.loopback();
  const int port = options.address.port;
  server.set_pre_routing_handler([this, loopback, port](const httplib::Request& req,
                                                        httplib::Response& res) {
    ++requests;
    if (req.method != "GET" && req.method != "HEAD") {
      res.set_header("Allow", "GET, HEAD");
      refuse(res, 405, "the live view is read-only: GET only");
      return httplib::Server::HandlerResponse::Handled;
    }
    if (loopback && !loopbackHost(req.get_header_value("Host"), port)) {
      refuse(res, 403, "the live view answers only requests for this machine's loopback address");
      return httplib::Server::HandlerResponse::Handled;
    }
    res.set_header("Cache-Control", "no-store");
    res.set_header("X-Content-Type-Options", "nosniff");
    return httplib::Server::HandlerResponse::Unhandled;
  });
  server.Get("/", [](const httplib::Request&, httplib::Response& res) {
    res.set_header("Content-Security-Policy",
                   "default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; "
                   "connect-src 'self'; img-src 'self' data:");
    res.set_content(std::string(livePageHtml()), "text/html; charset=utf-8");
  });
  server.Get("/state.json", [this](const httplib::Request&, httplib::Response& res) {
    res.set_content(*document().second, "application/json");
  });
  server.Get("/events", [this](const httplib::Request&, httplib::Response& res) { events(res); });
  server.set_error_handler([this](const httplib::Request&, httplib::Response& res) {
    if (res.status == 404) refuse(res, 404, "no such page: the live view serves /, /state.json and /events");
  });
}

void LiveView::Impl::events(httplib::Response& res) {
  if (++event_clients > options.max_event_clients) {
    --event_clients;
    refuse(res, 503, "too many event streams open; try again later");
    return;
  }
  // Per connection: the seq last sent.
  auto last = std::make_shared<std::uint64_t>(0);
  res.set_chunked_content_provider(
      "text/event-stream",
      [this, last](std::size_t, httplib::DataSink& sink) {
        bool stop_now = false;
        std::uint64_t s = 0;
        {
          std::unique_lock<std::mutex> lock(mutex);
          cv.wait_for(lock, millis(options.heartbeat_s),
                      [&] { return seq != *last || stopping; });
          stop_now = stopping;
          s = seq;
        }
        if (s != *last) {
          const auto [doc_seq, doc] = document();
          *last = doc_seq;
          const std::string event =
              "id: " + std::to_string(doc_seq) + "\ndata: " + *doc + "\n\n";
          if (!sink.write(event.data(), event.size())) return false;
          ++events_sent;
        } else if (!stop_now) {
          static const std::string kHeartbeat = ": heartbeat\n\n";
          if (!sink.write(kHeartbeat.data(), kHeartbeat.size())) return false;
        }
        if (stop_now) sink.done();  // the newest was sent: end the stream
        return true;
      },
      [this](bool) { --event_clients; });
}

LiveView::LiveView(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Result<std::unique_ptr<LiveView>> LiveView::start(const Options& options) {
  if (auto st = options.validate(); !st) return st.error();
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  httplib::Server& server = impl->server;
  // Not SO_REUSEPORT (cpp-httplib's default): a second server on a port in use must fail to
  // bind, not share the port with the first.
  server.set_socket_options([](socket_t sock) {
    int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof(yes));
  });
  const long write_ms = static_cast<long>(options.write_timeout_s * 1000.0);
  server.set_write_timeout(write_ms / 1000, (write_ms % 1000) * 1000);
  server.set_read_timeout(2, 0);
  server.set_keep_alive_timeout(1);  // an idle keep-alive connection delays stop() this long
  const int max_clients = options.max_event_clients;
  // Event streams hold a thread each; two more answer everything else.
  server.new_task_queue = [max_clients] {
    return new httplib::ThreadPool(static_cast<std::size_t>(max_clients) + 2);
  };
  impl->routes();
  errno = 0;
  if (!server.bind_to_port(options.address.host, options.address.port)) {
    const int e = errno;
    std::string why = e != 0 ? std::strerror(e) : "the system refused the address";
    std::string hint;
    if (e == EADDRINUSE) hint = ": another program listens on that port; choose another port";
    if (e == EADDRNOTAVAIL) hint = ": that is not an address of this machine";
    if (e == EACCES) hint = ": ports below 1024 need privileges; choose a port from 1024 up";
    return Error{"--serve " + options.address.text() + ": cannot listen there (" + why + ")" +
                 hint};
  }
  Impl* raw = impl.get();
  impl->thread = std::thread([raw] { raw->server.listen_after_bind(); });
  // stop() works only once the server runs (cpp-httplib: stop() before listen is a no-op).
  const auto t0 = Clock::now();
  while (!raw->server.is_running() && Clock::now() - t0 < std::chrono::seconds(5)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return std::unique_ptr<LiveView>(new LiveView(std::move(impl)));
}

LiveView::~LiveView() { stop(); }

void LiveView::publish(const LiveState& state) {
  auto copy = std::make_shared<const LiveState>(state);  // outside the lock
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    impl_->latest = std::move(copy);
    ++impl_->seq;
  }
  ++impl_->published;
  impl_->cv.notify_all();
}

void LiveView::stop() {
  std::lock_guard<std::mutex> stop_lock(impl_->stop_mutex);
  if (impl_->stopped) return;
  impl_->stopped = true;
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    impl_->stopping = true;
  }
  impl_->cv.notify_all();
  // The event streams send the newest snapshot and end; then the listening socket closes.
  const auto t0 = Clock::now();
  while (impl_->event_clients.load() > 0 && Clock::now() - t0 < std::chrono::seconds(1)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  impl_->server.stop();
  if (impl_->thread.joinable()) impl_->thread.join();
}

const ServeAddress& LiveView::address() const { return impl_->options.address; }

LiveView::Stats LiveView::stats() const {
  Stats s;
  s.published = impl_->published.load();
  s.requests = impl_->requests.load();
  s.events_sent = impl_->events_sent.load();
  s.refused = impl_->refused.load();
  s.event_clients = impl_->event_clients.load();
  return s;
}

std::string servingLine(const ServeAddress& address, bool json) {
  if (json) {
    return nlohmann::json{{"event", "serving"},
                          {"url", address.url()},
                          {"address", address.text()},
                          {"loopback", address.loopback()}}
        .dump();
  }
  return "live view at " + address.url() +
         (address.loopback() ? " (read-only; this machine only)"
                             : " (read-only; reachable from other machines on " +
                                   address.text() + ")");
}

}  // namespace crunch::serve
