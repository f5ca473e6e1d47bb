// The USB side of the whisker bridge (paper §2.1; docs/USB.md is the contract in prose): the FPGA
// bridge is a vendor-specific USB device that streams the 18-byte bridge frames of up to 28
// whisker boards (docs/protocol.md) on one bulk IN endpoint. UsbBridge reads that endpoint with
// libusb-1.0's asynchronous API, several transfers in flight so the bus never idles while the
// host handles a completed one, and hands every non-empty completed transfer (a "chunk": any
// number of bytes, frames cut anywhere) to the caller, who feeds it to io::BridgeStreamDecoder.
//
// Threads: open() runs on the caller's thread; afterwards one event thread, owned by the
// bridge, runs libusb's event loop. The ChunkHandler and the StateHandler are called on that
// thread only, one call at a time, never after stop() returns. They must not call stop() or
// destroy the bridge (that would join the thread from itself). The counters are atomics,
// readable from any thread. stop() and the destructor may be called from any other thread.
//
// Unplug and replug: a transfer that completes with LIBUSB_TRANSFER_NO_DEVICE, or one that
// cannot be resubmitted, closes the device: the remaining transfers are cancelled and reaped,
// the interface released and the handle closed; the StateHandler gets kDisconnected with a
// message naming the device. The bridge keeps its counters and keeps looking for the device —
// on a libusb hotplug arrival where the platform has hotplug (LIBUSB_CAP_HAS_HOTPLUG), and by
// polling every Options::reconnect_poll_s regardless, since hotplug events may not reach every
// backend (each poll enumerates through a fresh libusb context, so it does not depend on
// udev events either: no udev daemon in a container, a monitor that missed the event). When it is back it is opened and claimed again, the transfers are resubmitted, the
// StateHandler gets kConnected and chunks flow again. The decoder should then be resync()ed.
//
// Ownership: every libusb object (context, device list, device handle with its claimed
// interface, transfer) lives in an RAII wrapper owned by the bridge; the transfer buffers are
// allocated in open() and reused for the bridge's life.
// Allocation: none on the data path (transfer callback → ChunkHandler → resubmit); only
// open() and a reconnection allocate.
// Errors: open() returns an Error whose message names the device and says what to do
// (plug it in, install the udev rule, close the other program, pick another id with --usb).
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "crunch/core/result.h"

namespace crunch::io {

// A USB vendor:product id pair.
struct UsbId {
  std::uint16_t vid = 0;
  std::uint16_t pid = 0;
};

// Parses "VVVV:PPPP" (1 to 4 hex digits each, either case, e.g. "1209:0001"). The error names
// the text and the expected form.
Result<UsbId> parseUsbId(std::string_view text);
// "1209:0001": four lower-case hex digits each.
std::string formatUsbId(UsbId id);

class UsbBridge {
 public:
  struct Options {
    // pid.codes' test id 1209:0001. The FPGA bridge's USB core is programmed with this id
    // (docs/USB.md, "Device id"); a bridge programmed with another id is selected with
    // `--usb VID:PID` (parseUsbId) and needs its own line in tools/udev/99-crunchbot.rules.
    UsbId id{0x1209, 0x0001};
    std::uint8_t endpoint = 0x81;  // bulk IN endpoint address (direction bit set)
    int interface = 0;             // interface number claimed
    int transfers = 8;             // bulk IN transfers kept in flight, 1..64
    int transfer_size = 4096;      // bytes per transfer, 1..1 MiB (a multiple of 512 is best)
    double reconnect_poll_s = 0.25;  // while disconnected, look for the device this often, > 0
    unsigned timeout_ms = 0;  // per-transfer timeout; 0 = none. A timed-out transfer (no data
                              // in that time) is resubmitted and counts no error.
    bool use_hotplug = true;  // also listen for libusb hotplug arrivals (when supported); the
                              // poll runs either way. false tests the poll alone.
  };

  // One completed transfer's bytes (actual_length > 0), valid during the call only, and the
  // CLOCK_MONOTONIC time of its completion in nanoseconds.
  using ChunkHandler = std::function<void(std::span<const std::uint8_t> bytes, std::uint64_t t_ns)>;
  enum class LinkState { kConnected, kDisconnected };
  using StateHandler = std::function<void(LinkState, const std::string& message)>;

  // Finds the device by Options::id, opens it, claims Options::interface, checks that
  // Options::endpoint is a bulk IN endpoint of it, submits Options::transfers bulk IN
  // transfers of Options::transfer_size bytes and starts the event thread. Returns an Error
  // (nothing left running) when the options are invalid, libusb cannot start, no such device
  // is attached, permission is denied (the message gives the udev rule and plugdev steps), the
  // interface is busy or missing, the endpoint is absent, or a transfer cannot be submitted.
  // The StateHandler is called on changes after open() returns (the first call, if any, is
  // kDisconnected); `on_state` may be empty.
  static Result<std::unique_ptr<UsbBridge>> open(const Options& options, ChunkHandler on_chunk,
                                                 StateHandler on_state);

  // Whether this libusb can report device arrivals (LIBUSB_CAP_HAS_HOTPLUG).
  static bool hotplugSupported();

  ~UsbBridge();  // stop()
  UsbBridge(const UsbBridge&) = delete;
  UsbBridge& operator=(const UsbBridge&) = delete;

  // Cancels the transfers, waits for their callbacks, releases the interface, closes the
  // device and joins the event thread. No handler is called after it returns. Idempotent.
  void stop();

  // The device node of the device currently (or last) open, "/dev/bus/usb/BBB/DDD".
  std::string devicePath() const;
  bool connected() const { return connected_.load(std::memory_order_acquire); }

  // Counters; monotonic over the bridge's life, across reconnections.
  std::uint64_t transfersCompleted() const { return transfers_completed_.load(); }  // with data
  std::uint64_t bytes() const { return bytes_.load(); }  // bytes handed to the ChunkHandler
  std::uint64_t transferErrors() const { return transfer_errors_.load(); }  // failed, stalled,
                                                                            // overflowed
  std::uint64_t disconnects() const { return disconnects_.load(); }
  std::uint64_t reconnects() const { return reconnects_.load(); }

 private:
  struct Impl;
  explicit UsbBridge(std::unique_ptr<Impl> impl);

  std::unique_ptr<Impl> impl_;
  std::atomic<bool> connected_{false};
  std::atomic<std::uint64_t> transfers_completed_{0};
  std::atomic<std::uint64_t> bytes_{0};
  std::atomic<std::uint64_t> transfer_errors_{0};
  std::atomic<std::uint64_t> disconnects_{0};
  std::atomic<std::uint64_t> reconnects_{0};
};

}  // namespace crunch::io
