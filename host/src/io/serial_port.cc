#include "crunch/io/serial_port.h"

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <utility>

namespace crunch::io {

namespace {

bool baudConstant(int baud, speed_t* out) {
  switch (baud) {
    case 9600: *out = B9600; return true;
    case 19200: *out = B19200; return true;
    case 38400: *out = B38400; return true;
    case 57600: *out = B57600; return true;
    case 115200: *out = B115200; return true;
    default: return false;
  }
}

std::string openError(const std::string& device, int err) {
  switch (err) {
    case ENOENT:
      return "cannot open " + device +
             ": no such device: is the Create's serial cable plugged in? (see `ls /dev/ttyUSB*`)";
    case EACCES:
    case EPERM:
      return "cannot open " + device +
             ": permission denied: add yourself to the dialout group (sudo usermod -aG dialout "
             "$USER, then log in again)";
    case EBUSY:
      return "cannot open " + device + ": device busy: another program has it open (see `fuser " +
             device + "`)";
    case ENXIO:
    case ENODEV:
      return "cannot open " + device +
             ": the device node exists but no device answers it: replug the USB-serial cable";
    default:
      return "cannot open " + device + ": " + std::strerror(err);
  }
}

using Clock = std::chrono::steady_clock;

int remainingMs(Clock::time_point deadline) {
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
  if (left.count() <= 0) return 0;
  return static_cast<int>(std::min<long long>(left.count() + 1, 1 << 30));
}

Clock::time_point deadlineIn(double timeout_s) {
  if (!std::isfinite(timeout_s) || timeout_s < 0) timeout_s = 0;
  timeout_s = std::min(timeout_s, 1e6);
  return Clock::now() + std::chrono::duration_cast<Clock::duration>(
                            std::chrono::duration<double>(timeout_s));
}

}  // namespace

Result<SerialPort> SerialPort::open(const std::string& device, int baud) {
  speed_t speed{};
  if (!baudConstant(baud, &speed)) {
    return Error{"cannot open " + device + ": unsupported baud rate " + std::to_string(baud) +
                 " (use 57600 for the Create, or 9600/19200/38400/115200)"};
  }
  const int fd = ::open(device.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return Error{openError(device, errno)};
  SerialPort port(device, fd);
  termios tio{};
  if (::tcgetattr(fd, &tio) != 0) {
    const int err = errno;
    if (err == ENOTTY || err == EINVAL) {
      return Error{"cannot use " + device +
                   ": not a tty (not a serial port): pass the Create's serial device, e.g. "
                   "/dev/ttyUSB0"};
    }
    return Error{"cannot configure " + device + ": tcgetattr: " + std::strerror(err)};
  }
  ::cfmakeraw(&tio);
  tio.c_cflag &= ~static_cast<tcflag_t>(CSTOPB | PARENB | CSIZE | CRTSCTS);
  tio.c_cflag |= CS8 | CLOCAL | CREAD;
  tio.c_iflag &= ~static_cast<tcflag_t>(IXON | IXOFF | IXANY);
  tio.c_cc[VMIN] = 0;
  tio.c_cc[VTIME] = 0;
  if (::cfsetispeed(&tio, speed) != 0 || ::cfsetospeed(&tio, speed) != 0 ||
      ::tcsetattr(fd, TCSANOW, &tio) != 0) {
    return Error{"cannot configure " + device + " as raw 8N1 at " + std::to_string(baud) +
                 " baud: " + std::strerror(errno)};
  }
  ::tcflush(fd, TCIOFLUSH);
  return port;
}

SerialPort::SerialPort(SerialPort&& other) noexcept
    : device_(std::move(other.device_)), fd_(std::exchange(other.fd_, -1)) {}

SerialPort& SerialPort::operator=(SerialPort&& other) noexcept {
  if (this != &other) {
    close();
    device_ = std::move(other.device_);
    fd_ = std::exchange(other.fd_, -1);
  }
  return *this;
}

SerialPort::~SerialPort() { close(); }

void SerialPort::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

Result<std::size_t> SerialPort::read(std::span<std::uint8_t> buffer, double timeout_s) {
  if (fd_ < 0) return Error{"serial port " + device_ + " is closed"};
  if (buffer.empty()) return std::size_t{0};
  const auto deadline = deadlineIn(timeout_s);
  for (;;) {
    pollfd p{fd_, POLLIN, 0};
    const int rc = ::poll(&p, 1, remainingMs(deadline));
    if (rc < 0) {
      if (errno == EINTR) continue;
      return Error{"waiting for " + device_ + ": poll: " + std::strerror(errno)};
    }
    if (rc == 0) return std::size_t{0};
    if ((p.revents & POLLIN) != 0) {
      const ssize_t n = ::read(fd_, buffer.data(), buffer.size());
      if (n > 0) return static_cast<std::size_t>(n);
      if (n < 0 && (errno == EAGAIN || errno == EINTR)) {
        if (Clock::now() >= deadline) return std::size_t{0};
        continue;
      }
      if (n < 0 && errno != EIO) {
        return Error{"reading " + device_ + ": " + std::strerror(errno)};
      }
      // n == 0 or EIO: the other end went away.
    }
    if ((p.revents & (POLLHUP | POLLERR | POLLNVAL | POLLIN)) != 0) {
      return Error{device_ + " hung up: was the serial cable unplugged or the Create switched off?"};
    }
  }
}

Status SerialPort::writeAll(std::span<const std::uint8_t> bytes, double timeout_s) {
  if (fd_ < 0) return Error{"serial port " + device_ + " is closed"};
  const auto deadline = deadlineIn(timeout_s);
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
    if (n > 0) {
      done += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno != EAGAIN && errno != EINTR) {
      return Error{"writing to " + device_ + ": " + std::strerror(errno) +
                   (errno == EIO ? " (was the serial cable unplugged?)" : "")};
    }
    if (n < 0 && errno == EINTR) continue;
    const int ms = remainingMs(deadline);
    if (ms == 0) {
      return Error{"writing to " + device_ + ": timed out with " +
                   std::to_string(bytes.size() - done) + " bytes unsent (output blocked)"};
    }
    pollfd p{fd_, POLLOUT, 0};
    if (::poll(&p, 1, ms) < 0 && errno != EINTR) {
      return Error{"waiting to write to " + device_ + ": " + std::strerror(errno)};
    }
    if ((p.revents & (POLLERR | POLLHUP | POLLNVAL)) != 0) {
      return Error{device_ + " hung up: was the serial cable unplugged or the Create switched off?"};
    }
  }
  return okStatus();
}

}  // namespace crunch::io
