#include "crunch_sim/virtual_usb_bridge.h"

#include <errno.h>
#include <linux/ioctl.h>
#include <linux/usbdevice_fs.h>
#include <sys/ioctl.h>
#include <umockdev.h>
#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <fstream>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace crunch::sim {

namespace {

constexpr char kPreloadLib[] = "libumockdev-preload.so.0";
constexpr char kReexecMark[] = "CRUNCH_UMOCKDEV_REEXEC";

std::string hex(const std::vector<std::uint8_t>& bytes) {
  std::string s;
  char b[3];
  for (std::uint8_t v : bytes) {
    std::snprintf(b, sizeof b, "%02x", static_cast<unsigned>(v));
    s += b;
  }
  return s;
}

// Device, configuration, interface and endpoint descriptors, as the kernel exposes them in
// sysfs "descriptors" (libusb reads them from there; USB 2.0 spec §9.6).
std::vector<std::uint8_t> descriptors(io::UsbId id, std::uint8_t endpoint) {
  auto lo = [](std::uint16_t v) { return static_cast<std::uint8_t>(v & 0xff); };
  auto hi = [](std::uint16_t v) { return static_cast<std::uint8_t>(v >> 8); };
  return {
      // device: USB 2.00, class 0xff (vendor), EP0 64 bytes, bcdDevice 1.00, no strings
      0x12, 0x01, 0x00, 0x02, 0xff, 0x00, 0x00, 0x40, lo(id.vid), hi(id.vid), lo(id.pid),
      hi(id.pid), 0x00, 0x01, 0x00, 0x00, 0x00, 0x01,
      // configuration 1: total 25 bytes, one interface, bus powered, 100 mA
      0x09, 0x02, 0x19, 0x00, 0x01, 0x01, 0x00, 0x80, 0x32,
      // interface 0, alt 0: one endpoint, class 0xff
      0x09, 0x04, 0x00, 0x00, 0x01, 0xff, 0x00, 0x00, 0x00,
      // endpoint: bulk IN, 512-byte packets (high speed)
      0x07, 0x05, endpoint, 0x02, 0x00, 0x02, 0x00};
}

std::string rootDirOf(UMockdevTestbed* testbed) {
  gchar* d = umockdev_testbed_get_root_dir(testbed);
  std::string s = d != nullptr ? d : "";
  g_free(d);
  return s;
}

}  // namespace

// umockdev_ioctl_data_resolve() returns a new reference (transfer full, UMockdev-1.0.gir): held
// here and dropped at the end of its scope. (Kept without unref, every URB's data - its 4 KB
// buffer and umockdev's copy of it - leaked: ~12 MB/s at crunchhost's ~1,200 transfers a second,
// and an hour's soak ran the machine out of memory at 32 minutes.)
struct DataUnref {
  void operator()(UMockdevIoctlData* d) const { g_object_unref(d); }
};
using DataRef = std::unique_ptr<UMockdevIoctlData, DataUnref>;

// `len` bytes at `offset` of `parent`, resolved from the client's memory; on failure the ioctl is
// completed with EFAULT and null returned (the caller then only returns).
DataRef resolveOrFault(UMockdevIoctlClient* client, UMockdevIoctlData* parent, gsize offset,
                       gsize len) {
  GError* err = nullptr;
  DataRef d(umockdev_ioctl_data_resolve(parent, offset, len, &err));
  if (d == nullptr) {
    if (err != nullptr) g_error_free(err);
    umockdev_ioctl_client_complete(client, -1, EFAULT);
  }
  return d;
}

struct VirtualUsbBridge::Impl {
  // A URB the client submitted: the resolved copy of its usbdevfs_urb and of its buffer.
  struct Urb {
    UMockdevIoctlClient* client = nullptr;  // ref held
    UMockdevIoctlData* urb = nullptr;       // ref held; owns `buffer`
    UMockdevIoctlData* buffer = nullptr;    // child of `urb`
    bool done = false;                      // completed, waiting to be reaped
  };

  Options opt;
  UMockdevTestbed* testbed = nullptr;
  UMockdevIoctlBase* handler = nullptr;
  gulong signal_id = 0;

