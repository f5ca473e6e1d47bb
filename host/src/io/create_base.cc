#include "crunch/io/create_base.h"

#include <array>
#include <cmath>
#include <cstdio>

namespace crunch::io {

namespace {

std::string seconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f", s);
  return buf;
}

std::uint8_t streamLength() {
  int n = 0;
  for (const std::uint8_t id : oi::kCreateBaseStream) n += 1 + oi::packetSize(id);
  return static_cast<std::uint8_t>(n);
}

double secondsSince(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

}  // namespace

CreateBase::CreateBase(SerialPort port, const Options& options)
    : options_(options),
      port_(std::move(port)),
      tracker_(oi::StreamParserOptions{options.checksum_includes_header, streamLength()}),
      opened_(Clock::now()),
      last_packet_(opened_) {
  touch();
}

Result<std::unique_ptr<CreateBase>> CreateBase::open(const std::string& device,
                                                     const Options& options) {
  if (!(options.answer_timeout_s > 0) || !(options.stream_timeout_s > 0) ||
      !(options.watchdog_s > 0) || !(options.wheel_base > 0) || !(options.write_timeout_s > 0)) {
    return Error{"Create on " + device +
                 ": invalid options (timeouts, watchdog and wheel base must be positive)"};
  }
  auto port = SerialPort::open(device, options.baud);
  if (!port) return port.error();
  std::unique_ptr<CreateBase> base(new CreateBase(std::move(port).value(), options));

  // Named arrays: spans over temporaries in a range-for initializer would dangle.
  const auto start = oi::start();
  const auto mode = options.full_mode ? oi::full() : oi::safe();
  const auto ids = oi::stream(oi::kCreateBaseStream);
  for (const std::span<const std::uint8_t> cmd : {std::span<const std::uint8_t>(start),
                                                  std::span<const std::uint8_t>(mode),
                                                  ids.span()}) {
    if (Status s = base->send(cmd); !s) {
      return Error{"Create on " + device + ": could not send the start-up commands: " +
                   s.error().message};
    }
  }

  const auto deadline =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(
                         std::chrono::duration<double>(options.answer_timeout_s));
  while (base->tracker_.packets() == 0) {
    const double left = std::chrono::duration<double>(deadline - Clock::now()).count();
    if (left <= 0) {
      std::string msg = "Create on " + device + " did not answer within " +
                        seconds(options.answer_timeout_s) +
                        " s (no sensor stream): is it switched on, the cable plugged in, the "
                        "baud rate " + std::to_string(options.baud) + "?";
      if (base->counters_.bytes_read > 0) {
        msg += " (" + std::to_string(base->counters_.bytes_read) +
               " bytes received, none a valid stream packet: wrong baud rate, or try the other "
               "checksum_includes_header setting)";
      }
      return Error{msg};
    }
    bool got = false;
    if (Status s = base->readAvailable(left, &got); !s) {
      return Error{"Create on " + device + ": " + s.error().message};
    }
  }
  base->last_packet_ = Clock::now();
  base->touch();
  base->watchdog_ = std::thread([b = base.get()] { b->watchdogLoop(); });
  return base;
}

CreateBase::~CreateBase() {
  (void)stopAndDisarm();  // the motors' stop, once
  if (port_.isOpen()) {
    const auto pause = oi::pauseResume(false);
    (void)send(pause);
  }
}

double CreateBase::now() const { return secondsSince(opened_); }

Status CreateBase::send(std::span<const std::uint8_t> bytes) {
  std::lock_guard lock(write_mutex_);
  return port_.writeAll(bytes, options_.write_timeout_s);
}

Status CreateBase::sendWheels(int right_mm_s, int left_mm_s) {
  const auto cmd = oi::driveDirect(right_mm_s, left_mm_s);
  return send(cmd);
}

Status CreateBase::drive(double v, double omega) {
  touch();
  if (!std::isfinite(v) || !std::isfinite(omega)) {
    v = 0.0;
    omega = 0.0;
  }
  if (tracker_.wheelDropped()) {
    v = 0.0;
    omega = 0.0;
  } else if (tracker_.bumped() && v > 0.0) {
    v = 0.0;
    ++counters_.refused_forward;
  }
  const oi::WheelSpeeds w = oi::twistToWheels(v, omega, options_.wheel_base);
  if (w.clamped) ++counters_.clamped;
  if ((w.right_mm_s != 0 || w.left_mm_s != 0) && tracker_.modeKnown() &&
      tracker_.mode() == oi::Mode::kPassive) {
    return Error{"Create on " + device() +
                 " is in Passive mode and ignores drive commands (it leaves Safe mode after a "
                 "cliff, a wheel drop or the charger): put it on the floor, then call resume()"};
  }
  ++counters_.commands_sent;
  Status s = sendWheels(w.right_mm_s, w.left_mm_s);
  if (!s) return Error{"Create on " + device() + " did not take the drive command: " +
                       s.error().message};
  return okStatus();
}

Status CreateBase::resume() {
  touch();
  const auto cmd = options_.full_mode ? oi::full() : oi::safe();
  Status s = send(cmd);
  if (!s) return Error{"Create on " + device() + ": " + s.error().message};
  return okStatus();
}

Status CreateBase::readAvailable(double timeout_s, bool* got_packet) {
  std::array<std::uint8_t, 512> buf{};
  double wait = timeout_s;
  for (int round = 0; round < 64; ++round) {
    auto r = port_.read(buf, wait);
    if (!r) return r.error();
    const std::size_t n = r.value();
    if (n == 0) break;
    const std::span<const std::uint8_t> chunk(buf.data(), n);
    counters_.bytes_read += n;
    if (tap_) tap_(chunk);
    const std::uint64_t before = tracker_.packets();
    tracker_.feed(chunk);
    if (tracker_.packets() != before) {
      last_packet_ = Clock::now();
      *got_packet = true;
    }
    wait = 0.0;  // drain what is there, do not wait again
  }
  return okStatus();
}

Status CreateBase::poll(double timeout_s) {
  touch();
  bool got = false;
  Status read = readAvailable(timeout_s, &got);
  touch();
  if (!read) return Error{"Create on " + device() + ": " + read.error().message};
  if (tracker_.bumped()) {
    if (!stopped_for_bump_) {
      stopped_for_bump_ = true;
      ++counters_.safety_stops;
      ++counters_.commands_sent;
      if (Status s = sendWheels(0, 0); !s) {
        return Error{"Create on " + device() + ": could not stop after a bump: " +
                     s.error().message};
      }
    }
  } else {
    stopped_for_bump_ = false;
  }
  const double silent = secondsSince(last_packet_);
  if (silent > options_.stream_timeout_s) {
    const auto c = tracker_.counters().stream;
    return Error{"Create on " + device() + ": no valid sensor packet for " + seconds(silent) +
                 " s (" + std::to_string(c.checksum_failures) + " checksum failures, " +
                 std::to_string(c.bad_length_or_id) +
                 " malformed): is it still switched on and connected?"};
  }
  return okStatus();
}

Status CreateBase::stopAndDisarm() {
  if (watchdog_.joinable()) {
    {
      std::lock_guard lock(watchdog_mutex_);
      quit_ = true;
    }
    watchdog_cv_.notify_all();
    watchdog_.join();
  }
  return port_.isOpen() ? sendWheels(0, 0) : okStatus();
}

void CreateBase::watchdogLoop() {
  const auto limit = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(options_.watchdog_s));
  const auto period = std::max<Clock::duration>(limit / 5, std::chrono::milliseconds(2));
  Clock::rep handled = -1;  // the activity stamp whose stall was already stopped
  std::unique_lock lock(watchdog_mutex_);
  while (!quit_) {
    watchdog_cv_.wait_for(lock, period, [this] { return quit_; });
    if (quit_) break;
    const Clock::rep stamp = last_activity_ns_.load();
    const Clock::time_point last{Clock::duration(stamp)};
    if (Clock::now() - last > limit && stamp != handled) {
      handled = stamp;
      const auto cmd = oi::driveDirect(0, 0);
      (void)send(cmd);
      watchdog_stops_.fetch_add(1);
    }
  }
}

}  // namespace crunch::io
