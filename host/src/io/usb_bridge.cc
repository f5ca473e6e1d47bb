#include "crunch/io/usb_bridge.h"

#include <libusb.h>
#include <sys/types.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace crunch::io {

namespace {

// ---- RAII wrappers for libusb objects -------------------------------------------------------

struct ContextDeleter {
  void operator()(libusb_context* c) const { libusb_exit(c); }
};
using ContextPtr = std::unique_ptr<libusb_context, ContextDeleter>;

struct DeviceListDeleter {
  void operator()(libusb_device** list) const { libusb_free_device_list(list, 1); }
};
// The list and the count libusb_get_device_list() returned; unreferences the devices.
struct DeviceList {
  std::unique_ptr<libusb_device*, DeviceListDeleter> list;
  ssize_t count = 0;
};

struct ConfigDeleter {
  void operator()(libusb_config_descriptor* c) const { libusb_free_config_descriptor(c); }
};
using ConfigPtr = std::unique_ptr<libusb_config_descriptor, ConfigDeleter>;

struct TransferDeleter {
  void operator()(libusb_transfer* t) const { libusb_free_transfer(t); }
};
using TransferPtr = std::unique_ptr<libusb_transfer, TransferDeleter>;

// An open device; the interface it claimed (if any) is released before it is closed.
class DeviceHandle {
 public:
  explicit DeviceHandle(libusb_device_handle* h) : h_(h) {}
  ~DeviceHandle() {
    if (claimed_ >= 0) libusb_release_interface(h_, claimed_);
    libusb_close(h_);
  }
  DeviceHandle(const DeviceHandle&) = delete;
  DeviceHandle& operator=(const DeviceHandle&) = delete;

  libusb_device_handle* get() const { return h_; }
  int claim(int interface) {
    const int r = libusb_claim_interface(h_, interface);
    if (r == 0) claimed_ = interface;
    return r;
  }

 private:
  libusb_device_handle* h_;
  int claimed_ = -1;
};

std::uint64_t monotonicNs() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::uint64_t>(ts.tv_sec) * 1'000'000'000ull +
         static_cast<std::uint64_t>(ts.tv_nsec);
}

std::string nodePath(libusb_device* dev) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "/dev/bus/usb/%03u/%03u",
                static_cast<unsigned>(libusb_get_bus_number(dev)),
                static_cast<unsigned>(libusb_get_device_address(dev)));
  return buf;
}

std::string usbError(int r) {
  return std::string(libusb_error_name(r)) + " (" + libusb_strerror(r) + ")";
}

int hexDigit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

bool parseHex16(std::string_view s, std::uint16_t& out) {
  if (s.empty() || s.size() > 4) return false;
  unsigned v = 0;
  for (char c : s) {
    const int d = hexDigit(c);
    if (d < 0) return false;
    v = v * 16 + static_cast<unsigned>(d);
  }
  out = static_cast<std::uint16_t>(v);
  return true;
}

constexpr int kMaxTransfers = 64;
constexpr int kMaxTransferSize = 1 << 20;
// How long stop() or a disconnection waits for cancelled transfers to come back. libusb
// guarantees a callback for each, normally within a millisecond; past this the transfers and
// the handle are leaked rather than freed under the kernel's feet.
constexpr auto kDrainDeadline = std::chrono::seconds(5);
// Slice of libusb event handling between checks of the stop flag and the reconnect timer.
constexpr long kEventSliceUs = 50'000;

}  // namespace

Result<UsbId> parseUsbId(std::string_view text) {
  const auto colon = text.find(':');
  UsbId id;
  if (colon == std::string_view::npos || !parseHex16(text.substr(0, colon), id.vid) ||
      !parseHex16(text.substr(colon + 1), id.pid))
    return Error{"bad USB id '" + std::string(text) +
                 "': expected VID:PID in hexadecimal, e.g. 1209:0001 (as lsusb prints it)"};
  return id;
}

std::string formatUsbId(UsbId id) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "%04x:%04x", static_cast<unsigned>(id.vid),
                static_cast<unsigned>(id.pid));
  return buf;
}

// ---- the bridge --------------------------------------------------------------------------------

struct UsbBridge::Impl {
  struct Slot {
    Impl* impl = nullptr;
    TransferPtr transfer;
    std::vector<std::uint8_t> buffer;
    bool in_flight = false;
  };