  mutable std::mutex mu;
  std::deque<std::uint8_t> queue;
  std::deque<Urb> urbs;  // in submission order
  bool is_plugged = false;
  int devnum = 1;
  std::string syspath;   // of the plugged device
  std::string devnode;   // "/dev/bus/usb/001/NNN" of the plugged device
  std::vector<std::string> attached;  // every node the handler was attached to
  UMockdevIoctlClient* claimed_by = nullptr;  // not a ref: compared only
  // umockdev sends uevents through the preload's netlink emulation; without the preload in
  // this process they fail (clients then find a replugged device by polling only).
  bool send_uevents = false;
  std::uint64_t urbs_completed = 0;
  std::uint64_t bytes_delivered = 0;

  ~Impl() {
    {
      std::lock_guard<std::mutex> lock(mu);
      for (auto& u : urbs) release(u);
      urbs.clear();
    }
    for (const auto& node : attached) umockdev_testbed_detach_ioctl(testbed, node.c_str(), nullptr);
    if (handler != nullptr) {
      if (signal_id != 0) g_signal_handler_disconnect(handler, signal_id);
      g_object_unref(handler);
    }
    if (testbed != nullptr) g_object_unref(testbed);
  }

  static void release(Urb& u) {
    if (u.urb != nullptr) g_object_unref(u.urb);
    if (u.client != nullptr) g_object_unref(u.client);
    u.urb = nullptr;
    u.client = nullptr;
  }

  // Adds the device with the current devnum and attaches the handler to its node.
  bool plug() {
    char node[32];
    std::snprintf(node, sizeof node, "/dev/bus/usb/001/%03d", devnum);
    devnode = node;
    GError* err = nullptr;
    if (!umockdev_testbed_attach_ioctl(testbed, devnode.c_str(), handler, &err)) {
      if (err != nullptr) g_error_free(err);
      return false;
    }
    attached.push_back(devnode);
    char vid[8], pid[8];
    std::snprintf(vid, sizeof vid, "%04x", static_cast<unsigned>(opt.id.vid));
    std::snprintf(pid, sizeof pid, "%04x", static_cast<unsigned>(opt.id.pid));
    const std::string n = std::to_string(devnum);
    char product[24];
    std::snprintf(product, sizeof product, "%x/%x/100", static_cast<unsigned>(opt.id.vid),
                  static_cast<unsigned>(opt.id.pid));
    const std::string rec =
        "P: /devices/usb1\n"
        "N: " + devnode.substr(5) + "\n"
        "E: SUBSYSTEM=usb\n"
        "E: DEVTYPE=usb_device\n"
        "E: DRIVER=usb\n"
        "E: BUSNUM=001\n"
        "E: DEVNUM=" + std::string(node + 17) + "\n"
        "E: DEVNAME=" + devnode + "\n"
        "E: PRODUCT=" + product + "\n"
        "A: busnum=1\\n\n"
        "A: devnum=" + n + "\\n\n"
        "A: idVendor=" + vid + "\\n\n"
        "A: idProduct=" + pid + "\\n\n"
        "A: bConfigurationValue=1\\n\n"
        "A: bNumInterfaces= 1\\n\n"
        "A: speed=480\\n\n"
        "H: descriptors=" + hex(descriptors(opt.id, opt.endpoint)) + "\n";
    if (!umockdev_testbed_add_from_string(testbed, rec.c_str(), &err)) {
      if (err != nullptr) g_error_free(err);
      return false;
    }
    syspath = "/sys/devices/usb1";
    if (send_uevents) umockdev_testbed_uevent(testbed, syspath.c_str(), "add");
    return true;
  }

  // Completes one ioctl of `client`; returns TRUE (handled) always for the ioctls below.
  static gboolean onIoctl(UMockdevIoctlBase*, UMockdevIoctlClient* client, gpointer user) {
    return static_cast<Impl*>(user)->handle(client) ? TRUE : FALSE;
  }

  // Drops the URBs of clients that closed the device (libusb_close, or a process that died).
  void forgetClosedClients() {
    for (auto it = urbs.begin(); it != urbs.end();) {
      if (!umockdev_ioctl_client_get_connected(it->client)) {
        if (claimed_by == it->client) claimed_by = nullptr;
        release(*it);
        it = urbs.erase(it);
      } else {
        ++it;
      }
    }
  }

  static void setStatus(Urb& u, int status, int actual) {
    auto* urb = reinterpret_cast<usbdevfs_urb*>(u.urb->data);
    urb->status = status;
    urb->actual_length = actual;
  }

