#include "crunch_sim/create_emulator.h"

#include <fcntl.h>
#include <pty.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>

namespace crunch::sim {

namespace oi = io::oi;

namespace {

// Data bytes after the opcode for OI v2 opcodes 128..157; -1: variable (140, 148, 149, 151);
// -2: not an opcode of the Create.
constexpr std::array<int, 30> kDataBytes = {
    0,  1, 0, 0, 0,   // 128 Start, 129 Baud, 130 Control, 131 Safe, 132 Full
    -2, 0, 0, 1,      // 133 (none), 134 Spot, 135 Cover, 136 Demo
    4,  1, 3, -1, 1,  // 137 Drive, 138 Low Side Drivers, 139 LEDs, 140 Song, 141 Play
    1,  0, 3, 4, 1,   // 142 Sensors, 143 Cover and Dock, 144 PWM LSD, 145 Drive Direct, 146 DO
    1,  -1, -1, 1, -1,  // 147 Send IR, 148 Stream, 149 Query List, 150 Pause/Resume, 151 Script
    0,  0, 1, 2, 2, 1,  // 152 Play Script, 153 Show Script, 154..157 Wait Time/Distance/Angle/Event
};

int int16At(const std::uint8_t* p) {
  return static_cast<std::int16_t>(static_cast<std::uint16_t>((p[0] << 8) | p[1]));
}

// Packet ids 0..6 are groups of the single packets (OI spec, "Sensors").
std::pair<int, int> groupRange(std::uint8_t id) {
  switch (id) {
    case 0: return {7, 26};
    case 1: return {7, 16};
    case 2: return {17, 20};
    case 3: return {21, 26};
    case 4: return {27, 34};
    case 5: return {35, 42};
    case 6: return {7, 42};
    default: return {id, id};
  }
}

bool knownId(std::uint8_t id) { return id <= oi::kLastPacketId; }

// Data bytes of packet `id`, a group's being the sum of its members'.
std::size_t dataBytes(std::uint8_t id) {
  const auto [first, last] = groupRange(id);
  std::size_t n = 0;
  for (int m = first; m <= last; ++m) {
    n += static_cast<std::size_t>(oi::packetSize(static_cast<std::uint8_t>(m)));
  }
  return n;
}

// Appends the data of packet `id` (a group: its members in order) from `f` at out[k]; returns the
// new end. The OI sends 16-bit values high byte first.
std::size_t writeData(std::uint8_t id, const oi::SensorFrame& f, std::span<std::uint8_t> out,
                      std::size_t k) {
  const auto [first, last] = groupRange(id);
  for (int m = first; m <= last; ++m) {
    const auto member = static_cast<std::uint8_t>(m);
    const std::int32_t v = f.get(member);
    if (oi::packetSize(member) == 2) out[k++] = static_cast<std::uint8_t>((v >> 8) & 0xFF);
    out[k++] = static_cast<std::uint8_t>(v & 0xFF);
  }
  return k;
}

// The single packets behind `requested` (groups expanded, in order) into `ids`; returns how many.
std::size_t expandIds(std::span<const std::uint8_t> requested, std::span<std::uint8_t> ids) {
  std::size_t n = 0;
  for (const std::uint8_t r : requested) {
    const auto [first, last] = groupRange(r);
    for (int id = first; id <= last && n < ids.size(); ++id) {
      ids[n++] = static_cast<std::uint8_t>(id);
    }
  }
  return n;
}

// The manual's limits on a Stream: at most 43 ids; n, one byte, counts the frame's data bytes.
constexpr std::size_t kMaxStreamIds = 43;
constexpr std::size_t kMaxStreamBytes = 255;

}  // namespace

Result<std::unique_ptr<CreateEmulator>> CreateEmulator::open(MobileBase& body,
                                                             const Options& options) {
  if (!(options.stream_period > 0) || !(options.wheel_base > 0) || options.max_catch_up < 1) {
    return Error{"Create emulator: stream_period and wheel_base must be positive, "
                 "max_catch_up at least 1"};
  }
  int master = -1, slave = -1;
  if (::openpty(&master, &slave, nullptr, nullptr, nullptr) != 0) {
    return Error{std::string("Create emulator: openpty failed: ") + std::strerror(errno) +
                 " (is /dev/pts mounted?)"};
  }
  termios tio{};
  ::tcgetattr(slave, &tio);
  ::cfmakeraw(&tio);
  ::cfsetispeed(&tio, B57600);
  ::cfsetospeed(&tio, B57600);
  ::tcsetattr(slave, TCSANOW, &tio);
  ::fcntl(master, F_SETFL, ::fcntl(master, F_GETFL) | O_NONBLOCK);
  ::fcntl(master, F_SETFD, FD_CLOEXEC);
  ::fcntl(slave, F_SETFD, FD_CLOEXEC);
  char name[128] = {};
  if (::ttyname_r(slave, name, sizeof name) != 0) {
    ::close(master);
    ::close(slave);
    return Error{"Create emulator: cannot name the pty's slave side"};
  }
  return std::unique_ptr<CreateEmulator>(
      new CreateEmulator(body, options, master, slave, name));
}

CreateEmulator::CreateEmulator(MobileBase& body, const Options& options, int master, int slave,
                               std::string path)
    : body_(body), options_(options), master_(master), slave_(slave),
      slave_path_(std::move(path)), last_pose_(body.odometry()) {
  garbage_.reserve(1024);
}

CreateEmulator::~CreateEmulator() {
  if (master_ >= 0) ::close(master_);
  if (slave_ >= 0) ::close(slave_);
}

void CreateEmulator::injectGarbage(std::span<const std::uint8_t> bytes) {
  garbage_.insert(garbage_.end(), bytes.begin(), bytes.end());
}

void CreateEmulator::pump() {
  std::array<std::uint8_t, 256> in{};
  for (;;) {
    const ssize_t n = ::read(master_, in.data(), in.size());
    if (n <= 0) break;  // EAGAIN: nothing more; EIO cannot happen while slave_ is open
    counters_.bytes_received += static_cast<std::uint64_t>(n);
    if (silent_) continue;
    for (ssize_t i = 0; i < n; ++i) onByte(in[static_cast<std::size_t>(i)]);
  }
  accumulateMotion();
  if (silent_) {
    next_due_ = std::max(next_due_, body_.now());
    return;
  }

  if (options_.safe_stops_on_wheel_drop && mode_ == oi::Mode::kSafeMode && drops_ != 0) {
    ++counters_.safety_stops;
    enterPassive();
  }

  if (!garbage_.empty()) {
    write(garbage_);
    counters_.garbage_bytes_sent += garbage_.size();
    garbage_.clear();
  }

  if (!streaming()) return;
  const double now = body_.now();
  int sent = 0;
  while (now >= next_due_) {
    if (sent == options_.max_catch_up) {
      const auto missed =
          static_cast<std::uint64_t>(std::floor((now - next_due_) / options_.stream_period)) + 1;
      counters_.packets_skipped += missed;
      next_due_ += static_cast<double>(missed) * options_.stream_period;
      break;
    }
    sendPacket();
    next_due_ += options_.stream_period;
    ++sent;
  }
}

void CreateEmulator::onByte(std::uint8_t b) {
  if (cmd_size_ == 0) {
    if (b < 128 || b > 157 || kDataBytes[b - 128] == -2) {
      ++counters_.unknown_bytes;
      return;
    }
    cmd_need_ = kDataBytes[b - 128] >= 0 ? 1 + static_cast<std::size_t>(kDataBytes[b - 128]) : 0;
  }
  cmd_[cmd_size_++] = b;
  if (cmd_need_ == 0) {  // variable length: known once its count byte is in
    const std::uint8_t op = cmd_[0];
    if ((op == oi::kStream || op == oi::kQueryList || op == 151) && cmd_size_ == 2) {
      cmd_need_ = 2 + static_cast<std::size_t>(cmd_[1]);
    } else if (op == 140 && cmd_size_ == 3) {  // Song: number, N, N (note, duration) pairs
      cmd_need_ = 3 + 2 * static_cast<std::size_t>(cmd_[2]);
    }
  }
  if (cmd_need_ != 0 && cmd_size_ >= cmd_need_) {
    execute();
    cmd_size_ = 0;
    cmd_need_ = 0;
  }
}

void CreateEmulator::execute() {
  ++counters_.commands;
  const std::uint8_t op = cmd_[0];
  if (mode_ == oi::Mode::kOff && op != oi::kStart) {
    ++counters_.ignored_commands;
    return;
  }
  const bool active = mode_ == oi::Mode::kSafeMode || mode_ == oi::Mode::kFullMode;
  switch (op) {
    case oi::kStart:
      enterPassive();
      break;
    case oi::kControl:
    case oi::kSafe:
      mode_ = oi::Mode::kSafeMode;
      break;
    case oi::kFull:
      mode_ = oi::Mode::kFullMode;
      break;
    case oi::kDrive: {
      if (!active) {
        ++counters_.ignored_commands;
        break;
      }
      const int vel = std::clamp(int16At(&cmd_[1]), -oi::kMaxWheelSpeedMm, oi::kMaxWheelSpeedMm);
      const int rad = int16At(&cmd_[3]);
      req_velocity_ = vel;
      req_radius_ = rad;
      const double v = vel / 1000.0;
      const double half = 0.5 * options_.wheel_base;
      if (rad == oi::kRadiusStraight || rad == oi::kRadiusStraightAlt) {
        req_right_ = req_left_ = vel;
        applyDrive(v, 0.0);
      } else if (rad == oi::kRadiusTurnCcw || rad == oi::kRadiusTurnCw) {
        req_right_ = rad * vel;
        req_left_ = -rad * vel;
        applyDrive(0.0, rad * v / half);
      } else {
        const double r = std::clamp(rad, -oi::kMaxRadiusMm, oi::kMaxRadiusMm) / 1000.0;
        req_right_ = static_cast<int>(std::lround(vel * (r + half) / r));
        req_left_ = static_cast<int>(std::lround(vel * (r - half) / r));
        applyDrive(v, v / r);
      }
      break;
    }
    case oi::kDriveDirect: {
      if (!active) {
        ++counters_.ignored_commands;
        break;
      }
      const int right =
          std::clamp(int16At(&cmd_[1]), -oi::kMaxWheelSpeedMm, oi::kMaxWheelSpeedMm);
      const int left = std::clamp(int16At(&cmd_[3]), -oi::kMaxWheelSpeedMm, oi::kMaxWheelSpeedMm);
      req_right_ = right;
      req_left_ = left;
      req_velocity_ = (right + left) / 2;
      req_radius_ = 0;
      applyDrive((right + left) / 2000.0, (right - left) / 1000.0 / options_.wheel_base);
      break;
    }
    case oi::kSensors:
      answerSensors({&cmd_[1], 1});
      break;
    case oi::kQueryList:
      answerSensors({&cmd_[2], cmd_[1]});
      break;
    case oi::kStream: {
      stream_n_ = 0;
      std::size_t frame_bytes = 0;
      for (std::size_t i = 0; i < cmd_[1]; ++i) {
        const std::uint8_t id = cmd_[2 + i];
        const std::size_t need = knownId(id) ? 1 + dataBytes(id) : 0;
        if (!knownId(id) || stream_n_ == kMaxStreamIds || frame_bytes + need > kMaxStreamBytes) {
          noteUnsupported(id);
          continue;
        }
        stream_ids_[stream_n_++] = id;
        frame_bytes += need;
      }
      paused_ = false;
      next_due_ = body_.now();
      break;
    }
    case oi::kPauseResume:
      paused_ = cmd_[1] == 0;
      if (!paused_) next_due_ = body_.now();
      break;
    default:
      ++counters_.ignored_commands;  // LEDs, songs, scripts, demos: parsed, not emulated
      break;
  }
}

void CreateEmulator::applyDrive(double v, double omega) {
  ++counters_.drive_commands;
  (void)body_.drive(v, omega);
}

void CreateEmulator::enterPassive() {
  if (mode_ == oi::Mode::kSafeMode || mode_ == oi::Mode::kFullMode) {
    (void)body_.drive(0.0, 0.0);
    req_velocity_ = req_radius_ = req_right_ = req_left_ = 0;
  }
  mode_ = oi::Mode::kPassive;
}

void CreateEmulator::accumulateMotion() {
  const Pose2 p = body_.odometry();
  const double dtheta = wrapPi(p.theta - last_pose_.theta);
  const double half = 0.5 * dtheta;
  const double mid = last_pose_.theta + half;
  // Displacement along the mid heading is the chord; the wheels travel the arc.
  const double chord = (p.x - last_pose_.x) * std::cos(mid) + (p.y - last_pose_.y) * std::sin(mid);
  const double arc = std::abs(half) < 1e-9 ? chord : chord * half / std::sin(half);
  dist_acc_mm_ += 1000.0 * arc;
  angle_acc_deg_ += dtheta * 180.0 / kPi;
  last_pose_ = p;
}

void CreateEmulator::noteUnsupported(std::uint8_t id) {
  ++counters_.unsupported_ids;
  unsupported_seen_.set(id);
}

oi::SensorFrame CreateEmulator::snapshot(std::span<const std::uint8_t> ids) {
  accumulateMotion();
  oi::SensorFrame f;
  for (const std::uint8_t id : ids) {
    if (f.has(id)) continue;  // asked twice (e.g. 19 and group 2): one reading, sent twice
    std::int32_t v = 0;
    switch (id) {
      case oi::kBumpsWheelDrops:
        v = static_cast<std::uint8_t>(body_.bumper()) | drops_;  // bits 0, 1: right, left
        break;
      case oi::kDistance: {
        const double whole = std::clamp(std::trunc(dist_acc_mm_), -32768.0, 32767.0);
        dist_acc_mm_ -= whole;
        v = static_cast<std::int32_t>(whole);
        break;
      }
      case oi::kAngle: {
        const double whole = std::clamp(std::trunc(angle_acc_deg_), -32768.0, 32767.0);
        angle_acc_deg_ = options_.drop_angle_remainder ? 0.0 : angle_acc_deg_ - whole;
        v = static_cast<std::int32_t>(whole);
        break;
      }
      case oi::kVoltage: v = 16000; break;       // mV, a charged pack
      case 24: v = 25; break;                     // battery temperature, deg C
      case 25: v = 2500; break;                   // charge, mAh
      case 26: v = 3000; break;                   // capacity, mAh
      case oi::kOiMode: v = static_cast<std::int32_t>(mode_); break;
      case 38: v = static_cast<std::int32_t>(stream_n_); break;
      case oi::kRequestedVelocity: v = req_velocity_; break;
      case oi::kRequestedRadius: v = req_radius_; break;
      case oi::kRequestedRightVelocity: v = req_right_; break;
      case oi::kRequestedLeftVelocity: v = req_left_; break;
      default: break;  // walls, cliffs, IR, buttons, cargo bay: nothing there
    }
    f.set(id, v);
  }
  return f;
}

void CreateEmulator::answerSensors(std::span<const std::uint8_t> requested) {
  std::array<std::uint8_t, 256> known{};
  std::size_t m = 0;
  for (const std::uint8_t r : requested) {
    if (knownId(r)) {
      known[m++] = r;
    } else {
      noteUnsupported(r);  // no bytes for it: the manual has no error reply
    }
  }
  std::array<std::uint8_t, 256 * 36> ids{};
  const std::size_t n = expandIds({known.data(), m}, ids);
  const oi::SensorFrame f = snapshot({ids.data(), n});
  std::array<std::uint8_t, 256 * 52> out{};
  std::size_t k = 0;
  for (std::size_t i = 0; i < m; ++i) k = writeData(known[i], f, out, k);
  write({out.data(), k});
}

void CreateEmulator::sendPacket() {
  std::array<std::uint8_t, kMaxStreamIds * 36> ids{};
  const std::size_t n_ids = expandIds(streamIds(), ids);
  const oi::SensorFrame f = snapshot({ids.data(), n_ids});
  std::array<std::uint8_t, kMaxStreamBytes + 3> out{};
  std::size_t k = 2;
  for (const std::uint8_t id : streamIds()) {
    out[k++] = id;
    k = writeData(id, f, out, k);
  }
  out[0] = oi::kStreamHeader;
  out[1] = static_cast<std::uint8_t>(k - 2);
  unsigned sum = 0;
  for (std::size_t i = options_.checksum_includes_header ? 0 : 1; i < k; ++i) sum += out[i];
  out[k++] = static_cast<std::uint8_t>((256u - (sum & 0xFFu)) & 0xFFu);
  if (corrupt_ > 0) {
    --corrupt_;
    ++counters_.corrupted_packets;
    out[k - 1] ^= 0x5A;
  }
  ++counters_.packets_sent;
  write({out.data(), k});
}

void CreateEmulator::write(std::span<const std::uint8_t> bytes) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(master_, bytes.data() + done, bytes.size() - done);
    if (n > 0) {
      done += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    break;  // EAGAIN: the pty is full, nobody reads; a real serial line loses them too
  }
  counters_.bytes_sent += done;
  counters_.bytes_dropped += bytes.size() - done;
}

}  // namespace crunch::sim