  UsbBridge* owner = nullptr;
  Options opt;
  std::string id_text;
  ChunkHandler on_chunk;
  StateHandler on_state;

  // Destroyed in reverse order: transfers, then the device, then the context.
  ContextPtr ctx;
  std::unique_ptr<DeviceHandle> handle;
  std::vector<Slot> slots;  // sized once in open(); Slot addresses are transfer user_data

  // Event-thread state (open() touches it before the thread starts).
  int in_flight = 0;
  bool closing = false;          // a disconnection was seen; draining the transfers
  std::string close_reason;      // why, for the kDisconnected message
  int consecutive_errors = 0;
  std::chrono::steady_clock::time_point next_poll{};
  bool leaked = false;           // transfers never came back: handle and transfers not freed

  libusb_hotplug_callback_handle hotplug{};
  bool hotplug_registered = false;
  std::atomic<bool> hotplug_arrived{false};
  std::atomic<bool> stop_requested{false};

  mutable std::mutex path_mu;
  std::string path;

  std::mutex ctx_mu;  // guards replacing `ctx` (event thread) against stop()'s interrupt

  std::mutex stop_mu;
  std::thread thread;

  ~Impl() {
    if (hotplug_registered) libusb_hotplug_deregister_callback(ctx.get(), hotplug);
    if (leaked) {  // see kDrainDeadline: never free what the kernel may still write to
      for (auto& s : slots) (void)s.transfer.release();
      (void)handle.release();
      (void)ctx.release();
    }
  }

  std::string deviceName() const {
    std::lock_guard<std::mutex> lock(path_mu);
    return "the whisker bridge " + id_text + (path.empty() ? "" : " at " + path);
  }

  void registerHotplug() {
    if (!opt.use_hotplug || !libusb_has_capability(LIBUSB_CAP_HAS_HOTPLUG)) return;
    const int r = libusb_hotplug_register_callback(
        ctx.get(), LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED, LIBUSB_HOTPLUG_NO_FLAGS, opt.id.vid,
        opt.id.pid, LIBUSB_HOTPLUG_MATCH_ANY, &Impl::onHotplug, this, &hotplug);
    hotplug_registered = (r == 0);  // without it the poll still finds the device
  }

  // A fresh context enumerates the bus afresh. With a hotplug-capable backend libusb's device
  // list changes only on hotplug events, which never come where no udev daemon runs (many
  // containers) or a monitor missed them; the poll must not depend on them. Only while no
  // device is open (no transfers refer to the old context).
  void renewContext() {
    libusb_context* fresh = nullptr;
    if (libusb_init(&fresh) != 0) return;  // keep the old one; the next poll tries again
    if (hotplug_registered) libusb_hotplug_deregister_callback(ctx.get(), hotplug);
    hotplug_registered = false;
    {
      std::lock_guard<std::mutex> lock(ctx_mu);
      ctx.reset(fresh);
    }
    registerHotplug();
  }

  static void LIBUSB_CALL onTransfer(libusb_transfer* t) {
    auto* slot = static_cast<Slot*>(t->user_data);
    slot->impl->completed(*slot, t);
  }

  static int LIBUSB_CALL onHotplug(libusb_context*, libusb_device*, libusb_hotplug_event event,
                                   void* user) {
    if (event == LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED)
      static_cast<Impl*>(user)->hotplug_arrived.store(true);
    return 0;  // stay registered
  }