  // Hands a completed URB back through the REAPURB argument (a pointer to the client's pointer).
  bool reap(UMockdevIoctlClient* client, UMockdevIoctlData* arg, std::deque<Urb>::iterator it) {
    const DataRef ptr = resolveOrFault(client, arg, 0, sizeof(void*));
    if (ptr == nullptr) return true;
    umockdev_ioctl_data_set_ptr(ptr.get(), 0, it->urb);
    release(*it);  // the argument now holds the URB data until the reply is flushed
    urbs.erase(it);
    umockdev_ioctl_client_complete(client, 0, 0);
    return true;
  }

  bool handle(UMockdevIoctlClient* client) {
    const gulong request = umockdev_ioctl_client_get_request(client);
    UMockdevIoctlData* arg = umockdev_ioctl_client_get_arg(client);
    std::lock_guard<std::mutex> lock(mu);
    forgetClosedClients();
    // A client of an earlier plug-in, or any client while unplugged, talks to a gone device.
    const bool present =
        is_plugged && devnode == umockdev_ioctl_client_get_devnode(client);

    switch (request) {
      case USBDEVFS_REAPURB:
      case USBDEVFS_REAPURBNDELAY: {
        // 1. a URB that is already complete (discarded, or killed by an unplug)
        for (auto it = urbs.begin(); it != urbs.end(); ++it)
          if (it->client == client && it->done) return reap(client, arg, it);
        // 2. the oldest URB in flight: fail it if the device is gone, fill it if bytes wait
        for (auto it = urbs.begin(); it != urbs.end(); ++it) {
          if (it->client != client) continue;
          if (!present) {
            setStatus(*it, -ESHUTDOWN, 0);
            return reap(client, arg, it);
          }
          if (queue.empty()) break;
          const std::size_t room = static_cast<std::size_t>(it->buffer->data_len);
          const std::size_t n = std::min(room, queue.size());
          std::copy_n(queue.begin(), n, it->buffer->data);
          queue.erase(queue.begin(), queue.begin() + static_cast<std::ptrdiff_t>(n));
          setStatus(*it, 0, static_cast<int>(n));
          ++urbs_completed;
          bytes_delivered += n;
          return reap(client, arg, it);
        }
        umockdev_ioctl_client_complete(client, -1, present ? EAGAIN : ENODEV);
        return true;
      }

      case USBDEVFS_SUBMITURB: {
        if (!present) {
          umockdev_ioctl_client_complete(client, -1, ENODEV);
          return true;
        }
        DataRef urb_data = resolveOrFault(client, arg, 0, sizeof(usbdevfs_urb));
        if (urb_data == nullptr) return true;
        auto* urb = reinterpret_cast<usbdevfs_urb*>(urb_data->data);
        if (urb->type != USBDEVFS_URB_TYPE_BULK || urb->endpoint != opt.endpoint ||
            urb->buffer_length <= 0) {
          // Only the bulk IN endpoint exists (control requests: stall, like a minimal device).
          umockdev_ioctl_client_complete(client, -1,
                                         urb->type == USBDEVFS_URB_TYPE_CONTROL ? EPIPE : ENOENT);
          return true;
        }
        // The buffer lives as long as the URB data, which holds it as its child.
        const DataRef buf = resolveOrFault(client, urb_data.get(), offsetof(usbdevfs_urb, buffer),
                                           static_cast<gsize>(urb->buffer_length));
        if (buf == nullptr) return true;
        Urb u;
        u.client = static_cast<UMockdevIoctlClient*>(g_object_ref(client));
        u.urb = urb_data.release();  // the reference resolve gave, dropped by release()
        u.buffer = buf.get();
        urbs.push_back(u);
        umockdev_ioctl_client_complete(client, 0, 0);
        return true;
      }

      case USBDEVFS_DISCARDURB: {
        // The argument is the client's URB address itself.
        const gulong addr = *reinterpret_cast<const gulong*>(arg->data);
        for (auto& u : urbs) {
          if (u.client == client && !u.done && u.urb->client_addr == addr) {
            setStatus(u, -ENOENT, 0);
            u.done = true;
            umockdev_ioctl_client_complete(client, 0, 0);
            return true;
          }
        }
        umockdev_ioctl_client_complete(client, -1, EINVAL);  // already completed
        return true;
      }

      case USBDEVFS_GET_CAPABILITIES: {
        if (!present) {
          umockdev_ioctl_client_complete(client, -1, ENODEV);
          return true;
        }
        const DataRef d = resolveOrFault(client, arg, 0, sizeof(guint32));
        if (d == nullptr) return true;
        const guint32 caps = USBDEVFS_CAP_BULK_CONTINUATION | USBDEVFS_CAP_NO_PACKET_SIZE_LIM |
                             USBDEVFS_CAP_REAP_AFTER_DISCONNECT;
        std::memcpy(d->data, &caps, sizeof caps);
        umockdev_ioctl_client_complete(client, 0, 0);
        return true;
      }

      case USBDEVFS_CLAIMINTERFACE:
      case USBDEVFS_RELEASEINTERFACE: {
        if (!present) {
          umockdev_ioctl_client_complete(client, -1, ENODEV);
          return true;
        }
        const DataRef d = resolveOrFault(client, arg, 0, sizeof(guint32));
        if (d == nullptr) return true;
        guint32 itf = 0;
        std::memcpy(&itf, d->data, sizeof itf);
        if (itf != 0) {
          umockdev_ioctl_client_complete(client, -1, request == USBDEVFS_CLAIMINTERFACE ? ENOENT
                                                                                    : EINVAL);
          return true;
        }
        if (request == USBDEVFS_CLAIMINTERFACE) {
          if (claimed_by != nullptr && claimed_by != client) {
            umockdev_ioctl_client_complete(client, -1, EBUSY);
            return true;
          }
          claimed_by = client;
        } else if (claimed_by == client) {
          claimed_by = nullptr;
        }
        umockdev_ioctl_client_complete(client, 0, 0);
        return true;
      }

      case USBDEVFS_GETDRIVER:  // no kernel driver bound to a vendor-specific interface
        umockdev_ioctl_client_complete(client, -1, present ? ENODATA : ENODEV);
        return true;

      case USBDEVFS_CLEAR_HALT:
      case USBDEVFS_RESETEP:
      case USBDEVFS_SETINTERFACE:
      case USBDEVFS_SETCONFIGURATION:
      case USBDEVFS_RESET:
        umockdev_ioctl_client_complete(client, present ? 0 : -1, present ? 0 : ENODEV);
        return true;

      default:
        umockdev_ioctl_client_complete(client, -1, present ? ENOTTY : ENODEV);
        return true;
    }
  }
};

