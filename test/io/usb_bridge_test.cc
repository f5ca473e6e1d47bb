// UsbBridge without hardware: the id parser, option checks, and open() against the real libusb
// when no such device is attached (must return promptly with the actionable message, never hang
// or crash). Streaming, unplug and replug are tested against the umockdev virtual bridge in
// test/hil/usb_bridge_hil_test.cc.
#include "crunch/io/usb_bridge.h"

#include <catch2/catch.hpp>
#include <chrono>
#include <string>

using crunch::io::parseUsbId;
using crunch::io::UsbBridge;
using crunch::io::UsbId;

TEST_CASE("parseUsbId: hex VID:PID as lsusb prints it", "[io][usb]") {
  auto a = parseUsbId("1209:0001");
  REQUIRE(a.ok());
  CHECK(a.value().vid == 0x1209);
  CHECK(a.value().pid == 0x0001);
  auto b = parseUsbId("FFFF:aBcD");
  REQUIRE(b.ok());
  CHECK(b.value().vid == 0xffff);
  CHECK(b.value().pid == 0xabcd);
  auto c = parseUsbId("1:2");
  REQUIRE(c.ok());
  CHECK(c.value().vid == 1);
  CHECK(c.value().pid == 2);
  CHECK(crunch::io::formatUsbId(UsbId{0x1209, 0x0001}) == "1209:0001");
}

TEST_CASE("parseUsbId: malformed ids are errors naming the text", "[io][usb]") {
  for (const char* bad : {"", "1209", "1209:", ":0001", "12345:0001", "1209:00g1", "1209-0001",
                          "1209:0001:2", " 1209:0001", "0x1209:0x0001"}) {
    INFO(bad);
    auto r = parseUsbId(bad);
    REQUIRE_FALSE(r.ok());
    CHECK(r.error().message.find(std::string("'") + bad + "'") != std::string::npos);
    CHECK(r.error().message.find("VID:PID") != std::string::npos);
  }
}

TEST_CASE("UsbBridge: default options are the documented contract", "[io][usb]") {
  const UsbBridge::Options o;
  CHECK(o.id.vid == 0x1209);
  CHECK(o.id.pid == 0x0001);
  CHECK(o.endpoint == 0x81);
  CHECK(o.interface == 0);
  CHECK(o.transfers == 8);
  CHECK(o.transfer_size == 4096);
  CHECK(o.reconnect_poll_s == 0.25);
  CHECK(o.timeout_ms == 0u);
}

TEST_CASE("UsbBridge: invalid options are refused before touching USB", "[io][usb]") {
  auto expectError = [](UsbBridge::Options o, const char* what) {
    auto r = UsbBridge::open(o, nullptr, nullptr);
    REQUIRE_FALSE(r.ok());
    INFO(r.error().message);
    CHECK(r.error().message.find(what) != std::string::npos);
  };
  UsbBridge::Options o;
  o.transfers = 0;
  expectError(o, "transfers in flight");
  o = {};
  o.transfers = 65;
  expectError(o, "transfers in flight");
  o = {};
  o.transfer_size = 0;
  expectError(o, "transfer size");
  o = {};
  o.reconnect_poll_s = 0.0;
  expectError(o, "reconnect poll");
  o = {};
  o.endpoint = 0x01;
  expectError(o, "not an IN endpoint");
}

TEST_CASE("UsbBridge: no such device gives the actionable error promptly", "[io][usb]") {
  // An id from pid.codes' private test range that no real device on a build machine carries.
  UsbBridge::Options o;
  o.id = UsbId{0x1209, 0xfffe};
  int chunks = 0;
  const auto t0 = std::chrono::steady_clock::now();
  auto r = UsbBridge::open(
      o, [&](std::span<const std::uint8_t>, std::uint64_t) { ++chunks; }, nullptr);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  REQUIRE_FALSE(r.ok());
  INFO(r.error().message);
  const std::string& m = r.error().message;
  // Either libusb started and found nothing, or it could not start at all (no /dev/bus/usb in
  // a container): both name the id and say what to do.
  CHECK(m.find("1209:fffe") != std::string::npos);
  const bool none_found =
      m.find("no whisker bridge with USB id 1209:fffe found: is it plugged in and powered?") !=
      std::string::npos;
  const bool no_libusb = m.find("cannot start libusb") != std::string::npos;
  CHECK((none_found || no_libusb));
  if (none_found) {
    CHECK(m.find("lsusb") != std::string::npos);
    CHECK(m.find("--usb VID:PID") != std::string::npos);
  }
  CHECK(chunks == 0);
  CHECK(s < 5.0);  // bounded: enumeration only, no waiting for a device
}