  // Transfer callback, on the event thread (or inside open()'s drain).
  void completed(Slot& slot, libusb_transfer* t) {
    slot.in_flight = false;
    --in_flight;
    switch (t->status) {
      case LIBUSB_TRANSFER_COMPLETED:
      case LIBUSB_TRANSFER_TIMED_OUT:  // may carry part of its data
        if (t->status == LIBUSB_TRANSFER_COMPLETED) {
          owner->transfers_completed_.fetch_add(1, std::memory_order_relaxed);
          consecutive_errors = 0;
        }
        if (t->actual_length > 0) {
          const std::uint64_t now = monotonicNs();
          owner->bytes_.fetch_add(static_cast<std::uint64_t>(t->actual_length),
                                  std::memory_order_relaxed);
          if (on_chunk && !stop_requested.load(std::memory_order_relaxed))
            on_chunk(std::span<const std::uint8_t>(t->buffer,
                                                   static_cast<std::size_t>(t->actual_length)),
                     now);
        }
        break;
      case LIBUSB_TRANSFER_CANCELLED:
        return;
      case LIBUSB_TRANSFER_NO_DEVICE:
        beginClose("the device was removed");
        return;
      case LIBUSB_TRANSFER_ERROR:
      case LIBUSB_TRANSFER_STALL:
      case LIBUSB_TRANSFER_OVERFLOW:
      default:
        owner->transfer_errors_.fetch_add(1, std::memory_order_relaxed);
        // A few failures are link noise; a stream of them with nothing good between is a
        // device that has gone (the kernel reports some unplugs as protocol errors).
        if (++consecutive_errors > 2 * opt.transfers) {
          beginClose(std::string("repeated transfer errors (last: ") +
                     libusb_error_name(t->status) + ")");
          return;
        }
        break;
    }
    if (closing || stop_requested.load(std::memory_order_relaxed)) return;
    const int r = libusb_submit_transfer(t);
    if (r == 0) {
      slot.in_flight = true;
      ++in_flight;
    } else {
      beginClose("resubmitting a transfer failed: " + usbError(r));
    }
  }

  void beginClose(std::string reason) {
    if (closing) return;
    closing = true;
    close_reason = std::move(reason);
  }

  void cancelAll() {
    for (auto& s : slots)
      if (s.in_flight && s.transfer) libusb_cancel_transfer(s.transfer.get());
  }

  // Handles events until every transfer is back; false if kDrainDeadline passed first.
  bool drain() {
    const auto deadline = std::chrono::steady_clock::now() + kDrainDeadline;
    while (in_flight > 0) {
      if (std::chrono::steady_clock::now() > deadline) return false;
      timeval tv{0, kEventSliceUs};
      libusb_handle_events_timeout_completed(ctx.get(), &tv, nullptr);
    }
    return true;
  }

  // Cancels and reaps the transfers, then releases the interface and closes the device.
  void closeDevice() {
    if (!handle) return;
    cancelAll();
    if (!drain()) {
      leaked = true;
      return;
    }
    // A completed transfer keeps a reference to its device until it is resubmitted or freed
    // (libusb 1.0.26), and libusb_free_transfer() reads transfer->dev_handle. Free them now,
    // while the device and its context live, with no dangling handle; openDevice() makes new
    // ones. (A reconnection may replace the context.)
    for (auto& s : slots) {
      s.transfer->dev_handle = nullptr;
      s.transfer.reset();
    }
    handle.reset();
  }

  // Finds, opens and claims the device and submits every transfer. On failure nothing is
  // left open and the message says what to do.
  Status openDevice() {
    libusb_device** raw = nullptr;
    DeviceList list;
    list.count = libusb_get_device_list(ctx.get(), &raw);
    list.list.reset(raw);
    if (list.count < 0)
      return Error{"cannot list USB devices while looking for the whisker bridge " + id_text +
                   ": " + usbError(static_cast<int>(list.count))};
    libusb_device* dev = nullptr;
    for (ssize_t i = 0; i < list.count && dev == nullptr; ++i) {
      libusb_device_descriptor d{};
      if (libusb_get_device_descriptor(raw[i], &d) == 0 && d.idVendor == opt.id.vid &&
          d.idProduct == opt.id.pid)
        dev = raw[i];
    }
    if (dev == nullptr)
      return Error{"no whisker bridge with USB id " + id_text +
                   " found: is it plugged in and powered? (`lsusb` lists USB devices; --usb "
                   "VID:PID selects another id)"};
    const std::string node = nodePath(dev);

    libusb_device_handle* h = nullptr;
    int r = libusb_open(dev, &h);
    if (r == LIBUSB_ERROR_ACCESS)
      return Error{"permission denied opening the whisker bridge " + id_text + " at " + node +
                   ": install the udev rule (sudo cp tools/udev/99-crunchbot.rules "
                   "/etc/udev/rules.d/ && sudo udevadm control --reload && replug) and add "
                   "yourself to plugdev (sudo usermod -aG plugdev $USER, then log in again)"};
    if (r != 0)
      return Error{"cannot open the whisker bridge " + id_text + " at " + node + ": " +
                   usbError(r) + (r == LIBUSB_ERROR_NO_DEVICE ? ": it was unplugged" : "")};
    auto dh = std::make_unique<DeviceHandle>(h);

    r = dh->claim(opt.interface);
    if (r == LIBUSB_ERROR_BUSY)
      return Error{"the whisker bridge " + id_text + " at " + node + " is busy: interface " +
                   std::to_string(opt.interface) +
                   " is claimed by another program or kernel driver (another crunchhost?); "
                   "stop it and retry"};
    if (r == LIBUSB_ERROR_NOT_FOUND)
      return Error{"the USB device " + id_text + " at " + node + " has no interface " +
                   std::to_string(opt.interface) +
                   ": is it a whisker bridge? (--usb VID:PID selects another id)"};
    if (r != 0)
      return Error{"cannot claim interface " + std::to_string(opt.interface) +
                   " of the whisker bridge " + id_text + " at " + node + ": " + usbError(r)};

    if (Status s = checkEndpoint(dev, node); !s) return s;

    {
      std::lock_guard<std::mutex> lock(path_mu);
      path = node;
    }
    handle = std::move(dh);
    closing = false;
    consecutive_errors = 0;
    for (auto& s : slots) {
      if (!s.transfer) s.transfer.reset(libusb_alloc_transfer(0));
      if (!s.transfer) {
        closeDevice();
        return Error{"whisker bridge " + id_text + ": out of memory for USB transfers"};
      }
      libusb_fill_bulk_transfer(s.transfer.get(), handle->get(), opt.endpoint, s.buffer.data(),
                                opt.transfer_size, &Impl::onTransfer, &s, opt.timeout_ms);
      r = libusb_submit_transfer(s.transfer.get());
      if (r != 0) {
        closeDevice();
        return Error{"cannot submit a bulk IN transfer to endpoint 0x" + hex2(opt.endpoint) +
                     " of the whisker bridge " + id_text + " at " + node + ": " + usbError(r)};
      }
      s.in_flight = true;
      ++in_flight;
    }
    return okStatus();
  }

