// The address a live view listens on (`crunchhost --sim|--robot --serve ADDRESS`; docs/
// LIVE_VIEW.md). One road in: the command line hands the text to parseServeAddress, which is the
// only place a value is checked (ARCHITECTURE.md §3).
//
//   PORT            127.0.0.1:PORT: loopback, the default: only this machine can connect
//   HOST:PORT       HOST a numeric IPv4 address (0.0.0.0: every interface) or "localhost"
//   [IPV6]:PORT     a numeric IPv6 address in brackets ([::1] loopback, [::] every interface)
// PORT is 1 to 65535 (0, "any free port", is refused: the user must know where to point the
// browser). Host names other than localhost are refused rather than resolved: the address must
// not depend on DNS.
#pragma once

#include <string>

#include "crunch/core/result.h"

namespace crunch::serve {

struct ServeAddress {
  std::string host = "127.0.0.1";  // numeric, without brackets ("::1")
  int port = 8080;                 // 1..65535
  bool ipv6 = false;

  // true when only this machine can connect (127.0.0.0/8 or ::1).
  bool loopback() const;
  // "127.0.0.1:8080", "[::1]:8080": as the user would type it back.
  std::string text() const;
  // "http://127.0.0.1:8080/"; for a wildcard host (0.0.0.0, ::) the loopback URL, which works
  // on this machine.
  std::string url() const;
};

// The --serve value, or an Error that starts with "--serve VALUE: " and says what is expected.
Result<ServeAddress> parseServeAddress(const std::string& text);

}  // namespace crunch::serve
