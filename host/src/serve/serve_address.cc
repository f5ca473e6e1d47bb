#include "crunch/serve/serve_address.h"

#include <arpa/inet.h>

#include <cstring>

namespace crunch::serve {

namespace {

Error bad(const std::string& text, const std::string& why) {
  return Error{"--serve " + text + ": " + why};
}

const char* kExpected =
    "expected PORT, HOST:PORT or [IPV6]:PORT, HOST a numeric address or localhost (e.g. "
    "127.0.0.1:8080, the loopback default; 0.0.0.0:8080 to let other machines connect)";

}  // namespace

bool ServeAddress::loopback() const {
  if (ipv6) {
    in6_addr a{};
    return inet_pton(AF_INET6, host.c_str(), &a) == 1 && IN6_IS_ADDR_LOOPBACK(&a);
  }
  in_addr a{};
  return inet_pton(AF_INET, host.c_str(), &a) == 1 && (ntohl(a.s_addr) >> 24) == 127;
}

std::string ServeAddress::text() const {
  return (ipv6 ? "[" + host + "]" : host) + ":" + std::to_string(port);
}

std::string ServeAddress::url() const {
  std::string h = ipv6 ? "[" + host + "]" : host;
  if (host == "0.0.0.0") h = "127.0.0.1";
  if (host == "::") h = "[::1]";
  return std::string("http://") + h + ":" + std::to_string(port) + "/";
}

Result<ServeAddress> parseServeAddress(const std::string& text) {
  ServeAddress a;
  std::string port_text;
  if (text.empty()) return bad("''", kExpected);
  if (text.front() == '[') {
    const auto close = text.find(']');
    if (close == std::string::npos || close + 1 >= text.size() || text[close + 1] != ':') {
      return bad(text, kExpected);
    }
    a.host = text.substr(1, close - 1);
    a.ipv6 = true;
    port_text = text.substr(close + 2);
    in6_addr v6{};
    if (inet_pton(AF_INET6, a.host.c_str(), &v6) != 1) {
      return bad(text, "'" + a.host + "' is not a numeric IPv6 address");
    }
  } else if (const auto colon = text.rfind(':'); colon != std::string::npos) {
    a.host = text.substr(0, colon);
    port_text = text.substr(colon + 1);
    if (a.host.find(':') != std::string::npos) {
      return bad(text, "an IPv6 address goes in brackets, e.g. [::1]:8080");
    }
    if (a.host == "localhost") a.host = "127.0.0.1";
    in_addr v4{};
    if (inet_pton(AF_INET, a.host.c_str(), &v4) != 1) {
      return bad(text, "'" + a.host + "' is not a numeric IPv4 address or localhost (" +
                           kExpected + ")");
    }
  } else {
    port_text = text;  // PORT alone: loopback
  }
  if (port_text.empty() || port_text.size() > 5 ||
      port_text.find_first_not_of("0123456789") != std::string::npos) {
    return bad(text, "'" + port_text + "' is not a port number (" + kExpected + ")");
  }
  a.port = std::stoi(port_text);
  if (a.port < 1 || a.port > 65535) {
    return bad(text, "port " + port_text + " is out of range 1-65535");
  }
  return a;
}

}  // namespace crunch::serve