  static std::string hex2(std::uint8_t v) {
    char buf[4];
    std::snprintf(buf, sizeof buf, "%02x", static_cast<unsigned>(v));
    return buf;
  }

  // The claimed interface must have Options::endpoint as a bulk IN endpoint.
  Status checkEndpoint(libusb_device* dev, const std::string& node) const {
    libusb_config_descriptor* raw = nullptr;
    const int r = libusb_get_active_config_descriptor(dev, &raw);
    if (r != 0)
      return Error{"cannot read the configuration descriptor of the whisker bridge " + id_text +
                   " at " + node + ": " + usbError(r)};
    ConfigPtr cfg(raw);
    for (int i = 0; i < cfg->bNumInterfaces; ++i) {
      const libusb_interface& itf = cfg->interface[i];
      for (int a = 0; a < itf.num_altsetting; ++a) {
        const libusb_interface_descriptor& alt = itf.altsetting[a];
        if (alt.bInterfaceNumber != opt.interface) continue;
        for (int e = 0; e < alt.bNumEndpoints; ++e) {
          const libusb_endpoint_descriptor& ep = alt.endpoint[e];
          if (ep.bEndpointAddress == opt.endpoint &&
              (ep.bmAttributes & 0x3) == LIBUSB_TRANSFER_TYPE_BULK)
            return okStatus();
        }
      }
    }
    return Error{"the USB device " + id_text + " at " + node + " has no bulk IN endpoint 0x" +
                 hex2(opt.endpoint) + " on interface " + std::to_string(opt.interface) +
                 ": is it a whisker bridge with the firmware docs/USB.md describes?"};
  }

  void report(LinkState state, const std::string& message) {
    if (on_state) on_state(state, message);
  }

  // The event thread.
  void run() {
    while (!stop_requested.load()) {
      if (handle && closing) {
        const std::string name = deviceName();
        closeDevice();
        if (leaked) break;
        owner->connected_.store(false, std::memory_order_release);
        owner->disconnects_.fetch_add(1);
        next_poll = std::chrono::steady_clock::now();
        report(LinkState::kDisconnected,
               name + " disconnected (" + close_reason +
                   "): keeping what was received and waiting for it to come back");
        continue;
      }
      if (!handle) {
        const auto now = std::chrono::steady_clock::now();
        const bool arrived = hotplug_arrived.exchange(false);
        if (arrived || now >= next_poll) {
          if (!arrived) renewContext();
          next_poll = now + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                std::chrono::duration<double>(opt.reconnect_poll_s));
          if (openDevice()) {
            owner->connected_.store(true, std::memory_order_release);
            owner->reconnects_.fetch_add(1);
            report(LinkState::kConnected, deviceName() + " reconnected: reading again");
            continue;
          }
        }
        const auto wait = std::chrono::duration_cast<std::chrono::microseconds>(
            next_poll - std::chrono::steady_clock::now());
        const long us = std::max(0L, std::min<long>(kEventSliceUs, wait.count()));
        timeval tv{0, us};
        // Without an open device this only waits for hotplug events (or the timeout).
        libusb_handle_events_timeout_completed(ctx.get(), &tv, nullptr);
        continue;
      }
      timeval tv{0, kEventSliceUs};
      libusb_handle_events_timeout_completed(ctx.get(), &tv, nullptr);
    }
    closeDevice();
    owner->connected_.store(false, std::memory_order_release);
  }
};