VirtualUsbBridge::VirtualUsbBridge(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
VirtualUsbBridge::~VirtualUsbBridge() = default;

Result<std::unique_ptr<VirtualUsbBridge>> VirtualUsbBridge::create(const Options& options) {
  if ((options.endpoint & 0x80) == 0)
    return Error{"virtual USB bridge: endpoint must be an IN address (bit 7 set), e.g. 0x81"};
  auto impl = std::make_unique<Impl>();
  impl->opt = options;
  impl->send_uevents = preloaded();
  impl->testbed = umockdev_testbed_new();
  if (impl->testbed == nullptr) return Error{"virtual USB bridge: cannot create a umockdev testbed"};
  // Only the USB device nodes are emulated (docs/CREATE.md, "Your own Create client against the
  // virtual robot"). umockdev 0.17's testbed always serves a catch-all ioctl handler on
  // ROOT/ioctl/_default, and its preload connects every file a process opens under /dev/ that
  // has no handler of its own to it: a pty /dev/pts/N, /dev/ttyUSB0, /dev/null. From then on each
  // ioctl() call on that file goes to the catch-all, which has no recording and answers ENOTTY,
  // so ioctl(FIONBIO) (boost::asio's non-blocking mode) and ioctl(FIONREAD) (pyserial's
  // in_waiting) fail on the child's Create port, while tcgetattr/tcsetattr work (glibc issues
  // their ioctls as system calls, past the preload's ioctl() wrapper). Without the socket the
  // preload's connect fails and, for a path outside the testbed, it leaves the file alone: it is
  // the kernel's tty again. (For a node inside the testbed without a handler of its own the
  // preload would exit instead; plug() attaches the handler before it adds the node.)
  {
    const std::string catch_all = rootDirOf(impl->testbed) + "/ioctl/_default";
    if (::unlink(catch_all.c_str()) != 0 && errno != ENOENT)
      return Error{"virtual USB bridge: cannot remove umockdev's catch-all ioctl socket " +
                   catch_all + ": " + std::strerror(errno)};
  }
  impl->handler = umockdev_ioctl_base_new();
  impl->signal_id = g_signal_connect(impl->handler, "handle-ioctl",
                                     G_CALLBACK(&Impl::onIoctl), impl.get());
  if (!impl->plug())
    return Error{"virtual USB bridge: umockdev cannot add the device " +
                 io::formatUsbId(options.id) + " to its testbed"};
  impl->is_plugged = true;
  return std::unique_ptr<VirtualUsbBridge>(new VirtualUsbBridge(std::move(impl)));
}

void VirtualUsbBridge::push(std::span<const std::uint8_t> bytes) {
  std::lock_guard<std::mutex> lock(impl_->mu);
  impl_->queue.insert(impl_->queue.end(), bytes.begin(), bytes.end());
}

void VirtualUsbBridge::unplug() {
  std::lock_guard<std::mutex> lock(impl_->mu);
  if (!impl_->is_plugged) return;
  impl_->is_plugged = false;  // the handler fails every URB and ioctl of the old node from now
  if (impl_->send_uevents) umockdev_testbed_uevent(impl_->testbed, impl_->syspath.c_str(), "remove");
  umockdev_testbed_remove_device(impl_->testbed, impl_->syspath.c_str());
  impl_->claimed_by = nullptr;
}

void VirtualUsbBridge::replug() {
  std::lock_guard<std::mutex> lock(impl_->mu);
  if (impl_->is_plugged) return;
  ++impl_->devnum;  // the kernel gives a re-enumerated device the next address
  impl_->is_plugged = impl_->plug();
}

bool VirtualUsbBridge::plugged() const {
  std::lock_guard<std::mutex> lock(impl_->mu);
  return impl_->is_plugged;
}

std::string VirtualUsbBridge::devicePath() const {
  std::lock_guard<std::mutex> lock(impl_->mu);
  return impl_->devnode;
}

std::string VirtualUsbBridge::rootDir() const { return rootDirOf(impl_->testbed); }

std::uint64_t VirtualUsbBridge::urbsCompleted() const {
  std::lock_guard<std::mutex> lock(impl_->mu);
  return impl_->urbs_completed;
}
std::uint64_t VirtualUsbBridge::bytesDelivered() const {
  std::lock_guard<std::mutex> lock(impl_->mu);
  return impl_->bytes_delivered;
}
std::size_t VirtualUsbBridge::urbsInFlight() const {
  std::lock_guard<std::mutex> lock(impl_->mu);
  return static_cast<std::size_t>(
      std::count_if(impl_->urbs.begin(), impl_->urbs.end(), [](const Impl::Urb& u) {
        return !u.done && umockdev_ioctl_client_get_connected(u.client);
      }));
}
std::size_t VirtualUsbBridge::queuedBytes() const {
  std::lock_guard<std::mutex> lock(impl_->mu);
  return impl_->queue.size();
}

bool VirtualUsbBridge::preloaded() {
  std::ifstream maps("/proc/self/maps");
  std::string line;
  while (std::getline(maps, line))
    if (line.find("libumockdev-preload") != std::string::npos) return true;
  return false;
}

void VirtualUsbBridge::ensurePreloaded(int argc, char** argv) {
  if (preloaded()) return;
  if (std::getenv(kReexecMark) != nullptr) {
    std::fprintf(stderr,
                 "virtual USB bridge: %s was put in LD_PRELOAD but is not loaded: is umockdev "
                 "installed (apt install umockdev libumockdev0)?\n",
                 kPreloadLib);
    return;
  }
  if (argc < 1 || argv == nullptr) return;
  std::string preload = kPreloadLib;
  if (const char* old = std::getenv("LD_PRELOAD"); old != nullptr && *old != '\0')
    preload += std::string(":") + old;
  std::string asan = "verify_asan_link_order=0";
  if (const char* old = std::getenv("ASAN_OPTIONS"); old != nullptr && *old != '\0')
    asan = std::string(old) + ":" + asan;
  setenv("LD_PRELOAD", preload.c_str(), 1);
  setenv("ASAN_OPTIONS", asan.c_str(), 1);
  setenv(kReexecMark, "1", 1);
  execv("/proc/self/exe", argv);
  std::fprintf(stderr, "virtual USB bridge: cannot re-execute %s with %s: %s\n", argv[0],
               kPreloadLib, std::strerror(errno));
}

}  // namespace crunch::sim
