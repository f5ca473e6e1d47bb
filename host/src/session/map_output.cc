#include "crunch/session/map_output.h"

#include <algorithm>
#include <chrono>
#include <nlohmann/json.hpp>
#include <utility>

#include "crunch/core/atomic_file.h"
#include "crunch/mapping/map_io.h"
#include "crunch/mapping/report_json.h"
#include "crunch/render/map_render.h"
#include "crunch/scene/scene.h"

namespace crunch::session {

using json = nlohmann::json;

Status stageMapFiles(OutputSet& outputs, const Map& map, const Vec2& area_hi,
                     const std::string& out_dir, const std::string& title,
                     const exploration::ExplorationReport* exploration) {
  if (auto st = ensureDirectory(out_dir); !st) return st;
  Scene area;  // the "truth" drawn is only the mapped area
  area.width = area_hi.x();
  area.depth = area_hi.y();
  area.source = "robot";
  RenderOptions ropt;
  ropt.title = title;
  ropt.exploration = exploration;
  if (auto st = outputs.stage(out_dir + "/map.json", mapToJson(map)); !st) return st;
  auto png_file = outputs.add(out_dir + "/map.png");
  if (!png_file) return png_file.error();
  return renderMapPng(map, area, *png_file.value(), ropt);
}

Status writeMapFiles(const Map& map, const Vec2& area_hi, const std::string& out_dir,
                     const std::string& title, const exploration::ExplorationReport* exploration) {
  OutputSet outputs;
  if (auto st = stageMapFiles(outputs, map, area_hi, out_dir, title, exploration); !st) return st;
  return outputs.publish();
}

std::string sessionReportJson(const RobotSession& session, const Map& map) {
  const auto& d = session.decoderCounters();
  const auto& a = session.assemblerCounters();
  const auto& c = session.counts();
  const auto& e = session.evidenceCounts();
  const auto t = session.tracker().counters();
  const Pose2 p = session.pose();
  json shapelets = json::array();
  for (const Shapelet& sh : map.shapelets) {
    shapelets.push_back({{"x", sh.x},
                         {"y", sh.y},
                         {"phi", sh.phi},
                         {"oriented", sh.oriented},
                         {"whisker", sh.whisker},
                         {"pose", sh.pose_index},
                         {"from", {sh.ox, sh.oy}}});
  }
  const json report = {{"bridge",
                        {{"chunks", c.bridge_chunks},
                         {"bytes", d.bytes},
                         {"frames", d.frames},
                         {"crc_failures", d.crc_failures},
                         {"bad_version", d.bad_version},
                         {"bad_board", d.bad_board},
                         {"skipped_bytes", d.skipped_bytes},
                         {"lost_frames", d.lostFrames()},
                         {"dropped_samples", d.droppedSamples()}}},
                       {"samples",
                        {{"assembled", a.samples},
                         {"gap_placeholders", a.placeholders},
                         {"silent_fills", a.silent_fills},
                         {"unmapped_frames", a.unmapped_frames}}},
                       {"create",
                        {{"chunks", c.create_chunks},
                         {"packets", t.stream.packets},
                         {"checksum_failures", t.stream.checksum_failures},
                         {"bad_length_or_id", t.stream.bad_length_or_id},
                         {"skipped_bytes", t.stream.skipped_bytes}}},
                       {"contacts",
                        {{"episodes", c.episodes},
                         {"roaming_episodes", c.roaming_episodes},
                         {"whisks", c.whisks},
                         {"reports", c.reports},
                         {"no_radial", e.no_radial},
                         {"no_orientation", e.no_orientation},
                         {"no_ramp", e.no_ramp},
                         {"shaft", e.shaft},
                         {"flat", e.flat}}},
                       {"final_pose", {p.x, p.y, p.theta}},
                       {"map", {{"tables", map.tables.size()}, {"shapelets", map.stats.shapelets}}},
                       {"global_inference", json::parse(globalInferenceJson(map.stats).dump())},
                       {"shapelets", shapelets}};
  return report.dump();
}

MapWriter::MapWriter(const Vec2& area_hi, std::string out_dir, std::string title,
                     std::function<void(const Error&)> on_error)
    : area_hi_(area_hi),
      out_dir_(std::move(out_dir)),
      title_(std::move(title)),
      on_error_(std::move(on_error)),
      thread_([this] { loop(); }) {}

MapWriter::~MapWriter() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  cv_.notify_one();
  thread_.join();
}

void MapWriter::post(Map map) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    pending_ = std::move(map);
  }
  cv_.notify_one();
}

void MapWriter::loop() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    cv_.wait(lock, [this] { return stop_ || pending_.has_value(); });
    if (stop_) return;
    Map map = std::move(*pending_);
    pending_.reset();
    lock.unlock();  // the write runs unlocked: post() never waits for a render or an fsync
    const auto t0 = std::chrono::steady_clock::now();
    const Status st = writeMapFiles(map, area_hi_, out_dir_, title_);
    const double took =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!st && on_error_) on_error_(st.error());
    lock.lock();
    ++stats_.writes;
    stats_.failures += st ? 0 : 1;
    stats_.last_s = took;
    stats_.max_s = std::max(stats_.max_s, took);
  }
}

MapWriter::Stats MapWriter::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

}  // namespace crunch::session
