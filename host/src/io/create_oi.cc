#include "crunch/io/create_oi.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace crunch::io::oi {

namespace {

// OI spec "Sensor Packets", ids 7..42: data bytes of each.
constexpr std::array<std::uint8_t, kLastPacketId + 1> kSizes = {
    0, 0, 0, 0, 0, 0, 0,     // 0..6 groups: not accepted in a stream here
    1, 1, 1, 1, 1, 1, 1,     // 7 bumps, 8 wall, 9..12 cliffs, 13 virtual wall
    1, 1, 1, 1, 1,           // 14 overcurrents, 15, 16 unused, 17 IR, 18 buttons
    2, 2,                    // 19 distance, 20 angle
    1, 2, 2, 1, 2, 2,        // 21 charging, 22 voltage, 23 current, 24 temp, 25 charge, 26 cap
    2, 2, 2, 2, 2,           // 27 wall signal, 28..31 cliff signals
    1, 2, 1,                 // 32 cargo digital, 33 cargo analog, 34 charging sources
    1, 1, 1, 1,              // 35 OI mode, 36 song number, 37 song playing, 38 stream packets
    2, 2, 2, 2,              // 39 req velocity, 40 req radius, 41 req right, 42 req left
};

std::uint8_t hi(int v) { return static_cast<std::uint8_t>((static_cast<unsigned>(v) >> 8) & 0xFFu); }
std::uint8_t lo(int v) { return static_cast<std::uint8_t>(static_cast<unsigned>(v) & 0xFFu); }

int clampInt(int v, int limit) { return std::clamp(v, -limit, limit); }

IdCommand idCommand(std::uint8_t opcode, std::span<const std::uint8_t> ids) {
  IdCommand c;
  const std::size_t n = std::min(ids.size(), kMaxIds);
  c.bytes[0] = opcode;
  c.bytes[1] = static_cast<std::uint8_t>(n);
  for (std::size_t i = 0; i < n; ++i) c.bytes[2 + i] = ids[i];
  c.size = 2 + n;
  return c;
}

}  // namespace

int packetSize(std::uint8_t id) { return id <= kLastPacketId ? kSizes[id] : 0; }

bool packetSigned(std::uint8_t id) {
  switch (id) {
    case 19: case 20: case 23: case 24: case 39: case 40: case 41: case 42:
      return true;
    default:
      return false;
  }
}

std::array<std::uint8_t, 1> start() { return {kStart}; }
std::array<std::uint8_t, 1> safe() { return {kSafe}; }
std::array<std::uint8_t, 1> full() { return {kFull}; }

std::array<std::uint8_t, 5> drive(int velocity_mm_s, int radius_mm) {
  const int v = clampInt(velocity_mm_s, kMaxWheelSpeedMm);
  int r = radius_mm;
  if (r == 32768 || r == -32768) {
    r = kRadiusStraight;  // 0x8000
  } else if (r != kRadiusStraightAlt && r != kRadiusTurnCw && r != kRadiusTurnCcw) {
    r = clampInt(r, kMaxRadiusMm);
  }
  return {kDrive, hi(v), lo(v), hi(r), lo(r)};
}

std::array<std::uint8_t, 5> driveDirect(int right_mm_s, int left_mm_s) {
  const int r = clampInt(right_mm_s, kMaxWheelSpeedMm);
  const int l = clampInt(left_mm_s, kMaxWheelSpeedMm);
  return {kDriveDirect, hi(r), lo(r), hi(l), lo(l)};
}

std::array<std::uint8_t, 2> pauseResume(bool resume) {
  return {kPauseResume, static_cast<std::uint8_t>(resume ? 1 : 0)};
}
std::array<std::uint8_t, 2> sensors(std::uint8_t id) { return {kSensors, id}; }

IdCommand stream(std::span<const std::uint8_t> ids) { return idCommand(kStream, ids); }
IdCommand queryList(std::span<const std::uint8_t> ids) { return idCommand(kQueryList, ids); }

WheelSpeeds twistToWheels(double v, double omega, double wheel_base) {
  WheelSpeeds w;
  if (!std::isfinite(v) || !std::isfinite(omega) || !std::isfinite(wheel_base)) {
    w.clamped = true;  // refuse nonsense: stop
    return w;
  }
  double right = v + 0.5 * omega * wheel_base;
  double left = v - 0.5 * omega * wheel_base;
  const double limit = kMaxWheelSpeedMm / 1000.0;
  const double biggest = std::max(std::abs(right), std::abs(left));
  if (biggest > limit) {
    const double s = limit / biggest;
    right *= s;
    left *= s;
    w.clamped = true;
  }
  w.right_mm_s = clampInt(static_cast<int>(std::lround(right * 1000.0)), kMaxWheelSpeedMm);
  w.left_mm_s = clampInt(static_cast<int>(std::lround(left * 1000.0)), kMaxWheelSpeedMm);
  return w;
}

