// Hardware-in-loop test of the USB whisker bridge (ARCHITECTURE.md §5, docs/USB.md).
// With CRUNCH_HIL_USB=VID:PID it reads the real bridge for 2 s and fails if it is absent or
// silent. Otherwise it says "hil: virtual USB bridge (umockdev)" and runs io::UsbBridge —
// unmodified libusb, 8 transfers in flight — against sim::VirtualUsbBridge serving real bridge
// frames from the firmware core (VirtualWhiskerBoard), with corrupt frames, an unplug and a
// replug mid-stream, a busy interface and a missing device. Every wait is on a condition with a
// deadline.
// main() is at the end; Catch2's implementation is compiled once, in crunch_catch.
#include <fcntl.h>
#include <poll.h>
#include <pty.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <thread>
#include <string>
#include <tuple>
#include <vector>

#include "crunch/io/bridge_stream.h"
#include "crunch/io/usb_bridge.h"
#include "crunch_sim/virtual_usb_bridge.h"
#include "crunch_sim/virtual_whisker_board.h"
#include "support/catch_session.h"

using crunch::io::BridgeStreamDecoder;
using crunch::io::DecodedFrame;
using crunch::io::UsbBridge;
using crunch::io::UsbId;
using crunch::sim::VirtualUsbBridge;
using crunch::sim::VirtualWhiskerBoard;
using Bytes = std::vector<std::uint8_t>;
using Clock = std::chrono::steady_clock;

namespace {

// Generous: the virtual device busy-polls through a socket on a shared 2-core machine.
constexpr auto kDeliveryDeadline = std::chrono::seconds(60);
constexpr auto kStateDeadline = std::chrono::seconds(10);

auto key(const bridge_frame_t& f) {
  return std::make_tuple(f.board, f.seq, f.tick, f.alpha, f.beta, f.status);
}

// Real bridge frames: `boards` virtual boards ticked in turn for `ticks` 500 us periods.
Bytes makeStream(int boards, int ticks) {
  std::vector<std::unique_ptr<VirtualWhiskerBoard>> b;
  for (int i = 0; i < boards; ++i)
    b.push_back(std::make_unique<VirtualWhiskerBoard>(static_cast<std::uint8_t>(i)));
  Bytes out;
  for (int k = 0; k < ticks; ++k)
    for (auto& board : b) {
      board->sensor().setReading(static_cast<std::uint16_t>(8000 + 37 * k + board->boardId()),
                                 static_cast<std::uint16_t>(20000 + 11 * k));
      const auto sent = board->tick();
      out.insert(out.end(), sent.begin(), sent.end());
    }
  return out;
}

struct Reference {
  std::vector<bridge_frame_t> frames;
  crunch::io::BridgeStreamCounters counters;
};
// What a decoder makes of the whole stream in one feed (the result does not depend on chunking).
Reference decodeAll(const Bytes& bytes) {
  BridgeStreamDecoder dec;
  Reference r;
  dec.feed(bytes, [&](const DecodedFrame& d) { r.frames.push_back(d.frame); });
  r.counters = dec.counters();
  return r;
}

// The receiving side: a decoder fed on the USB event thread, state changes, all observable
// under one mutex with a condition variable for bounded waits.
struct Receiver {
  std::mutex mu;
  std::condition_variable cv;
  BridgeStreamDecoder decoder;
  std::vector<bridge_frame_t> frames;
  std::vector<std::pair<UsbBridge::LinkState, std::string>> states;
  std::uint64_t chunks = 0;
  bool saw_zero_length = false;

