// serve/serve_address.h: the --serve value, the one road in for the live view's address.
#include "crunch/serve/serve_address.h"

#include <catch2/catch.hpp>
#include <string>

namespace {

using crunch::serve::parseServeAddress;

// The error for `text`, which must be one; it names the flag and the value.
std::string errorFor(const std::string& text) {
  const auto a = parseServeAddress(text);
  REQUIRE_FALSE(a);
  CHECK(a.error().message.rfind("--serve " + text + ": ", 0) == 0);
  return a.error().message;
}

}  // namespace

TEST_CASE("Serve address: a port alone listens on loopback", "[serve]") {
  const auto a = parseServeAddress("8080");
  REQUIRE(a);
  CHECK(a.value().host == "127.0.0.1");
  CHECK(a.value().port == 8080);
  CHECK(a.value().loopback());
  CHECK(a.value().text() == "127.0.0.1:8080");
  CHECK(a.value().url() == "http://127.0.0.1:8080/");
}

TEST_CASE("Serve address: HOST:PORT, localhost, IPv6 in brackets, every interface", "[serve]") {
  const auto v4 = parseServeAddress("127.0.0.1:65535");
  REQUIRE(v4);
  CHECK(v4.value().port == 65535);
  const auto local = parseServeAddress("localhost:9000");
  REQUIRE(local);
  CHECK(local.value().host == "127.0.0.1");
  const auto any = parseServeAddress("0.0.0.0:8080");
  REQUIRE(any);
  CHECK_FALSE(any.value().loopback());
  CHECK(any.value().url() == "http://127.0.0.1:8080/");  // what works from this machine
  const auto lan = parseServeAddress("192.168.1.20:1");
  REQUIRE(lan);
  CHECK_FALSE(lan.value().loopback());
  const auto v6 = parseServeAddress("[::1]:8080");
  REQUIRE(v6);
  CHECK(v6.value().ipv6);
  CHECK(v6.value().host == "::1");
  CHECK(v6.value().loopback());
  CHECK(v6.value().text() == "[::1]:8080");
  const auto v6any = parseServeAddress("[::]:8080");
  REQUIRE(v6any);
  CHECK_FALSE(v6any.value().loopback());
  CHECK(v6any.value().url() == "http://[::1]:8080/");
  CHECK(parseServeAddress("127.1.2.3:80").value().loopback());
}

TEST_CASE("Serve address: bad values are errors naming --serve and what is expected", "[serve]") {
  CHECK(errorFor("nonsense").find("not a port number") != std::string::npos);
  CHECK(errorFor("0").find("port 0 is out of range 1-65535") != std::string::npos);
  CHECK(errorFor("70000").find("port 70000 is out of range 1-65535") != std::string::npos);
  CHECK(errorFor("127.0.0.1:0").find("out of range") != std::string::npos);
  CHECK(errorFor("127.0.0.1:123456").find("not a port number") != std::string::npos);
  CHECK(errorFor("127.0.0.1:").find("not a port number") != std::string::npos);
  CHECK(errorFor("127.0.0.1:-1").find("not a port number") != std::string::npos);
  CHECK(errorFor("127.0.0.1:80x").find("not a port number") != std::string::npos);
  CHECK(errorFor("example.com:8080").find("not a numeric IPv4 address") != std::string::npos);
  CHECK(errorFor("300.1.1.1:8080").find("not a numeric IPv4 address") != std::string::npos);
  CHECK(errorFor("::1:8080").find("in brackets") != std::string::npos);
  CHECK(errorFor("[::1]8080").find("expected PORT") != std::string::npos);
  CHECK(errorFor("[nope]:8080").find("not a numeric IPv6 address") != std::string::npos);
  const auto empty = parseServeAddress("");
  REQUIRE_FALSE(empty);
  CHECK(empty.error().message.find("--serve") == 0);
}