DriveArgs twistToDrive(double v, double omega, double wheel_base) {
  DriveArgs d;
  if (!std::isfinite(v) || !std::isfinite(omega) || !std::isfinite(wheel_base)) return d;
  const double limit = kMaxWheelSpeedMm / 1000.0;
  const double biggest =
      std::max(std::abs(v + 0.5 * omega * wheel_base), std::abs(v - 0.5 * omega * wheel_base));
  if (biggest > limit) {
    const double s = limit / biggest;
    v *= s;
    omega *= s;
  }
  const int vel = static_cast<int>(std::lround(v * 1000.0));
  if (std::abs(omega) < 1e-9) {
    d.velocity_mm_s = vel;
    d.radius_mm = kRadiusStraight;
    return d;
  }
  const double radius_mm = 1000.0 * v / omega;
  if (std::abs(radius_mm) < 0.5) {
    d.velocity_mm_s = static_cast<int>(std::lround(std::abs(omega) * 0.5 * wheel_base * 1000.0));
    d.radius_mm = omega > 0 ? kRadiusTurnCcw : kRadiusTurnCw;
    return d;
  }
  d.velocity_mm_s = vel;
  if (std::abs(radius_mm) > kMaxRadiusMm) {
    d.radius_mm = kRadiusStraight;
    return d;
  }
  int r = static_cast<int>(std::lround(radius_mm));
  if (r == 1 || r == -1) r *= 2;  // keep clear of the turn-in-place specials
  d.radius_mm = r;
  return d;
}

std::size_t encodeStreamPacket(std::span<const std::uint8_t> ids, const SensorFrame& values,
                               bool checksum_includes_header, std::span<std::uint8_t> out) {
  std::size_t n = 0;
  for (const std::uint8_t id : ids) {
    const int size = packetSize(id);
    if (size == 0) return 0;
    n += 1 + static_cast<std::size_t>(size);
  }
  if (n == 0 || n > 255 || out.size() < n + 3) return 0;
  std::size_t i = 0;
  out[i++] = kStreamHeader;
  out[i++] = static_cast<std::uint8_t>(n);
  for (const std::uint8_t id : ids) {
    out[i++] = id;
    const std::int32_t v = values.get(id);
    if (packetSize(id) == 2) {
      out[i++] = hi(v);
      out[i++] = lo(v);
    } else {
      out[i++] = lo(v);
    }
  }
  unsigned sum = 0;
  for (std::size_t k = checksum_includes_header ? 0 : 1; k < i; ++k) sum += out[k];
  out[i++] = static_cast<std::uint8_t>((256u - (sum & 0xFFu)) & 0xFFu);
  return i;
}

// ---- StreamParser ---------------------------------------------------------------------------

bool StreamParser::feed(std::uint8_t byte) {
  ++counters_.bytes;
  if (size_ == 0 && byte != kStreamHeader) {
    ++counters_.skipped_bytes;
    return false;
  }
  buf_[size_++] = byte;
  return process();
}

bool StreamParser::drainHeld() { return size_ > 0 && process(); }

bool StreamParser::process() {
  while (size_ > 0) {
    switch (examine()) {
      case Verdict::kNeedMore:
        return false;
      case Verdict::kValid: {
        decode();
        const std::size_t len = static_cast<std::size_t>(buf_[1]) + 3;
        ++counters_.packets;
        counters_.packet_bytes += len;
        std::memmove(buf_.data(), buf_.data() + len, size_ - len);
        size_ -= len;
        examined_ = 0;
        next_id_ = 2;
        // Held bytes after the packet cannot start with anything but a header: drop the rest.
        std::size_t skip = 0;
        while (skip < size_ && buf_[skip] != kStreamHeader) ++skip;
        if (skip > 0) {
          counters_.skipped_bytes += skip;
          std::memmove(buf_.data(), buf_.data() + skip, size_ - skip);
          size_ -= skip;
        }
        return true;
      }
      case Verdict::kBadLayout:
        ++counters_.bad_length_or_id;
        rejectHead();
        break;
      case Verdict::kBadChecksum:
        ++counters_.checksum_failures;
        rejectHead();
        break;
    }
  }
  return false;
}