  UsbBridge::ChunkHandler chunkHandler() {
    return [this](std::span<const std::uint8_t> bytes, std::uint64_t) {
      std::lock_guard<std::mutex> lock(mu);
      if (bytes.empty()) saw_zero_length = true;
      ++chunks;
      decoder.feed(bytes, [&](const DecodedFrame& d) { frames.push_back(d.frame); });
      cv.notify_all();
    };
  }
  UsbBridge::StateHandler stateHandler() {
    return [this](UsbBridge::LinkState s, const std::string& m) {
      std::lock_guard<std::mutex> lock(mu);
      if (s == UsbBridge::LinkState::kConnected) decoder.resync();  // a reopened device
      states.emplace_back(s, m);
      cv.notify_all();
    };
  }
  // Waits until pred() (called under the lock) holds; false at the deadline.
  template <typename Pred>
  bool waitFor(Pred pred, Clock::duration deadline) {
    std::unique_lock<std::mutex> lock(mu);
    return cv.wait_for(lock, deadline, pred);
  }
};

template <typename Pred>
bool pollUntil(Pred pred, Clock::duration deadline) {
  const auto end = Clock::now() + deadline;
  while (!pred()) {
    if (Clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));  // polling a condition, bounded
  }
  return true;
}

// Pushes `bytes` in uneven pieces, as a bridge's FIFO would fill.
void pushPieces(VirtualUsbBridge& dev, std::span<const std::uint8_t> bytes) {
  std::size_t i = 0, k = 0;
  const std::size_t sizes[] = {1, 17, 18, 19, 700, 4096, 5000, 333, 9000};
  while (i < bytes.size()) {
    const std::size_t n = std::min(sizes[k++ % std::size(sizes)], bytes.size() - i);
    dev.push(bytes.subspan(i, n));
    i += n;
  }
}

bool sameFrames(const std::vector<bridge_frame_t>& a, const std::vector<bridge_frame_t>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (key(a[i]) != key(b[i])) return false;
  return true;
}

// CRUNCH_HIL_USB: the real device's id, or nothing for the virtual one. A malformed value fails.
std::optional<UsbId> realId() {
  const char* env = std::getenv("CRUNCH_HIL_USB");
  if (env == nullptr || *env == '\0') return std::nullopt;
  auto id = crunch::io::parseUsbId(env);
  if (!id) FAIL("CRUNCH_HIL_USB: " << id.error().message);
  return id.value();
}

bool announceVirtual() {
  if (realId()) {
    WARN("hil: CRUNCH_HIL_USB set: this virtual-only fault case is not run against hardware");
    return false;
  }
  std::printf("hil: virtual USB bridge (umockdev)\n");
  REQUIRE(VirtualUsbBridge::preloaded());  // else ensurePreloaded() printed why
  return true;
}

}  // namespace

