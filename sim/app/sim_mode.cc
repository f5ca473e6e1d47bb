#include "sim_mode.h"

#include <chrono>
#include <functional>
#include <ostream>
#include <sstream>

#include "crunch/core/atomic_file.h"
#include "crunch/mapping/map_io.h"
#include "crunch/mapping/mapper.h"
#include "crunch/render/map_render.h"
#include "crunch/serve/live_view.h"
#include "crunch/signal/models_io.h"
#include "crunch_sim/sim_report.h"
#include "crunch_sim/sim_run.h"
#include "progress.h"

namespace crunch::app {

namespace {

// --start x,y,theta.
Result<Pose2> parseStart(const std::string& text) {
  Pose2 p;
  char c1 = 0, c2 = 0;
  std::istringstream in(text);
  if (!(in >> p.x >> c1 >> p.y >> c2 >> p.theta) || c1 != ',' || c2 != ',' || !(in >> std::ws).eof()) {
    return Error{"--start " + text + ": expected x,y,theta (metres, metres, radians)"};
  }
  return p;
}

// --explore and its flags; nullopt without --explore. An Error names the flag.
Result<std::optional<exploration::ExploreOptions>> exploreOptions(const SimOptions& opt) {
  if (!opt.explore) {
    if (opt.teleport) return Error{"--teleport: needs --explore POLICY"};
    if (opt.start) return Error{"--start: needs --explore POLICY"};
  }
  auto flags = exploration::exploreOptionsFromFlags(opt.explore, opt.travel_budget, opt.whisk_budget);
  if (!flags || !flags.value()) return flags;
  exploration::ExploreOptions e = *flags.value();
  e.teleport = opt.teleport;
  if (opt.start) {
    auto start = parseStart(*opt.start);
    if (!start) return start.error();
    e.start = start.value();
  }
  if (auto st = e.validate(); !st) return st.error();
  return std::optional<exploration::ExploreOptions>{e};
}

// The library's run options from the command line's; an Error names the option.
Result<sim::SimRunOptions> runOptions(const SimOptions& opt) {
  sim::SimRunOptions o;
  auto kind = sim::sensorKindByName(opt.sensor_model);
  if (!kind) return kind.error();
  o.sensor = kind.value();
  auto noise = noiseRegimeByName(opt.noise);
  if (!noise) return Error{"--" + noise.error().message};
  o.noise = noise.value();
  o.models_path = opt.models_path.empty() ? crunch::signal::shippedModelsPath(CRUNCH_DEFAULT_MODELS) : opt.models_path;
  o.seed = opt.seed;
  o.mapping = opt.mapping;
  o.chain_fusion_given = opt.chain_fusion_given;
  o.snapshot_pose = opt.snapshot_pose;
  o.snapshot_temperature = opt.snapshot_temperature;
  auto explore = exploreOptions(opt);
  if (!explore) return explore.error();
  o.explore = explore.value();
  return o;
}

// All the run's files or none (OutputSet): each is written to a temporary, and they replace
// their targets together once every one is complete.
Status writeOutputs(const SimOptions& opt, const sim::SimScene& scene, const sim::SimRun& run,
                    const sim::SimRunOptions& ro, double total_s) {
  if (auto s = ensureDirectory(opt.out_dir); !s) return s;
  const std::string dir = opt.out_dir + "/";
  RenderOptions render;
  render.title = "crunchhost --sim, noise " + run.noise.name + ", seed " + std::to_string(opt.seed);
  if (run.exploration) {
    render.exploration = &*run.exploration;
    render.title += ", --explore " + run.exploration->policy +
                    (run.exploration->teleport ? " --teleport" : " (driven)");
  }
  OutputSet outputs;
  auto picture = [&](const std::string& path, const auto& draw) -> Status {
    auto f = outputs.add(path);
    if (!f) return f.error();
    return draw(*f.value());
  };
  const std::function<Status()> writes[] = {
      [&] { return outputs.stage(dir + "map.json", mapToJson(run.map)); },
      [&] {
        return picture(dir + "map.png",
                       [&](AtomicFile& f) { return renderMapPng(run.map, scene.scene, f, render); });
      },
      [&] {
        return outputs.stage(dir + "report.json",
                             sim::simReportJson(scene.scene, run, ro, total_s));
      },
      [&]() -> Status {
        if (!run.snapshot) return okStatus();
        const std::string base = dir + "snapshot_" + std::to_string(run.snapshot->pose_index);
        if (Status st = picture(base + ".png",
                                [&](AtomicFile& f) {
                                  return renderSnapshotPng(*run.snapshot, scene.scene, f);
                                });
            !st) {
          return st;
        }
        return picture(base + ".svg", [&](AtomicFile& f) {
          return renderSnapshotSvg(*run.snapshot, scene.scene, f);
        });
      }};
  for (const auto& write : writes)
    if (Status status = write(); !status) return status;  // ~OutputSet removes the temporaries
  return outputs.publish();
}

// --serve: the run as the live view shows it, published at most every kPeriod of wall time: after
// a mapped pose (with the mapper's snapshot(), which draws nothing: the map is the same with or
// without the view) or, while a driven --explore run moves, with the pose alone; the final map
// when the run ends. (A snapshot after every pose cost the default arena's 320-pose run 40% of
// its time; at kPeriod it costs nothing measurable.)
class SimLiveFeed {
  static constexpr std::chrono::milliseconds kPeriod{100};