StreamParser::Verdict StreamParser::examine() {
  for (; examined_ < size_; ++examined_) {
    const std::size_t i = examined_;
    if (i == 0) continue;  // the header, checked when it was held
    if (i == 1) {
      const std::uint8_t n = buf_[1];
      if (n == 0 || (options_.expected_length != 0 && n != options_.expected_length)) {
        return Verdict::kBadLayout;
      }
      continue;
    }
    const std::size_t end = 2 + static_cast<std::size_t>(buf_[1]);  // index of the checksum
    if (i < end) {
      if (i == next_id_) {
        const int size = packetSize(buf_[i]);
        if (size == 0) return Verdict::kBadLayout;
        next_id_ = i + 1 + static_cast<std::size_t>(size);
        if (next_id_ > end) return Verdict::kBadLayout;
      }
      continue;
    }
    // i == end: the checksum byte.
    unsigned sum = 0;
    for (std::size_t k = options_.checksum_includes_header ? 0 : 1; k <= end; ++k) sum += buf_[k];
    ++examined_;
    return (sum & 0xFFu) == 0 ? Verdict::kValid : Verdict::kBadChecksum;
  }
  return Verdict::kNeedMore;
}

void StreamParser::rejectHead() {
  // Discard the header only, then any non-header bytes up to the next possible header.
  std::size_t skip = 1;
  while (skip < size_ && buf_[skip] != kStreamHeader) ++skip;
  counters_.skipped_bytes += skip;
  std::memmove(buf_.data(), buf_.data() + skip, size_ - skip);
  size_ -= skip;
  examined_ = 0;
  next_id_ = 2;
}

void StreamParser::decode() {
  frame_ = SensorFrame{};
  const std::size_t end = 2 + static_cast<std::size_t>(buf_[1]);
  std::size_t i = 2;
  while (i < end) {
    const std::uint8_t id = buf_[i];
    const int size = packetSize(id);
    std::int32_t v = 0;
    if (size == 2) {
      const auto raw = static_cast<std::uint16_t>((buf_[i + 1] << 8) | buf_[i + 2]);
      v = packetSigned(id) ? static_cast<std::int16_t>(raw) : raw;
    } else {
      v = packetSigned(id) ? static_cast<std::int8_t>(buf_[i + 1]) : buf_[i + 1];
    }
    frame_.set(id, v);
    i += 1 + static_cast<std::size_t>(size);
  }
}

void StreamParser::resync() {
  counters_.skipped_bytes += size_;
  size_ = 0;
  examined_ = 0;
  next_id_ = 2;
}

// ---- Odometry -------------------------------------------------------------------------------

void Odometry::update(int distance_mm, int angle_deg) {
  constexpr double kRadPerDeg = kPi / 180.0;
  const double theta0 = start_.theta + static_cast<double>(total_deg_) * kRadPerDeg;
  total_deg_ += angle_deg;
  total_mm_ += distance_mm;
  const double theta1 = start_.theta + static_cast<double>(total_deg_) * kRadPerDeg;
  const double mid = 0.5 * (theta0 + theta1);
  const double d = distance_mm / 1000.0;
  pose_.x += d * std::cos(mid);
  pose_.y += d * std::sin(mid);
  pose_.theta = theta1;
}

void Odometry::reset(Pose2 start) {
  start_ = start;
  pose_ = start;
  total_mm_ = 0;
  total_deg_ = 0;
}

// ---- SensorTracker --------------------------------------------------------------------------

void SensorTracker::feed(std::span<const std::uint8_t> bytes) {
  const auto take = [this] {
    const SensorFrame& f = parser_.frame();
    if (f.has(kDistance) || f.has(kAngle)) odometry_.update(f.get(kDistance), f.get(kAngle));
    if (f.has(kBumpsWheelDrops)) {
      bumps_ = static_cast<std::uint8_t>(f.get(kBumpsWheelDrops));
      if (bumped()) ++bump_packets_;
    }
    if (f.has(kOiMode)) {
      mode_ = static_cast<Mode>(std::clamp(f.get(kOiMode), 0, 3));
      mode_known_ = true;
    }
  };
  for (const std::uint8_t b : bytes) {
    if (!parser_.feed(b)) continue;
    take();
    while (parser_.drainHeld()) take();
  }
}

}  // namespace crunch::io::oi
