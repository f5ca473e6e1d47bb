// The live view of a run (`crunchhost --sim|--robot --serve ADDRESS`; docs/LIVE_VIEW.md): a
// small read-only HTTP server (cpp-httplib, Debian's libcpp-httplib-dev) on its own threads that
// serves one page drawing the run as it goes.
//
//   GET /             the page: HTML + JS drawing the map, pose, path and contacts in SVG and
//                     the counters as text; no external script, font or style (nothing fetched
//                     from anywhere but this server)
//   GET /state.json   the newest snapshot (live_state.h, schema crunch.live/1)
//   GET /events       server-sent events (text/event-stream): each new snapshot as one event
//                     (`id: seq`, `data: <the document>`), a comment line every heartbeat_s when
//                     nothing changed, and the connection closed after the last (done) snapshot
// HEAD is answered as GET without a body; every other method is 405 (Allow: GET, HEAD), any
// other path 404. Bound to a loopback address, requests whose Host header names another host
// are refused with 403 (a web page elsewhere cannot read the view through DNS rebinding).
//
// The run's thread calls publish() with a LiveState: it copies the state into a mutex-guarded
// slot and wakes the event streams; it never waits for a client, a socket or the JSON text (the
// server's threads build the document, once per snapshot, when the first client asks). A slow
// client blocks only its own server thread, and is dropped after write_timeout_s. At most
// max_event_clients event streams at once (each holds a server thread); more get 503.
//
// Errors (start): the address cannot be listened on — in use, not an address of this machine,
// or a port below 1024 without the privilege — as "--serve ADDRESS: cannot listen there (the
// system's reason) ...". Nothing is served then; the caller has started nothing else (exit 3,
// ARCHITECTURE.md §4: the machine, not the command line, is at fault).
//
// Ownership and threads: LiveView owns the server and its threads; stop() (or the destructor)
// ends the event streams after they have sent the newest snapshot (waiting at most 1 s for
// them), closes the listening socket and joins every thread (bounded by the read and keep-alive
// timeouts, about 1 s). publish(), stop() and stats() may be called from any thread. Creating a
// LiveView makes the process ignore SIGPIPE (cpp-httplib's server does: a client that goes away
// must not end the run); writes to a closed pipe then fail with EPIPE instead.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "crunch/core/result.h"
#include "crunch/serve/live_state.h"
#include "crunch/serve/serve_address.h"

namespace crunch::serve {

class LiveView {
 public:
  struct Options {
    ServeAddress address;
    int max_event_clients = 4;  // 1..64
    double heartbeat_s = 5.0;   // (0, 60]: an idle event stream's comment line
    double write_timeout_s = 2.0;  // (0, 60]: a client that takes no bytes this long is dropped
    Status validate() const;
  };

  // Listens on options.address and starts serving (the state before the first publish(): an
  // empty map with stage "starting"). Errors: options.validate(), the address (see the top).
  static Result<std::unique_ptr<LiveView>> start(const Options& options);
  ~LiveView();  // stop()
  LiveView(const LiveView&) = delete;
  LiveView& operator=(const LiveView&) = delete;

  // The newest state of the run; copies it (the caller keeps filling its own).
  void publish(const LiveState& state);
  // Ends serving (see the top); idempotent.
  void stop();

  const ServeAddress& address() const;

  struct Stats {
    std::uint64_t published = 0;    // publish() calls
    std::uint64_t requests = 0;     // requests answered (any status)
    std::uint64_t events_sent = 0;  // snapshots written to event streams
    std::uint64_t refused = 0;      // 403, 404, 405, 503 answers
    int event_clients = 0;          // event streams open now
  };
  Stats stats() const;

 private:
  struct Impl;
  explicit LiveView(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// The line a front end prints once the view listens: for a person, "live view at
// http://127.0.0.1:8080/ (read-only; this machine only)" (or "... reachable from other
// machines" when not loopback); with `json`, {"event":"serving","url":...,"address":...,
// "loopback":true}. No newline.
std::string servingLine(const ServeAddress& address, bool json);

}  // namespace crunch::serve