 public:
  SimLiveFeed(serve::LiveView& view, const Scene& scene, std::size_t poses_total)
      : view_(view), t0_(std::chrono::steady_clock::now()), poses_total_(poses_total) {
    state_.mode = "sim";
    state_.stage = "mapping";
    state_.area_hi = {scene.width, scene.depth};
    view_.publish(state_);  // the arena, before the first pose
  }

  void install(sim::SimRunOptions& ro) {
    ro.observe = [this](const Mapper& mapper, const Pose2& pose) {
      state_.moveTo(pose);
      state_.setCounter("whisks", mapper.poses());
      if (poses_total_ > 0 && !explore_) state_.setCounter("poses_total", double(poses_total_));
      mapper_ = &mapper;  // lives as long as the run: read again when the next snapshot is due
      map_stale_ = true;
      if (due()) publish();
    };
    explore_ = ro.explore.has_value();
    if (explore_) {
      ro.moved = [this](const Pose2& pose, double sim_t) {
        state_.moveTo(pose);
        state_.setCounter("sim_time_s", sim_t);
        if (due()) publish();
      };
    }
  }

  // The final map; the last snapshot (done).
  void finish(const sim::SimRun& run) {
    mapper_ = nullptr;  // the run's mapper is gone
    map_stale_ = false;
    state_.setMap(run.map);
    state_.stage = "done";
    state_.done = true;
    state_.setCounter("recall", run.evaluation.recall);
    state_.setCounter("precision", run.evaluation.precision);
    publish();
  }

 private:
  bool due() const { return std::chrono::steady_clock::now() - last_ >= kPeriod; }

  void publish() {
    if (map_stale_ && mapper_ != nullptr) {
      state_.setMap(mapper_->snapshot());
      map_stale_ = false;
    }
    last_ = std::chrono::steady_clock::now();
    state_.t = std::chrono::duration<double>(last_ - t0_).count();
    state_.setCounter("tables", double(state_.tables.size()));
    state_.setCounter("walls", double(state_.walls.size()));
    state_.setCounter("shapelets", state_.shapelets);
    view_.publish(state_);
  }