TEST_CASE("USB HIL: frames stream through 8 transfers in flight, each decoded once in order",
          "[hil][usb]") {
  if (auto id = realId()) {
    std::printf("hil: real USB bridge %s\n", crunch::io::formatUsbId(*id).c_str());
    Receiver rx;
    UsbBridge::Options o;
    o.id = *id;
    auto bridge = UsbBridge::open(o, rx.chunkHandler(), rx.stateHandler());
    if (!bridge) FAIL("real bridge requested by CRUNCH_HIL_USB: " << bridge.error().message);
    // Read for 2 s (a fixed measurement window, not a synchronisation).
    std::this_thread::sleep_for(std::chrono::seconds(2));
    bridge.value()->stop();
    std::lock_guard<std::mutex> lock(rx.mu);
    const auto& c = rx.decoder.counters();
    std::printf("hil: %llu bytes, %llu frames, %llu CRC failures in 2 s\n",
                static_cast<unsigned long long>(c.bytes),
                static_cast<unsigned long long>(c.frames),
                static_cast<unsigned long long>(c.crc_failures));
    REQUIRE(c.frames > 0);  // a bridge that sends nothing is a failure, not a pass
    CHECK(c.crc_failures * 100 <= c.frames);
    return;
  }

  REQUIRE(announceVirtual());
  auto dev = VirtualUsbBridge::create({});
  REQUIRE(dev.ok());
  VirtualUsbBridge& vdev = *dev.value();
  const Bytes stream = makeStream(4, 3000);  // 12000 frames, 216 kB (0.75 s of 8 boards)
  const Reference ref = decodeAll(stream);
  REQUIRE(ref.frames.size() == 12000);

  Receiver rx;
  UsbBridge::Options o;  // defaults: 1209:0001, 0x81, 8 x 4096
  auto bridge = UsbBridge::open(o, rx.chunkHandler(), rx.stateHandler());
  REQUIRE(bridge.ok());
  UsbBridge& br = *bridge.value();
  CHECK(br.devicePath() == vdev.devicePath());
  // All 8 transfers are posted to the device before any data exists.
  REQUIRE(pollUntil([&] { return vdev.urbsInFlight() == 8; }, kStateDeadline));

  const auto t0 = Clock::now();
  pushPieces(vdev, stream);
  REQUIRE(rx.waitFor([&] { return rx.frames.size() >= ref.frames.size(); }, kDeliveryDeadline));
  const double s = std::chrono::duration<double>(Clock::now() - t0).count();
  std::printf("hil: %zu bytes in %.3f s through the virtual device: %.2f MB/s, %.0f frames/s, "
              "%llu URBs\n",
              stream.size(), s, stream.size() / s / 1e6, ref.frames.size() / s,
              static_cast<unsigned long long>(vdev.urbsCompleted()));
  // Back to idle: every transfer resubmitted and waiting again.
  REQUIRE(pollUntil([&] { return vdev.urbsInFlight() == 8; }, kStateDeadline));
  br.stop();

  std::lock_guard<std::mutex> lock(rx.mu);
  CHECK(sameFrames(rx.frames, ref.frames));
  const auto& c = rx.decoder.counters();
  CHECK(c.frames == ref.frames.size());
  CHECK(c.crc_failures == 0);
  CHECK(c.skipped_bytes == 0);
  CHECK(c.bytes == stream.size());
  CHECK(br.bytes() == stream.size());
  CHECK(vdev.bytesDelivered() == stream.size());
  CHECK(br.transfersCompleted() == vdev.urbsCompleted());
  CHECK(br.transferErrors() == 0);
  CHECK(br.disconnects() == 0);
  CHECK_FALSE(rx.saw_zero_length);
  CHECK(rx.states.empty());
  for (int b = 0; b < 4; ++b) CHECK(c.boards[b].lost_frames == 0);
}

TEST_CASE("USB HIL: corrupt frames are counted by the decoder and never delivered",
          "[hil][usb]") {
  if (!announceVirtual()) return;
  auto dev = VirtualUsbBridge::create({});
  REQUIRE(dev.ok());
  Bytes stream = makeStream(2, 1000);  // 2000 frames
  const Reference clean = decodeAll(stream);
  // Flip one payload bit in every 50th frame: its CRC no longer matches.
  std::vector<bridge_frame_t> expected;
  int corrupted = 0;
  for (std::size_t i = 0; i < clean.frames.size(); ++i) {
    if (i % 50 == 7) {
      stream[i * BRIDGE_FRAME_LEN + 9] ^= 0x01;
      ++corrupted;
    } else {
      expected.push_back(clean.frames[i]);
    }
  }
  const Reference ref = decodeAll(stream);
  REQUIRE(sameFrames(ref.frames, expected));

  Receiver rx;
  auto bridge = UsbBridge::open({}, rx.chunkHandler(), rx.stateHandler());
  REQUIRE(bridge.ok());
  pushPieces(*dev.value(), stream);
  REQUIRE(rx.waitFor([&] { return rx.decoder.counters().bytes >= stream.size(); },
                     kDeliveryDeadline));
  bridge.value()->stop();

  std::lock_guard<std::mutex> lock(rx.mu);
  CHECK(sameFrames(rx.frames, expected));  // none of the corrupt ones, all of the others
  const auto& c = rx.decoder.counters();
  CHECK(c.crc_failures >= static_cast<std::uint64_t>(corrupted));
  CHECK(c.crc_failures == ref.counters.crc_failures);  // the same as one whole-stream feed
  CHECK(c.skipped_bytes == ref.counters.skipped_bytes);
  CHECK(c.boards[0].lost_frames + c.boards[1].lost_frames ==
        static_cast<std::uint64_t>(corrupted));
}

