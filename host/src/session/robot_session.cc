#include "crunch/session/robot_session.h"

#include <limits>
#include <utility>

#include "crunch/core/range_check.h"

namespace crunch::session {

namespace {
SensingChainOptions chainOptions(const RobotSessionOptions& o) {
  SensingChainOptions c;
  c.pipeline = o.pipeline;
  c.mounts = o.mounts;
  c.start = o.start;
  return c;
}
}  // namespace

Status RobotSessionOptions::validate() const {
  if (auto s = chainOptions(*this).validate(); !s) return s;
  if (auto s = within("mapping", mapping.validate()); !s) return s;
  const Status checks[] = {
      // The area first: a start placed at a bad area's centre is bad because of the area.
      checkRange("area.lo.x", area_lo.x(), -1e3, 1e3),
      checkRange("area.lo.y", area_lo.y(), -1e3, 1e3),
      checkRange("area width (area.hi.x - area.lo.x)", area_hi.x() - area_lo.x(), 0.5, kMaxAreaSide),
      checkRange("area depth (area.hi.y - area.lo.y)", area_hi.y() - area_lo.y(), 0.5, kMaxAreaSide),
      checkRange("start.x", start.x, -1e3, 1e3),
      checkRange("start.y", start.y, -1e3, 1e3),
      checkRange("start.theta", start.theta, -1e3, 1e3)};
  for (const Status& s : checks) {
    if (!s) return s;
  }
  return okStatus();
}

Result<std::unique_ptr<RobotSession>> RobotSession::create(const RobotSessionOptions& options) {
  if (auto s = options.validate(); !s) return s.error();
  auto chain = SensingChain::create(chainOptions(options));
  if (!chain) return chain.error();
  if (auto s = chain.value()->setModels(options.models); !s) return s.error();
  return std::unique_ptr<RobotSession>(new RobotSession(options, std::move(chain).value()));
}

namespace {
MappingOptions withRoom(const RobotSessionOptions& o) {
  MappingOptions m = o.mapping;
  m.room.reset();
  if (o.room_bounds) m.room = std::pair<Vec2, Vec2>{o.area_lo, o.area_hi};
  return m;
}
}  // namespace

RobotSession::RobotSession(const RobotSessionOptions& options, std::unique_ptr<SensingChain> chain)
    : options_(options),
      chain_(std::move(chain)),
      tracker_(io::oi::StreamParserOptions{options.checksum_includes_header, 0}),
      mapper_(options.mounts, options.area_lo, options.area_hi, withRoom(options)) {}

Pose2 RobotSession::pose() const { return compose(options_.start, tracker_.odometry()); }

std::uint64_t RobotSession::settledUntil() const {
  // No odometry yet: the robot has not moved (it moves only after the Create answered).
  return track_.empty() ? std::numeric_limits<std::uint64_t>::max() : track_.settledUntil();
}

Pose2 RobotSession::poseAt(std::uint64_t t_ns) const {
  if (track_.empty()) return pose();
  return compose(options_.start, track_.poseAt(t_ns));
}

void RobotSession::feedCreate(const io::Chunk& chunk) {
  // Byte by byte, so that every packet's odometry is seen (a chunk may hold several). The
  // packets of one chunk arrived together; the Create sent them one stream period apart.
  std::size_t found = 0;
  const auto bytes = chunk.data();
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    const std::uint64_t before = tracker_.packets();
    tracker_.feed(bytes.subspan(i, 1));
    if (tracker_.packets() != before && found < packet_totals_.size()) {
      packet_totals_[found] = tracker_.odometryState().totalAngleDeg();
      packet_poses_[found] = tracker_.odometry();
      ++found;
    }
  }
  for (std::size_t k = 0; k < found; ++k) {
    const std::uint64_t back = static_cast<std::uint64_t>(found - 1 - k) * kStreamPeriodNs;
    track_.add(chunk.t_ns > back ? chunk.t_ns - back : 0, packet_totals_[k], packet_poses_[k]);
  }
  if (found > 0) sweepBody(false);
}

void RobotSession::sweepBody(bool to_end) {
  // Where the odometry says the body drove, no leg stands: swept in kSweepStep pieces (the
  // Create's path between two is near straight), from the first pose the Create reported.
  const Vec2 here = pose().position();
  if (!swept_to_ || to_end || (here - *swept_to_).norm() >= kSweepStep) {
    mapper_.addBodySweep(swept_to_.value_or(here), here);
    swept_to_ = here;
  }
}

void RobotSession::syncCounts() {
  const SensingCounts& c = chain_->counts();
  counts_.samples = c.samples;
  counts_.episodes = c.episodes;
  counts_.roaming_episodes = c.roaming_episodes;
  counts_.whisks = c.whisks;
  counts_.reports = c.reports;
}

Status RobotSession::handle(const io::Chunk& chunk) {
  if (recorder_ != nullptr) {
    if (auto s = recorder_->write(chunk); !s) return s;
  }
  switch (chunk.stream) {
    case io::StreamId::kBridge: {
      ++counts_.bridge_chunks;
      // The samples these bytes complete wait for the odometry of their moment.
      auto pose_at = [this](std::uint64_t t) { return poseAt(t); };
      chain_->feedTimed(chunk.data(), chunk.t_ns, pose_at);
      chain_->release(settledUntil(), pose_at);
      break;
    }
    case io::StreamId::kCreate:
      ++counts_.create_chunks;
      feedCreate(chunk);
      chain_->release(settledUntil(), [this](std::uint64_t t) { return poseAt(t); });
      break;
    case io::StreamId::kMark:
      ++counts_.marks;
      // Whatever was sensed before the mark belongs before it: the samples up to its time go
      // through with the best pose known now (odometry_track.h).
      chain_->release(chunk.t_ns, [this](std::uint64_t t) { return poseAt(t); });
      if (chunk.size >= 1) {
        if (chunk.bytes[0] == static_cast<std::uint8_t>(io::MarkKind::kWhiskStart)) {
          chain_->beginWhisk();
        }
        if (chunk.bytes[0] == static_cast<std::uint8_t>(io::MarkKind::kWhiskEnd)) closeWhisk();
        if (chunk.bytes[0] == static_cast<std::uint8_t>(io::MarkKind::kBridgeReconnected)) {
          chain_->reconnect();
        }
      }
      break;
  }
  syncCounts();
  return okStatus();
}

Status RobotSession::mark(io::MarkKind kind_id, std::uint64_t t_ns) {
  io::Chunk c;
  const std::uint8_t kind = static_cast<std::uint8_t>(kind_id);
  c.assign(io::StreamId::kMark, t_ns, {&kind, 1});
  return handle(c);
}

void RobotSession::closeWhisk() {
  reports_.clear();
  free_rays_.clear();
  chain_->endWhisk(reports_, free_rays_);
  mapper_.addPose(pose(), reports_, free_rays_);
  syncCounts();
}

Status RobotSession::bridgeReconnected(std::uint64_t t_ns) {
  return mark(io::MarkKind::kBridgeReconnected, t_ns);
}

Map RobotSession::finish() {
  chain_->release(std::numeric_limits<std::uint64_t>::max(),
                  [this](std::uint64_t t) { return poseAt(t); });
  if (swept_to_) sweepBody(true);
  closeWhisk();
  return mapper_.finish();
}

}  // namespace crunch::session
