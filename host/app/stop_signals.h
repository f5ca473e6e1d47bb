// SIGINT and SIGTERM as a request to stop (`crunchhost --robot`): while a StopSignals lives, the
// signals are not fatal; the control loop polls received() and shuts down in order (motors
// stopped, recording flushed, map written, exit 0). The previous handlers come back when it
// goes.
//
// Thread-safety: the handler only stores the signal number in an atomic; one StopSignals at a
// time per process (it owns the process's handlers for the two signals).
#pragma once

#include <csignal>

namespace crunch::app {

class StopSignals {
 public:
  StopSignals();   // clears received(), installs the handler
  ~StopSignals();  // restores the previous handlers
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;

  // 0, or the last signal that came.
  int received() const;
  // "SIGINT", "SIGTERM", or "signal".
  static const char* name(int sig);

 private:
  struct sigaction old_int_ {};
  struct sigaction old_term_ {};
};

}  // namespace crunch::app