namespace {

// Unplugs after half the stream and replugs with the rest queued; `use_hotplug` picks how the
// bridge notices the return. Returns the replug-to-kConnected time in seconds.
double unplugReplug(bool use_hotplug, double poll_s) {
  auto dev = VirtualUsbBridge::create({});
  REQUIRE(dev.ok());
  VirtualUsbBridge& vdev = *dev.value();
  const Bytes stream = makeStream(4, 1000);  // 4000 frames
  const Reference ref = decodeAll(stream);
  const std::size_t half = 2000 * BRIDGE_FRAME_LEN;

  Receiver rx;
  UsbBridge::Options o;
  o.reconnect_poll_s = poll_s;
  o.use_hotplug = use_hotplug;
  auto bridge = UsbBridge::open(o, rx.chunkHandler(), rx.stateHandler());
  REQUIRE(bridge.ok());
  UsbBridge& br = *bridge.value();
  const std::string first_path = br.devicePath();

  pushPieces(vdev, std::span<const std::uint8_t>(stream).first(half));
  REQUIRE(rx.waitFor([&] { return rx.frames.size() >= 2000; }, kDeliveryDeadline));

  const auto t_unplug = Clock::now();
  vdev.unplug();
  REQUIRE(rx.waitFor([&] { return !rx.states.empty(); }, kStateDeadline));
  const double detect_s = std::chrono::duration<double>(Clock::now() - t_unplug).count();
  {
    std::lock_guard<std::mutex> lock(rx.mu);
    REQUIRE(rx.states.size() == 1);
    CHECK(rx.states[0].first == UsbBridge::LinkState::kDisconnected);
    INFO(rx.states[0].second);
    CHECK(rx.states[0].second.find("1209:0001") != std::string::npos);
    CHECK(rx.states[0].second.find(first_path) != std::string::npos);
    CHECK(rx.states[0].second.find("disconnected") != std::string::npos);
    CHECK(rx.frames.size() == 2000);  // what was received is kept
  }
  CHECK_FALSE(br.connected());
  CHECK(br.disconnects() == 1);
  const std::uint64_t bytes_before = br.bytes();
  CHECK(bytes_before == half);

  // The bridge keeps producing while the host cannot read: the bytes wait in its FIFO.
  pushPieces(vdev, std::span<const std::uint8_t>(stream).subspan(half));
  const auto t_replug = Clock::now();
  vdev.replug();
  REQUIRE(rx.waitFor([&] { return rx.states.size() >= 2; }, kStateDeadline));
  const double reconnect_s = std::chrono::duration<double>(Clock::now() - t_replug).count();
  std::printf("hil: unplug detected in %.1f ms, replug reconnected in %.1f ms (%s, poll %.0f ms)\n",
              detect_s * 1e3, reconnect_s * 1e3, use_hotplug ? "hotplug" : "polling only",
              o.reconnect_poll_s * 1e3);
  {
    std::lock_guard<std::mutex> lock(rx.mu);
    CHECK(rx.states[1].first == UsbBridge::LinkState::kConnected);
    CHECK(rx.states[1].second.find("1209:0001") != std::string::npos);
  }
  CHECK(br.devicePath() == vdev.devicePath());
  CHECK(br.devicePath() != first_path);  // re-enumerated with a new address
  REQUIRE(rx.waitFor([&] { return rx.frames.size() >= ref.frames.size(); }, kDeliveryDeadline));
  br.stop();

  std::lock_guard<std::mutex> lock(rx.mu);
  CHECK(sameFrames(rx.frames, ref.frames));  // every frame once, in order, across the gap
  CHECK(rx.decoder.counters().crc_failures == 0);
  CHECK(br.bytes() == stream.size());
  CHECK(br.disconnects() == 1);
  CHECK(br.reconnects() == 1);
  CHECK(rx.states.size() == 2);
  return reconnect_s;
}

}  // namespace

TEST_CASE("USB HIL: unplug mid-stream is reported, replug resumes with the counters kept (hotplug)",
          "[hil][usb]") {
  if (!announceVirtual()) return;
  if (!UsbBridge::hotplugSupported()) {
    WARN("hil: this libusb has no hotplug; the polling case covers reconnection");
    return;
  }
  // A 3 s poll: coming back well before it proves the hotplug arrival did it.
  CHECK(unplugReplug(true, 3.0) < 1.5);
}

