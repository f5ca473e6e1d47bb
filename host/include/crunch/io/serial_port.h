// A serial port in raw mode through termios: the iRobot Create's link (OI v2: 57600 8N1, no
// flow control; paper §2.3). Also opens the slave side of a pseudo-terminal, which is how the
// tests reach the Create emulator (sim/create_emulator.h) through the same system calls.
//
// open() uses O_RDWR | O_NOCTTY | O_NONBLOCK, sets raw 8N1 (cfmakeraw, CLOCAL | CREAD, no
// CRTSCTS, no IXON/IXOFF), the given baud rate both ways, and flushes both queues. Every wait
// is bounded by the caller's timeout (poll(2)).
// Errors name the device and say what to do: a missing device, a permission problem, a path
// that is not a serial port, an unsupported baud rate, a hang-up (cable pulled).
// Ownership: owns the file descriptor; movable, not copyable; closed by the destructor.
// Thread-safety: none; read() and writeAll() may run on different threads (one each), as the
// fd is full-duplex, but each on one thread at a time.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

#include "crunch/core/result.h"

namespace crunch::io {

class SerialPort {
 public:
  static Result<SerialPort> open(const std::string& device, int baud = 57600);

  SerialPort(SerialPort&& other) noexcept;
  SerialPort& operator=(SerialPort&& other) noexcept;
  SerialPort(const SerialPort&) = delete;
  SerialPort& operator=(const SerialPort&) = delete;
  ~SerialPort();

  // Waits up to timeout_s (0: do not wait) for bytes, then reads what is there, at most
  // buffer.size(). Returns the count, 0 on timeout. Error on a hang-up or a failed read.
  Result<std::size_t> read(std::span<std::uint8_t> buffer, double timeout_s);
  // Writes every byte, waiting for room at most timeout_s in all. Error on timeout or failure.
  Status writeAll(std::span<const std::uint8_t> bytes, double timeout_s);

  const std::string& device() const { return device_; }
  int fd() const { return fd_; }
  bool isOpen() const { return fd_ >= 0; }
  void close();

 private:
  SerialPort(std::string device, int fd) : device_(std::move(device)), fd_(fd) {}
  std::string device_;
  int fd_ = -1;
};

}  // namespace crunch::io