UsbBridge::UsbBridge(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {
  impl_->owner = this;
}

UsbBridge::~UsbBridge() { stop(); }

Result<std::unique_ptr<UsbBridge>> UsbBridge::open(const Options& options, ChunkHandler on_chunk,
                                                   StateHandler on_state) {
  const std::string id_text = formatUsbId(options.id);
  if (options.transfers < 1 || options.transfers > kMaxTransfers)
    return Error{"whisker bridge " + id_text + ": transfers in flight must be 1.." +
                 std::to_string(kMaxTransfers) + ", not " + std::to_string(options.transfers)};
  if (options.transfer_size < 1 || options.transfer_size > kMaxTransferSize)
    return Error{"whisker bridge " + id_text + ": transfer size must be 1.." +
                 std::to_string(kMaxTransferSize) + " bytes, not " +
                 std::to_string(options.transfer_size)};
  if (!(options.reconnect_poll_s > 0.0) || options.reconnect_poll_s > 3600.0)
    return Error{"whisker bridge " + id_text + ": reconnect poll interval must be in (0, 3600] s"};
  if ((options.endpoint & LIBUSB_ENDPOINT_IN) == 0)
    return Error{"whisker bridge " + id_text + ": endpoint 0x" + Impl::hex2(options.endpoint) +
                 " is not an IN endpoint (bit 7 must be set, e.g. 0x81)"};
  if (options.interface < 0 || options.interface > 255)
    return Error{"whisker bridge " + id_text + ": interface must be 0..255"};

  auto impl = std::make_unique<Impl>();
  impl->opt = options;
  impl->id_text = id_text;
  impl->on_chunk = std::move(on_chunk);
  impl->on_state = std::move(on_state);

  libusb_context* raw_ctx = nullptr;
  if (const int r = libusb_init(&raw_ctx); r != 0)
    return Error{"cannot start libusb to look for the whisker bridge " + id_text + ": " +
                 usbError(r) +
                 " (is /dev/bus/usb available? in a container, pass the USB bus through)"};
  impl->ctx.reset(raw_ctx);

  impl->slots.resize(static_cast<std::size_t>(options.transfers));
  for (auto& s : impl->slots) {
    s.impl = impl.get();
    s.buffer.assign(static_cast<std::size_t>(options.transfer_size), 0);
  }

  // The owner must exist before a transfer can complete (the callbacks count into it).
  std::unique_ptr<UsbBridge> bridge(new UsbBridge(std::move(impl)));
  Impl& im = *bridge->impl_;
  if (Status s = im.openDevice(); !s) return s.error();
  bridge->connected_.store(true);

  im.registerHotplug();
  im.thread = std::thread([&im] { im.run(); });
  return bridge;
}

bool UsbBridge::hotplugSupported() { return libusb_has_capability(LIBUSB_CAP_HAS_HOTPLUG) != 0; }

void UsbBridge::stop() {
  std::lock_guard<std::mutex> lock(impl_->stop_mu);
  if (impl_->thread.joinable()) {
    impl_->stop_requested.store(true);
    {
      std::lock_guard<std::mutex> ctx_lock(impl_->ctx_mu);
      libusb_interrupt_event_handler(impl_->ctx.get());
    }
    impl_->thread.join();
  } else if (impl_->handle) {  // open() failed after opening: not reached today, kept safe
    impl_->stop_requested.store(true);
    impl_->closeDevice();
  }
}

std::string UsbBridge::devicePath() const {
  std::lock_guard<std::mutex> lock(impl_->path_mu);
  return impl_->path;
}

}  // namespace crunch::io
