#include "sweep_mode.h"

#include <sys/resource.h>

#include <algorithm>
#include <atomic>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <fstream>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <ostream>
#include <set>
#include <sstream>
#include <thread>

#include "crunch/core/atomic_file.h"
#include "crunch/mapping/evaluation.h"
#include "crunch/mapping/map_io.h"
#include "crunch/mapping/run_mapping.h"
#include "crunch/scene/scene.h"
#include "crunch_sim/ray_sensor.h"
#include "crunch_sim/world.h"

namespace crunch::app {

const std::vector<std::string> kSweepColumns = {
    "grid",           "grid_index",
    "grid_size",      "shard",
    "scene",          "noise",
    "sigma_r",        "sigma_phi",
    "schedule_steps", "sweeps",
    "working_memory", "seed",
    "poses",          "shapelets",
    "fused_tables",   "true_tables",
    "matched",        "precision",
    "recall",         "f1",
    "mean_position_error_m",
    "mean_angle_error_rad",
    "per_pose_match_fraction",
    "phantoms_near_walls",
    "phantoms_elsewhere",
    "proposals",      "peak_live_tables",
    "peak_live_legs", "wall_s",
    "process_peak_rss_kib"};

namespace {

using Json = nlohmann::ordered_json;

// Every World query of the process: this ODE build keeps its collision scratch global
// (crunch_sim/world.h), and each World reuses its own scratch geoms.
std::mutex g_world_mutex;

// A sensor whose every call into the World holds g_world_mutex.
class LockedSensor final : public SensorModel {
 public:
  explicit LockedSensor(SensorModel& inner) : inner_(inner) {}
  void sense(const Pose2& pose, Rng& rng, std::vector<ContactReport>& out) override {
    std::lock_guard<std::mutex> lock(g_world_mutex);
    inner_.sense(pose, rng, out);
  }
  const std::vector<WhiskerMount>& mounts() const override { return inner_.mounts(); }
  void freeRays(std::vector<FreeRay>& out) const override {
    std::lock_guard<std::mutex> lock(g_world_mutex);
    inner_.freeRays(out);
  }

 private:
  SensorModel& inner_;
};

// ---- Parsing the command line's lists. Every error names the option.

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return {};
  const auto e = s.find_last_not_of(" \t");
  return s.substr(b, e - b + 1);
}

Result<std::vector<std::string>> splitList(const std::string& text, const std::string& option) {
  std::vector<std::string> items;
  std::string item;
  std::istringstream in(text);
  while (std::getline(in, item, ',')) {
    item = trim(item);
    if (item.empty()) return Error{option + ": empty item in list '" + text + "'"};
    items.push_back(item);
  }
  if (!text.empty() && text.back() == ',')
    return Error{option + ": empty item in list '" + text + "'"};
  if (items.empty()) return Error{option + ": empty list"};
  return items;
}

template <typename T>
Result<std::vector<T>> parseIntegers(const std::string& text, const std::string& option, T min) {
  auto items = splitList(text, option);
  if (!items) return items.error();
  std::vector<T> values;
  std::set<T> seen;
  for (const std::string& s : items.value()) {
    T v{};
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || end != s.data() + s.size())
      return Error{option + ": '" + s + "' is not an integer"};
    if (v < min) return Error{option + ": " + s + " is below " + std::to_string(min)};
    if (!seen.insert(v).second) return Error{option + ": " + s + " appears twice"};
    values.push_back(v);
  }
  return values;
}

Result<std::vector<double>> parseScales(const std::string& text, const std::string& option) {
  auto items = splitList(text, option);
  if (!items) return items.error();
  std::vector<double> values;
  for (const std::string& s : items.value()) {
    char* end = nullptr;
    const double v = std::strtod(s.c_str(), &end);
    if (end != s.c_str() + s.size() || !std::isfinite(v))
      return Error{option + ": '" + s + "' is not a number"};
    if (v < 0) return Error{option + ": " + s + " is negative"};
    if (std::find(values.begin(), values.end(), v) != values.end())
      return Error{option + ": " + s + " appears twice"};
    values.push_back(v);
  }
  return values;
}