TEST_CASE("USB HIL: without hotplug the poll alone finds the replugged bridge", "[hil][usb]") {
  if (!announceVirtual()) return;
  CHECK(unplugReplug(false, 0.05) < 5.0);
}

TEST_CASE("USB HIL: a second reader of the same bridge is refused as busy", "[hil][usb]") {
  if (!announceVirtual()) return;
  auto dev = VirtualUsbBridge::create({});
  REQUIRE(dev.ok());
  auto first = UsbBridge::open({}, nullptr, nullptr);
  REQUIRE(first.ok());
  auto second = UsbBridge::open({}, nullptr, nullptr);
  REQUIRE_FALSE(second.ok());
  INFO(second.error().message);
  CHECK(second.error().message.find("busy") != std::string::npos);
  CHECK(second.error().message.find(dev.value()->devicePath()) != std::string::npos);
}

TEST_CASE("USB HIL: no bridge attached gives the actionable error", "[hil][usb]") {
  if (!announceVirtual()) return;
  auto dev = VirtualUsbBridge::create({});
  REQUIRE(dev.ok());
  UsbBridge::Options o;
  o.id = UsbId{0x1209, 0x0002};  // present: 1209:0001 only
  auto r = UsbBridge::open(o, nullptr, nullptr);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message ==
        "no whisker bridge with USB id 1209:0002 found: is it plugged in and powered? (`lsusb` "
        "lists USB devices; --usb VID:PID selects another id)");
  dev.value()->unplug();
  auto gone = UsbBridge::open({}, nullptr, nullptr);
  REQUIRE_FALSE(gone.ok());
  CHECK(gone.error().message.find("no whisker bridge with USB id 1209:0001 found") !=
        std::string::npos);
}

TEST_CASE("USB HIL: only the USB node is emulated, a pty opened under /dev keeps the kernel's "
          "ioctls",
          "[hil][usb]") {
  if (!announceVirtual()) return;
  auto dev = VirtualUsbBridge::create({});
  REQUIRE(dev.ok());
  // A Create's port as a child opens it: by its /dev/pts path, through the preload's open().
  int master = -1, slave = -1;
  REQUIRE(::openpty(&master, &slave, nullptr, nullptr, nullptr) == 0);
  char name[128] = {};
  REQUIRE(::ttyname_r(slave, name, sizeof name) == 0);
  const int fd = ::open(name, O_RDWR | O_NOCTTY);
  REQUIRE(fd >= 0);
  INFO(name);
  // umockdev 0.17 routed these to its catch-all handler, which answered ENOTTY (issue 18).
  int on = 1;
  CHECK(::ioctl(fd, FIONBIO, &on) == 0);
  termios raw{};
  REQUIRE(::tcgetattr(fd, &raw) == 0);
  ::cfmakeraw(&raw);
  REQUIRE(::tcsetattr(fd, TCSANOW, &raw) == 0);  // bytes, not lines
  REQUIRE(::write(master, "abc", 3) == 3);
  pollfd p{fd, POLLIN, 0};
  REQUIRE(::poll(&p, 1, 1000) == 1);  // the tty layer has moved the one write across
  int pending = -1;
  CHECK(::ioctl(fd, FIONREAD, &pending) == 0);
  CHECK(pending == 3);
  ::close(fd);
  ::close(slave);
  ::close(master);
  // The USB node still is emulated: libusb finds and opens the bridge.
  CHECK(UsbBridge::open({}, nullptr, nullptr).ok());
}

int main(int argc, char** argv) {
  // The virtual device needs libumockdev-preload in this process (docs/USB.md); a real one
  // does not, and must not be hidden behind an empty testbed.
  if (std::getenv("CRUNCH_HIL_USB") == nullptr) VirtualUsbBridge::ensurePreloaded(argc, argv);
  return crunch::testing::runCatchSession(argc, argv);
}