  serve::LiveView& view_;
  serve::LiveState state_;
  std::chrono::steady_clock::time_point t0_, last_{};
  std::size_t poses_total_;
  bool explore_ = false;
  const Mapper* mapper_ = nullptr;  // the run's, while it runs
  bool map_stale_ = false;          // a pose was mapped since the last snapshot
};

void printSummary(const SimOptions& opt, const sim::SimScene& scene, const sim::SimRun& run,
                  std::ostream& out) {
  const Evaluation& ev = run.evaluation;
  const MapStats& st = run.map.stats;
  if (opt.json_progress) {
    out << "{\"event\":\"done\",\"recall\":" << ev.recall << ",\"precision\":" << ev.precision
        << ",\"out\":\"" << opt.out_dir << "\"}\n";
    return;
  }
  const std::string dir = opt.out_dir + "/";
  if (run.exploration) {
    const auto& x = *run.exploration;
    out << "explored (" << x.policy << (x.teleport ? ", teleported" : ", driven") << "): "
        << x.travel_m << " m, " << x.whisks << " whisks, " << x.bumps << " bumps, "
        << x.sim_time_s << " s simulated; stopped: " << x.stop_reason << "\n";
  }
  out << "mapped " << scene.scene.source << ": " << st.poses << " poses (" << st.skipped_poses
      << " skipped), " << st.shapelets << " shapelets, " << run.map.tables.size()
      << " tables in the fused map\n"
      << "recall " << ev.recall << ", precision " << ev.precision << " ("
      << ev.phantoms_near_walls << " phantoms near walls, " << ev.phantoms_elsewhere
      << " elsewhere), mean error " << ev.mean_position_error << " m / "
      << ev.mean_angle_error * 180.0 / kPi << " deg\n"
      << "inference " << st.wall_s << " s; wrote " << dir << "{map.json,map.png,report.json}\n";
  if (run.snapshot) out << "wrote " << dir << "snapshot_" << run.snapshot->pose_index << ".{png,svg}\n";
}

}  // namespace

int runSim(const SimOptions& opt, std::ostream& out, std::ostream& err) {
  const auto t0 = std::chrono::steady_clock::now();
  auto loaded = sim::loadSimScene(opt.scene_path);
  if (!loaded) {
    err << "crunchhost: " << loaded.error().message << "\n";
    return 2;
  }
  auto ro = runOptions(opt);
  if (!ro) {
    err << "crunchhost: " << ro.error().message << "\n";
    return 2;
  }
  std::optional<serve::ServeAddress> serve_at;
  if (opt.serve) {
    auto parsed = serve::parseServeAddress(*opt.serve);
    if (!parsed) {
      err << "crunchhost: " << parsed.error().message << "\n";
      return 2;
    }
    serve_at = parsed.value();
  }
  // A --out that cannot take the outputs is refused before the run, not after it.
  if (Status s = checkOutputTargets(opt.out_dir, {"map.json", "map.png", "report.json"}); !s) {
    err << "crunchhost: --out " << s.error().message << "\n";
    return 2;
  }
  // --serve: listening before the run; an address that cannot be, before anything is written.
  std::unique_ptr<serve::LiveView> view;
  if (serve_at) {
    auto started = serve::LiveView::start({.address = *serve_at});
    if (!started) {
      err << "crunchhost: " << started.error().message << "\n";
      return 3;
    }
    view = std::move(started).value();
    (opt.json_progress ? out : err) << serve::servingLine(view->address(), opt.json_progress)
                                    << std::endl;
  }
  removeStaleTemps(opt.out_dir, {"map.json", "map.png", "report.json"});
  PoseProgress bar(opt.json_progress ? out : err, opt.json_progress);
  ro.value().mapping.progress = [&bar](int done, int total) { bar(done, total); };
  const sim::SimScene scene = sim::SimScene::build(std::move(loaded).value());
  std::optional<SimLiveFeed> feed;
  if (view) {
    feed.emplace(*view, scene.scene, scene.poses.size());
    feed->install(ro.value());
  }
  auto run = sim::runSimulation(scene, ro.value());
  if (!run) {
    err << "crunchhost: " << run.error().message << "\n";
    return 2;
  }
  if (!run.value().warning.empty()) err << "crunchhost: " << run.value().warning << "\n";
  const double total_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (Status s = writeOutputs(opt, scene, run.value(), ro.value(), total_s); !s) {
    err << "crunchhost: " << s.error().message << "\n";
    return 1;
  }
  if (feed) feed->finish(run.value());
  printSummary(opt, scene, run.value(), out);
  return 0;
}

}  // namespace crunch::app