std::string formatNumber(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// ---- The grid.

struct SceneEntry {
  std::string arg;  // as given: a path or "default"
  Scene scene;
  std::unique_ptr<sim::World> world;
  std::vector<Pose2> poses;  // reachable
  int skipped = 0;
};

struct Grid {
  std::vector<SceneEntry> scenes;
  std::vector<NoiseRegime> noises;
  std::vector<int> schedule_steps, sweeps, working_memory;
  std::vector<uint64_t> seeds;
  std::string fingerprint;

  size_t size() const {
    return scenes.size() * noises.size() * schedule_steps.size() * sweeps.size() *
           working_memory.size() * seeds.size();
  }
};

struct Point {
  size_t scene, noise;
  int schedule_steps, sweeps, working_memory;
  uint64_t seed;
};

// Index -> point, seed fastest, scene slowest.
Point pointAt(const Grid& g, size_t index) {
  Point p{};
  size_t i = index;
  p.seed = g.seeds[i % g.seeds.size()];
  i /= g.seeds.size();
  p.working_memory = g.working_memory[i % g.working_memory.size()];
  i /= g.working_memory.size();
  p.sweeps = g.sweeps[i % g.sweeps.size()];
  i /= g.sweeps.size();
  p.schedule_steps = g.schedule_steps[i % g.schedule_steps.size()];
  i /= g.schedule_steps.size();
  p.noise = i % g.noises.size();
  i /= g.noises.size();
  p.scene = i;
  return p;
}

uint64_t fnv1a(const std::string& s) {
  uint64_t h = 1469598103934665603ull;
  for (const unsigned char c : s) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

std::string hex64(uint64_t v) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

Result<std::string> readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{path + ": cannot read"};
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Parses and checks every option; loads every scene. Nothing is written.
Result<Grid> buildGrid(const SweepOptions& opt, std::vector<std::string>& scene_texts) {
  Grid g;
  const std::vector<std::string> scene_args =
      opt.scenes.empty() ? std::vector<std::string>{"default"} : opt.scenes;
  for (const std::string& arg : scene_args) {
    SceneEntry e;
    e.arg = arg;
    if (arg == "default") {
      e.scene = defaultArena();
      scene_texts.push_back("default");
    } else {
      auto loaded = loadScene(arg);
      if (!loaded) return Error{"--scene: " + loaded.error().message};
      e.scene = std::move(loaded).value();
      auto text = readFile(arg);
      if (!text) return Error{"--scene: " + text.error().message};
      scene_texts.push_back(text.value());
    }
    g.scenes.push_back(std::move(e));
  }
  if (!opt.noise.empty()) {
    auto names = splitList(opt.noise, "--noise");
    if (!names) return names.error();
    for (const std::string& n : names.value()) {
      auto regime = noiseRegimeByName(n);
      if (!regime) return Error{"--" + regime.error().message};
      g.noises.push_back(regime.value());
    }
  }
  if (!opt.noise_scale.empty()) {
    auto scales = parseScales(opt.noise_scale, "--noise-scale");
    if (!scales) return scales.error();
    const NoiseRegime r = NoiseRegime::realistic();
    for (const double s : scales.value())
      g.noises.push_back({"x" + formatNumber(s), s * r.sigma_r, s * r.sigma_phi});
  }
  if (g.noises.empty()) g.noises.push_back(NoiseRegime::realistic());
  for (size_t i = 0; i < g.noises.size(); ++i)
    for (size_t j = 0; j < i; ++j)
      if (g.noises[i].name == g.noises[j].name)
        return Error{"--noise: regime '" + g.noises[i].name + "' appears twice"};

  const SamplerOptions sampler_defaults;
  const MappingOptions mapping_defaults;
  auto ints = [](const std::string& text, const std::string& option, int fallback,
                 std::vector<int>& out) -> Status {
    if (text.empty()) {
      out = {fallback};
      return okStatus();
    }
    auto v = parseIntegers<int>(text, option, 1);
    if (!v) return v.error();
    out = v.value();
    return okStatus();
  };
  if (auto s = ints(opt.schedule_steps, "--schedule-steps", sampler_defaults.schedule_steps,
                    g.schedule_steps); !s)
    return s.error();
  if (auto s = ints(opt.sweeps, "--sweeps", sampler_defaults.sweeps_per_temperature, g.sweeps); !s)
    return s.error();
  if (auto s = ints(opt.working_memory, "--working-memory", mapping_defaults.working_memory,
                    g.working_memory); !s)
    return s.error();
  // Every grid point's settings through the library's own validation (one road in).
  for (const NoiseRegime& n : g.noises)
    if (auto s = n.validate(); !s) return Error{"--noise-scale " + n.name + ": " + s.error().message};
  for (const int steps : g.schedule_steps)
    for (const int sw : g.sweeps)
      for (const int wm : g.working_memory) {
        MappingOptions mo;
        mo.sampler.schedule_steps = steps;
        mo.sampler.sweeps_per_temperature = sw;
        mo.working_memory = wm;
        if (auto s = mo.validate(); !s)
          return Error{"--schedule-steps/--sweeps/--working-memory: " + s.error().message};
      }

  if (!opt.seeds.empty() && !opt.seed_list.empty())
    return Error{"--seeds and --seed-list: give one of them"};
  if (!opt.seed_list.empty()) {
    auto v = parseIntegers<uint64_t>(opt.seed_list, "--seed-list", 0);
    if (!v) return v.error();
    g.seeds = v.value();
  } else {
    int n = 1;
    if (!opt.seeds.empty()) {
      auto v = parseIntegers<int>(opt.seeds, "--seeds", 1);
      if (!v) return v.error();
      if (v.value().size() != 1) return Error{"--seeds: one count N (seeds 1..N); a list is --seed-list"};
      n = v.value().front();
    }
    for (int s = 1; s <= n; ++s) g.seeds.push_back(static_cast<uint64_t>(s));
  }
  constexpr size_t kMaxGrid = 10'000'000;
  if (g.size() > kMaxGrid) return Error{"sweep: the grid has more than 10^7 points"};

  // The fingerprint: everything that decides a row except the binary itself.
  std::ostringstream d;
  d.precision(17);
  d << "crunch.sweep/1\nsensor gaussian\n";
  for (size_t i = 0; i < g.scenes.size(); ++i)
    d << "scene " << g.scenes[i].arg << " " << hex64(fnv1a(scene_texts[i])) << "\n";
  for (const NoiseRegime& n : g.noises)
    d << "noise " << n.name << " " << n.sigma_r << " " << n.sigma_phi << "\n";
  d << "schedule_steps";
  for (const int v : g.schedule_steps) d << " " << v;
  d << "\nsweeps";
  for (const int v : g.sweeps) d << " " << v;
  d << "\nworking_memory";
  for (const int v : g.working_memory) d << " " << v;
  d << "\nseeds";
  for (const uint64_t v : g.seeds) d << " " << v;
  d << "\nglobal " << mapping_defaults.global_sweeps << " " << mapping_defaults.global_chains
    << " smart " << sampler_defaults.smart_parent << " min_support "
    << mapping_defaults.fuse.min_support << "\n";
  g.fingerprint = hex64(fnv1a(d.str()));
  return g;
}

Result<std::pair<int, int>> parseShard(const std::string& text) {
  if (text.empty()) return std::pair<int, int>{0, 1};
  const auto slash = text.find('/');
  int i = -1, n = 0;
  if (slash != std::string::npos) {
    const char* b = text.data();
    const char* e = b + text.size();
    const auto [p1, ec1] = std::from_chars(b, b + slash, i);
    const auto [p2, ec2] = std::from_chars(b + slash + 1, e, n);
    if (ec1 != std::errc() || p1 != b + slash || ec2 != std::errc() || p2 != e) i = -1;
  }
  if (i < 0 || n < 1 || i >= n)
    return Error{"--shard: '" + text + "' is not i/n with 0 <= i < n"};
  return std::pair<int, int>{i, n};
}

long peakRssKib() {
  rusage u{};
  if (getrusage(RUSAGE_SELF, &u) != 0) return -1;
  return u.ru_maxrss;  // Linux: KiB
}

Json runPoint(const Grid& g, const Point& p, size_t index, const std::string& shard) {
  const auto t0 = std::chrono::steady_clock::now();
  const SceneEntry& se = g.scenes[p.scene];
  const NoiseRegime& noise = g.noises[p.noise];
  std::unique_ptr<sim::RaySensorModel> ray;
  {
    std::lock_guard<std::mutex> lock(g_world_mutex);
    ray = std::make_unique<sim::RaySensorModel>(*se.world, defaultWhiskerArray(), noise,
                                                sim::RaySensorModel::Options{});
  }
  LockedSensor sensor(*ray);
  MappingOptions mopt;
  mopt.seed = p.seed;
  mopt.sampler.schedule_steps = p.schedule_steps;
  mopt.sampler.sweeps_per_temperature = p.sweeps;
  mopt.working_memory = p.working_memory;
  // As sim_mode.cc: eq. 12's sigma_r^S, sigma_theta^S never below the regime's own noise.
  mopt.model = withSensorNoise(mopt.model, noise);
  const Map map = runMapping(sensor, se.poses, se.skipped, mopt).value();  // grid validated
  const Evaluation ev = evaluate(map, se.scene);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  Json row;
  row["grid"] = g.fingerprint;
  row["grid_index"] = index;
  row["grid_size"] = g.size();
  row["shard"] = shard;
  row["scene"] = se.arg;
  row["noise"] = noise.name;
  row["sigma_r"] = noise.sigma_r;
  row["sigma_phi"] = noise.sigma_phi;
  row["schedule_steps"] = p.schedule_steps;
  row["sweeps"] = p.sweeps;
  row["working_memory"] = p.working_memory;
  row["seed"] = p.seed;
  row["poses"] = map.stats.poses;
  row["shapelets"] = map.stats.shapelets;
  row["fused_tables"] = ev.fused_tables;
  row["true_tables"] = ev.true_tables;
  row["matched"] = ev.matched;
  row["precision"] = ev.precision;
  row["recall"] = ev.recall;
  row["f1"] = ev.f1;
  row["mean_position_error_m"] = ev.mean_position_error;
  row["mean_angle_error_rad"] = ev.mean_angle_error;
  row["per_pose_match_fraction"] = ev.per_pose_match_fraction;
  row["phantoms_near_walls"] = ev.phantoms_near_walls;
  row["phantoms_elsewhere"] = ev.phantoms_elsewhere;
  row["proposals"] = map.stats.proposals;
  row["peak_live_tables"] = map.stats.peak_live_tables;
  row["peak_live_legs"] = map.stats.peak_live_legs;
  row["wall_s"] = wall;
  row["process_peak_rss_kib"] = peakRssKib();
  return row;
}

std::string csvField(const Json& v) {
  if (!v.is_string()) return v.dump();
  const std::string s = v.get<std::string>();
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string q = "\"";
  for (const char c : s) {
    if (c == '"') q += '"';
    q += c;
  }
  return q + "\"";
}

std::string toCsv(const std::vector<Json>& rows) {
  std::string out;
  for (size_t c = 0; c < kSweepColumns.size(); ++c) out += (c ? "," : "") + kSweepColumns[c];
  out += "\n";
  for (const Json& row : rows) {
    for (size_t c = 0; c < kSweepColumns.size(); ++c) {
      if (c) out += ",";
      out += csvField(row.at(kSweepColumns[c]));
    }
    out += "\n";
  }
  return out;
}

std::string toJson(const std::vector<Json>& rows) {
  Json arr = Json::array();
  for (const Json& r : rows) arr.push_back(r);
  return arr.dump(1) + "\n";
}

int writeOutputs(const std::vector<Json>& rows, const std::string& out_dir, std::ostream& err) {
  if (auto s = ensureDirectory(out_dir); !s) {
    err << "crunchhost: " << s.error().message << "\n";
    return 1;
  }
  const std::string dir = out_dir + "/";
  if (auto s = writeFileAtomic(dir + "sweep.csv", toCsv(rows)); !s) {
    err << "crunchhost: " << s.error().message << "\n";
    return 1;
  }
  if (auto s = writeFileAtomic(dir + "sweep.json", toJson(rows)); !s) {
    err << "crunchhost: " << s.error().message << "\n";
    return 1;
  }
  return 0;
}

std::string formatDuration(double s) {
  if (!std::isfinite(s) || s < 0) return "?";
  const long t = std::lround(s);
  char buf[32];
  if (t >= 3600) std::snprintf(buf, sizeof buf, "%ldh%02ldm", t / 3600, (t / 60) % 60);
  else if (t >= 60) std::snprintf(buf, sizeof buf, "%ldm%02lds", t / 60, t % 60);
  else std::snprintf(buf, sizeof buf, "%lds", t);
  return buf;
}

class SweepProgress {
 public:
  SweepProgress(std::ostream& os, bool json, size_t total)
      : os_(os), json_(json), total_(total), t0_(std::chrono::steady_clock::now()) {}
  // Called with the mutex of the caller held.
  void completed(size_t done) {
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
    // Runs so far are the estimate of the rest: elapsed per run done times the runs left.
    const double left = done > 0 ? elapsed / static_cast<double>(done) *
                                       static_cast<double>(total_ - done)
                                 : NAN;
    if (json_) {
      Json j;
      j["event"] = "progress";
      j["done"] = done;
      j["total"] = total_;
      j["elapsed_s"] = elapsed;
      j["eta_s"] = left;
      os_ << j.dump() << "\n" << std::flush;
      return;
    }
    const size_t width = 30;
    const size_t filled = total_ > 0 ? done * width / total_ : width;
    os_ << "\r[" << std::string(filled, '#') << std::string(width - filled, ' ') << "] " << done
        << "/" << total_ << " runs, " << formatDuration(elapsed) << " elapsed, "
        << formatDuration(left) << " left   " << (done == total_ ? "\n" : "") << std::flush;
  }

 private:
  std::ostream& os_;
  bool json_;
  size_t total_;
  std::chrono::steady_clock::time_point t0_;
};

}  // namespace

int runSweep(const SweepOptions& opt, std::ostream& out, std::ostream& err) {
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<std::string> scene_texts;
  auto built = buildGrid(opt, scene_texts);
  if (!built) {
    err << "crunchhost sweep: " << built.error().message << "\n";
    return 2;
  }
  auto shard = parseShard(opt.shard);
  if (!shard) {
    err << "crunchhost sweep: " << shard.error().message << "\n";
    return 2;
  }
  int jobs = 0;
  if (!opt.jobs.empty()) {
    auto v = parseIntegers<int>(opt.jobs, "--jobs", 0);
    if (!v || v.value().size() != 1) {
      err << "crunchhost sweep: --jobs: '" << opt.jobs << "' is not a count >= 0 (0: one per core)\n";
      return 2;
    }
    jobs = v.value().front();
  }
  Grid& g = built.value();
  const auto [shard_i, shard_n] = shard.value();
  const std::string shard_name = std::to_string(shard_i) + "/" + std::to_string(shard_n);
  for (SceneEntry& e : g.scenes) {
    e.world = sim::World::build(e.scene);
    e.poses = e.world->reachablePoses(e.scene.poses, &e.skipped);
  }
  std::vector<size_t> indices;
  for (size_t i = 0; i < g.size(); ++i)
    if (i % static_cast<size_t>(shard_n) == static_cast<size_t>(shard_i)) indices.push_back(i);

  if (jobs == 0) jobs = static_cast<int>(std::thread::hardware_concurrency());
  jobs = std::max(1, std::min<int>(jobs, static_cast<int>(std::max<size_t>(1, indices.size()))));

  std::vector<Json> rows(indices.size());
  std::atomic<size_t> next{0};
  std::mutex done_mutex;
  size_t done = 0;
  std::string failure;
  SweepProgress progress(opt.json_progress ? out : err, opt.json_progress, indices.size());
  auto worker = [&] {
    for (;;) {
      const size_t k = next.fetch_add(1);
      if (k >= indices.size()) return;
      Json row;
      std::string what;
      try {
        row = runPoint(g, pointAt(g, indices[k]), indices[k], shard_name);
      } catch (const std::exception& e) {
        what = e.what();
      }
      std::lock_guard<std::mutex> lock(done_mutex);
      if (!what.empty() && failure.empty())
        failure = "grid point " + std::to_string(indices[k]) + ": " + what;
      rows[k] = std::move(row);
      progress.completed(++done);
    }
  };
  std::vector<std::thread> threads;
  for (int t = 1; t < jobs; ++t) threads.emplace_back(worker);
  worker();
  for (std::thread& t : threads) t.join();
  if (!failure.empty()) {
    err << "crunchhost sweep: " << failure << "\n";
    return 1;
  }
  if (const int code = writeOutputs(rows, opt.out_dir, err); code != 0) return code;
  const double total_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (opt.json_progress) {
    Json j;
    j["event"] = "done";
    j["runs"] = rows.size();
    j["grid_size"] = g.size();
    j["grid"] = g.fingerprint;
    j["shard"] = shard_name;
    j["wall_s"] = total_s;
    j["out"] = opt.out_dir;
    out << j.dump() << "\n";
  } else {
    out << "sweep " << g.fingerprint << ": " << rows.size() << " of " << g.size()
        << " grid points (shard " << shard_name << ") on " << jobs << " threads in "
        << formatDuration(total_s) << "; wrote " << opt.out_dir << "/{sweep.csv,sweep.json}\n";
  }
  return 0;
}

int runSweepMerge(const std::vector<std::string>& dirs, const std::string& out_dir,
                  std::ostream& out, std::ostream& err) {
  auto fail = [&](const std::string& why) {
    err << "crunchhost sweep-merge: " << why << "\n";
    return 2;
  };
  if (dirs.empty()) return fail("no shard directories given");
  std::optional<std::string> grid;
  std::optional<size_t> grid_size;
  std::string grid_from;
  std::vector<std::optional<Json>> slots;
  for (const std::string& dir : dirs) {
    const std::string path = dir + "/sweep.json";
    auto text = readFile(path);
    if (!text) return fail(text.error().message + " (not a sweep output directory)");
    Json arr = Json::parse(text.value(), nullptr, false);
    if (arr.is_discarded() || !arr.is_array()) return fail(path + ": not a JSON array");
    for (Json& row : arr) {
      bool ok = row.is_object() && row.size() == kSweepColumns.size();
      for (const std::string& c : kSweepColumns) ok = ok && row.contains(c);
      ok = ok && row["grid"].is_string() && row["grid_index"].is_number_unsigned() &&
           row["grid_size"].is_number_unsigned();
      if (!ok) return fail(path + ": a row is not a sweep row (columns differ)");
      const std::string fp = row["grid"].get<std::string>();
      const size_t size = row["grid_size"].get<size_t>();
      const size_t index = row["grid_index"].get<size_t>();
      if (!grid) {
        grid = fp;
        grid_size = size;
        grid_from = dir;
        slots.resize(size);
      }
      if (fp != *grid || size != *grid_size)
        return fail(dir + " is a shard of another grid (fingerprint " + fp + ", " +
                    std::to_string(size) + " points) than " + grid_from + " (" + *grid + ", " +
                    std::to_string(*grid_size) + " points)");
      if (index >= size) return fail(path + ": grid_index " + std::to_string(index) + " out of range");
      if (slots[index])
        return fail("grid point " + std::to_string(index) + " appears twice (again in " + dir + ")");
      slots[index] = std::move(row);
    }
  }
  if (!grid) return fail("the shards hold no rows");
  std::vector<Json> rows;
  std::vector<size_t> missing;
  for (size_t i = 0; i < slots.size(); ++i) {
    if (slots[i]) rows.push_back(*slots[i]);
    else missing.push_back(i);
  }
  if (!missing.empty()) {
    std::string list;
    for (size_t k = 0; k < std::min<size_t>(missing.size(), 10); ++k)
      list += (k ? ", " : "") + std::to_string(missing[k]);
    if (missing.size() > 10) list += ", ...";
    return fail(std::to_string(missing.size()) + " of " + std::to_string(slots.size()) +
                " grid points missing (" + list + "): is a shard left out?");
  }
  if (const int code = writeOutputs(rows, out_dir, err); code != 0) return code;
  out << "merged " << dirs.size() << " shards of grid " << *grid << ": " << rows.size()
      << " rows; wrote " << out_dir << "/{sweep.csv,sweep.json}\n";
  return 0;
}

}  // namespace crunch::app
