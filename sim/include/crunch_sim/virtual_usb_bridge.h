// A whisker bridge in software for the hardware-in-loop tests (ARCHITECTURE.md §5, docs/USB.md
// "Virtual bridge"): an umockdev testbed in which unmodified libusb code — io::UsbBridge in this
// process, or `crunchhost --robot` in a child process — finds, opens, claims and reads a
// vendor-specific USB device through the real usbdevfs ioctls.
//
// create() builds a UMockdevTestbed (it sets UMOCKDEV_DIR in this process's environment, so a
// child started afterwards with the umockdev preload sees the same fake /sys and /dev), adds a
// USB device with full descriptors (device class 0xff, one configuration, interface 0 of class
// 0xff with one bulk IN endpoint, 512-byte packets at 480 Mb/s) and attaches a live
// UMockdevIoctlBase handler to its node /dev/bus/usb/001/NNN. The handler serves
// GET_CAPABILITIES, CLAIM/RELEASEINTERFACE (EBUSY if another open file holds the claim),
// SUBMITURB, REAPURB(NDELAY) and DISCARDURB with any number of URBs in flight: a bulk IN URB is
// completed, at the client's next reap, with as many queued bytes as fit (at least one, like a
// short packet), in submission order. push() queues those bytes.
//
// unplug(): the URBs in flight complete with -ESHUTDOWN (libusb: LIBUSB_TRANSFER_NO_DEVICE),
// every later ioctl fails with ENODEV, a "remove" uevent is sent and the device leaves the
// testbed's sysfs. replug(): the device comes back with the next device number (as the kernel
// does) and an "add" uevent. Bytes pushed while unplugged wait in the queue.
//
// Threads: the ioctl handler runs on umockdev's own testbed worker thread (a GLib main loop
// that umockdev 0.17 starts for attached handlers), not on the caller's. push(), unplug(),
// replug() and the counters are thread-safe.
// Only the USB device nodes are emulated: create() removes umockdev's catch-all ioctl handler,
// so any other file a preloaded process opens under /dev/ (a Create's pty, /dev/ttyUSB0) keeps
// the kernel's ioctls (the .cc says why; docs/CREATE.md, "Your own Create client against the
// virtual robot").
// Preload: libusb sees the testbed only in a process that runs with libumockdev-preload.so.0
// loaded (LD_PRELOAD, as umockdev-wrapper does). ensurePreloaded() re-executes a test binary
// with it; a child process needs LD_PRELOAD=libumockdev-preload.so.0 and the inherited
// UMOCKDEV_DIR (see docs/USB.md). The uevents of unplug()/replug() (libusb hotplug) are sent
// only when this process runs with the preload too; without them clients find a replugged
// device by polling.
// Ownership: the bridge owns the testbed; destroying it removes the temporary tree and unsets
// UMOCKDEV_DIR. Destroy it only after every client has closed the device.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "crunch/core/result.h"
#include "crunch/io/usb_bridge.h"

namespace crunch::sim {

class VirtualUsbBridge {
 public:
  struct Options {
    io::UsbId id{0x1209, 0x0001};  // the real bridge's default (io::UsbBridge::Options)
    std::uint8_t endpoint = 0x81;  // bulk IN endpoint address
  };

  // Errors: the endpoint is not an IN address, or umockdev cannot build the device.
  static Result<std::unique_ptr<VirtualUsbBridge>> create(const Options& options);
  ~VirtualUsbBridge();
  VirtualUsbBridge(const VirtualUsbBridge&) = delete;
  VirtualUsbBridge& operator=(const VirtualUsbBridge&) = delete;

  // Queues bytes for the bulk IN endpoint; they are delivered in order, split across URBs
  // however they fall. Thread-safe.
  void push(std::span<const std::uint8_t> bytes);
  // Unplugs the device (see the top of this file). No-op if unplugged. Thread-safe.
  void unplug();
  // Plugs it back in, with a new device number. No-op if plugged. Thread-safe.
  void replug();
  bool plugged() const;

  // The device node while plugged, e.g. "/dev/bus/usb/001/002" (inside the testbed).
  std::string devicePath() const;
  // The testbed root (the value of UMOCKDEV_DIR a child process must inherit).
  std::string rootDir() const;

  std::uint64_t urbsCompleted() const;   // bulk IN URBs completed with data
  std::uint64_t bytesDelivered() const;  // bytes in those URBs
  std::size_t urbsInFlight() const;      // submitted, not yet completed
  std::size_t queuedBytes() const;       // pushed, not yet delivered

  // True when libumockdev-preload is loaded in this process (checked in /proc/self/maps).
  static bool preloaded();
  // Call first thing in main(): if the preload is not loaded, re-executes this program
  // (/proc/self/exe with the same argv) with LD_PRELOAD=libumockdev-preload.so.0 prepended
  // (and ASAN_OPTIONS=verify_asan_link_order=0 added, so an ASan build accepts a preload that
  // comes before its runtime); returns only when the preload is already loaded, or after
  // printing why the re-exec failed (the caller's virtual tests then fail with that reason).
  // Runs once: CRUNCH_UMOCKDEV_REEXEC marks the re-executed process.
  static void ensurePreloaded(int argc, char** argv);

 private:
  struct Impl;
  explicit VirtualUsbBridge(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace crunch::sim
