#include "crunch/mapping/sweep.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>

#include "crunch/core/atomic_file.h"
#include "crunch/core/json_input.h"

namespace crunch {

const std::vector<std::string> kSweepColumns = {
    "grid",           "grid_index",
    "grid_size",      "shard",
    "scene",          "model",
    "explore",        "noise",          "sigma_r",
    "sigma_phi",
    "schedule_steps",
    "sweeps",         "working_memory",
    "seed",           "poses",
    "shapelets",      "travel_m",
    "whisks",         "fused_tables",
    "true_tables",    "matched",
    "precision",      "recall",
    "f1",
    "mean_position_error_m",
    "mean_angle_error_rad",
    "per_pose_match_fraction",
    "phantoms_near_walls",
    "phantoms_elsewhere",
    "proposals",      "peak_live_tables",
    "peak_live_legs", "wall_s",
    "process_peak_rss_kib"};

const std::vector<std::string> kCurveColumns = {
    "grid_index", "scene",    "model",  "explore", "noise",     "seed",
    "whisk",      "travel_m", "whisks", "recall",  "precision", "f1",
    "run_travel_m", "run_recall", "run_f1"};

namespace {

using Json = nlohmann::ordered_json;

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

// An integer list with a default when the text is empty. Its range is MappingOptions::validate's
// (buildGrid checks every point), not this parser's: one place for each setting's range.
Status parseBudgets(const std::string& text, const std::string& option, int fallback,
                    std::vector<int>& out) {
  if (text.empty()) {
    out = {fallback};
    return okStatus();
  }
  auto v = parseIntegers<int>(text, option, std::numeric_limits<int>::min());
  if (!v) return v.error();
  out = v.value();
  return okStatus();
}

std::string formatNumber(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
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

Result<std::string> readFile(const std::string& path) { return readInputFile(path, "file"); }

Status loadScenes(const SweepGridSpec& spec, SweepGrid& g, std::vector<std::string>& texts) {
  const std::vector<std::string> args =
      spec.scenes.empty() ? std::vector<std::string>{"default"} : spec.scenes;
  for (const std::string& arg : args) {
    SweepScene e;
    e.arg = arg;
    if (arg == "default") {
      e.scene = defaultArena();
      texts.push_back("default");
    } else {
      auto loaded = loadScene(arg);
      if (!loaded) return Error{"--scene: " + loaded.error().message};
      e.scene = std::move(loaded).value();
      auto text = readFile(arg);
      if (!text) return Error{"--scene: " + text.error().message};
      texts.push_back(text.value());
    }
    g.scenes.push_back(std::move(e));
  }
  return okStatus();
}

Status parseModels(const SweepGridSpec& spec, SweepGrid& g) {
  if (spec.models.empty()) {  // crunchhost --sim's model (defaultMappingModel)
    g.models = {defaultMappingModel().objects};
    return okStatus();
  }
  auto names = splitList(spec.models, "--model");
  if (!names) return names.error();
  for (const std::string& n : names.value()) {
    auto model = objectModelByName(n);
    if (!model) return Error{"--" + model.error().message};
    if (std::find(g.models.begin(), g.models.end(), model.value()) != g.models.end())
      return Error{"--model: '" + n + "' appears twice"};
    g.models.push_back(model.value());
  }
  return okStatus();
}

// The names only: whether each is a policy is the exploration library's check
// (crunch_sim/sweep_run.h validateSweepExplore), which this layer cannot link.
Status parseExplore(const SweepGridSpec& spec, SweepGrid& g) {
  if (spec.explore.empty()) {
    g.explores = {"none"};
  } else {
    auto names = splitList(spec.explore, "--explore");
    if (!names) return names.error();
    for (const std::string& n : names.value()) {
      if (std::find(g.explores.begin(), g.explores.end(), n) != g.explores.end())
        return Error{"--explore: '" + n + "' appears twice"};
      g.explores.push_back(n);
    }
  }
  const bool any_policy =
      std::any_of(g.explores.begin(), g.explores.end(), [](const auto& n) { return n != "none"; });
  if (!spec.travel_budget.empty()) {
    if (!any_policy) return Error{"--travel-budget: needs --explore with a policy"};
    char* end = nullptr;
    const double v = std::strtod(spec.travel_budget.c_str(), &end);
    if (end != spec.travel_budget.c_str() + spec.travel_budget.size() || std::isnan(v))
      return Error{"--travel-budget: '" + spec.travel_budget + "' is not a number of metres"};
    g.travel_budget_m = v;
  }
  if (!spec.whisk_budget.empty()) {
    if (!any_policy) return Error{"--whisk-budget: needs --explore with a policy"};
    auto v = parseIntegers<int>(spec.whisk_budget, "--whisk-budget",
                                std::numeric_limits<int>::min());
    if (!v) return v.error();
    if (v.value().size() != 1) return Error{"--whisk-budget: one count, for every explore point"};
    g.whisk_budget = v.value().front();
  }
  return okStatus();
}

Status parseNoises(const SweepGridSpec& spec, SweepGrid& g) {
  if (!spec.noise.empty()) {
    auto names = splitList(spec.noise, "--noise");
    if (!names) return names.error();
    for (const std::string& n : names.value()) {
      auto regime = noiseRegimeByName(n);
      if (!regime) return Error{"--" + regime.error().message};
      g.noises.push_back(regime.value());
    }
  }
  if (!spec.noise_scale.empty()) {
    auto scales = parseScales(spec.noise_scale, "--noise-scale");
    if (!scales) return scales.error();
    const NoiseRegime r = NoiseRegime::realistic();
    for (const double s : scales.value()) {
      std::string name = "x";  // (not "x" + ...: GCC 12 warns -Wrestrict falsely on it here)
      name += formatNumber(s);
      g.noises.push_back({name, s * r.sigma_r, s * r.sigma_phi});
    }
  }
  if (g.noises.empty()) g.noises.push_back(NoiseRegime::realistic());
  for (size_t i = 0; i < g.noises.size(); ++i)
    for (size_t j = 0; j < i; ++j)
      if (g.noises[i].name == g.noises[j].name)
        return Error{"--noise: regime '" + g.noises[i].name + "' appears twice"};
  for (const NoiseRegime& n : g.noises)
    if (auto s = n.validate(); !s) return Error{"--noise-scale " + n.name + ": " + s.error().message};
  return okStatus();
}

Status parseSeeds(const SweepGridSpec& spec, SweepGrid& g) {
  if (!spec.seeds.empty() && !spec.seed_list.empty())
    return Error{"--seeds and --seed-list: give one of them"};
  if (!spec.seed_list.empty()) {
    auto v = parseIntegers<uint64_t>(spec.seed_list, "--seed-list", 0);
    if (!v) return v.error();
    g.seeds = v.value();
    return okStatus();
  }
  int n = 1;
  if (!spec.seeds.empty()) {
    auto v = parseIntegers<int>(spec.seeds, "--seeds", 1);
    if (!v) return v.error();
    if (v.value().size() != 1) return Error{"--seeds: one count N (seeds 1..N); a list is --seed-list"};
    n = v.value().front();
  }
  for (int s = 1; s <= n; ++s) g.seeds.push_back(static_cast<uint64_t>(s));
  return okStatus();
}

// The fingerprint: everything that decides a row except the binary itself.
std::string fingerprint(const SweepGrid& g, const std::vector<std::string>& scene_texts) {
  const SamplerOptions sampler_defaults;
  const MappingOptions mapping_defaults;
  std::ostringstream d;
  d.precision(17);
  d << "crunch.sweep/1\nsensor gaussian\n";
  for (size_t i = 0; i < g.scenes.size(); ++i)
    d << "scene " << g.scenes[i].arg << " " << hex64(fnv1a(scene_texts[i])) << "\n";
  // The object model line only when a model other than the paper's is swept: a paper-only grid
  // keeps the fingerprint it had before the axis existed.
  if (g.models != std::vector<ObjectModel>{ObjectModel::kPaper}) {
    d << "models";
    for (const ObjectModel m : g.models) d << " " << objectModelName(m);
    d << "\n";
  }
  // The explore line only with the axis: a grid without it keeps the fingerprint it had.
  if (g.explores != std::vector<std::string>{"none"}) {
    d << "explore";
    for (const std::string& e : g.explores) d << " " << e;
    d << " travel_budget " << g.travel_budget_m << " whisk_budget " << g.whisk_budget << "\n";
  }
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
  // Only when not the default, so that earlier sweeps' fingerprints stay valid.
  if (g.chain_fusion != ChainFusion::kVote)
    d << "chain_fusion " << chainFusionName(g.chain_fusion) << " "
      << mapping_defaults.marginal_steps << "\n";
  if (g.acceptance != Acceptance::kTempered) d << "acceptance " << acceptanceName(g.acceptance) << "\n";
  return hex64(fnv1a(d.str()));
}

// ---- Rows <-> JSON.

Json rowJson(const SweepRow& r) {
  const Evaluation& ev = r.accuracy;
  Json row;
  row["grid"] = r.grid;
  row["grid_index"] = r.grid_index;
  row["grid_size"] = r.grid_size;
  row["shard"] = r.shard;
  row["scene"] = r.scene;
  row["model"] = r.model;
  row["explore"] = r.explore;
  row["noise"] = r.noise;
  row["sigma_r"] = r.sigma_r;
  row["sigma_phi"] = r.sigma_phi;
  row["schedule_steps"] = r.schedule_steps;
  row["sweeps"] = r.sweeps;
  row["working_memory"] = r.working_memory;
  row["seed"] = r.seed;
  row["poses"] = r.poses;
  row["shapelets"] = r.shapelets;
  row["travel_m"] = r.travel_m;  // NaN ("none") is written as null
  row["whisks"] = r.whisks;
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
  row["proposals"] = r.proposals;
  row["peak_live_tables"] = r.peak_live_tables;
  row["peak_live_legs"] = r.peak_live_legs;
  row["wall_s"] = r.wall_s;
  row["process_peak_rss_kib"] = r.process_peak_rss_kib;
  return row;
}

// A number written by rowJson; null is how a non-finite double was written.
double number(const Json& v) {
  return v.is_null() ? std::numeric_limits<double>::quiet_NaN() : v.get<double>();
}

// The row back from its JSON object; throws nlohmann's type_error on a wrong type.
SweepRow rowFromJson(const Json& j) {
  SweepRow r;
  Evaluation& ev = r.accuracy;
  r.grid = j.at("grid").get<std::string>();
  r.grid_index = j.at("grid_index").get<std::size_t>();
  r.grid_size = j.at("grid_size").get<std::size_t>();
  r.shard = j.at("shard").get<std::string>();
  r.scene = j.at("scene").get<std::string>();
  r.model = j.at("model").get<std::string>();
  r.explore = j.at("explore").get<std::string>();
  r.noise = j.at("noise").get<std::string>();
  r.sigma_r = number(j.at("sigma_r"));
  r.sigma_phi = number(j.at("sigma_phi"));
  r.schedule_steps = j.at("schedule_steps").get<int>();
  r.sweeps = j.at("sweeps").get<int>();
  r.working_memory = j.at("working_memory").get<int>();
  r.seed = j.at("seed").get<std::uint64_t>();
  r.poses = j.at("poses").get<int>();
  r.shapelets = j.at("shapelets").get<int>();
  r.travel_m = number(j.at("travel_m"));
  r.whisks = j.at("whisks").get<int>();
  ev.fused_tables = j.at("fused_tables").get<int>();
  ev.true_tables = j.at("true_tables").get<int>();
  ev.matched = j.at("matched").get<int>();
  ev.precision = number(j.at("precision"));
  ev.recall = number(j.at("recall"));
  ev.f1 = number(j.at("f1"));
  ev.mean_position_error = number(j.at("mean_position_error_m"));
  ev.mean_angle_error = number(j.at("mean_angle_error_rad"));
  ev.per_pose_match_fraction = number(j.at("per_pose_match_fraction"));
  ev.phantoms_near_walls = j.at("phantoms_near_walls").get<int>();
  ev.phantoms_elsewhere = j.at("phantoms_elsewhere").get<int>();
  r.proposals = j.at("proposals").get<long long>();
  r.peak_live_tables = j.at("peak_live_tables").get<int>();
  r.peak_live_legs = j.at("peak_live_legs").get<int>();
  r.wall_s = number(j.at("wall_s"));
  r.process_peak_rss_kib = j.at("process_peak_rss_kib").get<long>();
  return r;
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

}  // namespace

std::size_t SweepGrid::size() const {
  return scenes.size() * models.size() * explores.size() * noises.size() * schedule_steps.size() * sweeps.size() *
         working_memory.size() * seeds.size();
}

SweepPoint SweepGrid::pointAt(std::size_t index) const {
  SweepPoint p;
  size_t i = index;
  p.seed = seeds[i % seeds.size()];
  i /= seeds.size();
  p.working_memory = working_memory[i % working_memory.size()];
  i /= working_memory.size();
  p.sweeps = sweeps[i % sweeps.size()];
  i /= sweeps.size();
  p.schedule_steps = schedule_steps[i % schedule_steps.size()];
  i /= schedule_steps.size();
  p.noise = i % noises.size();
  i /= noises.size();
  p.explore = explores[i % explores.size()];
  i /= explores.size();
  p.model = models[i % models.size()];
  i /= models.size();
  p.scene = i;
  return p;
}

MappingOptions SweepGrid::mappingOptions(const SweepPoint& p) const {
  MappingOptions mopt;
  mopt.seed = p.seed;
  mopt.model.objects = p.model;
  mopt.sampler.schedule_steps = p.schedule_steps;
  mopt.sampler.sweeps_per_temperature = p.sweeps;
  mopt.working_memory = p.working_memory;
  mopt.chain_fusion = chain_fusion;
  mopt.sampler.acceptance = acceptance;
  return mopt;
}

Result<SweepGrid> buildSweepGrid(const SweepGridSpec& spec) {
  SweepGrid g;
  std::vector<std::string> scene_texts;
  if (auto s = loadScenes(spec, g, scene_texts); !s) return s.error();
  if (auto s = parseModels(spec, g); !s) return s.error();
  if (auto s = parseExplore(spec, g); !s) return s.error();
  if (auto s = parseNoises(spec, g); !s) return s.error();
  const SamplerOptions sampler_defaults;
  const MappingOptions mapping_defaults;
  if (auto s = parseBudgets(spec.schedule_steps, "--schedule-steps",
                            sampler_defaults.schedule_steps, g.schedule_steps); !s)
    return s.error();
  if (auto s = parseBudgets(spec.sweeps, "--sweeps", sampler_defaults.sweeps_per_temperature,
                            g.sweeps); !s)
    return s.error();
  if (auto s = parseBudgets(spec.working_memory, "--working-memory",
                            mapping_defaults.working_memory, g.working_memory); !s)
    return s.error();
  // Every grid value through the library's own validation (one road in), named by its option
  // (each axis varies one field of MappingOptions, so checking each value checks every point;
  // the acceptance, which is valid only with some models, is checked with each model below).
  auto check = [](const std::string& option, const auto& values, auto set) -> Status {
    for (const int v : values) {
      MappingOptions mo;
      set(mo, v);
      if (auto s = mo.validate(); !s) return Error{option + ": " + s.error().message};
    }
    return okStatus();
  };
  if (auto s = check("--schedule-steps", g.schedule_steps,
                     [](MappingOptions& mo, int v) { mo.sampler.schedule_steps = v; });
      !s)
    return s.error();
  if (auto s = check("--sweeps", g.sweeps,
                     [](MappingOptions& mo, int v) { mo.sampler.sweeps_per_temperature = v; });
      !s)
    return s.error();
  if (auto s = check("--working-memory", g.working_memory,
                     [](MappingOptions& mo, int v) { mo.working_memory = v; });
      !s)
    return s.error();
  if (auto s = parseSeeds(spec, g); !s) return s.error();
  if (!spec.chain_fusion.empty()) {
    const auto f = chainFusionByName(spec.chain_fusion);
    if (!f) return Error{"--chain-fusion: " + f.error().message};
    g.chain_fusion = f.value();
  }
  if (!spec.acceptance.empty()) {
    const auto a = acceptanceByName(spec.acceptance);
    if (!a) return Error{"--acceptance: " + a.error().message};
    g.acceptance = a.value();
  }
  // The one setting checked against another axis: the acceptance with each object model.
  for (const ObjectModel m : g.models) {
    MappingOptions mo;
    mo.model.objects = m;
    mo.sampler.acceptance = g.acceptance;
    if (auto s = mo.validate(); !s) return Error{"--acceptance: " + s.error().message};
  }
  constexpr size_t kMaxGrid = 10'000'000;
  if (g.size() > kMaxGrid) return Error{"sweep: the grid has more than 10^7 points"};
  g.fingerprint = fingerprint(g, scene_texts);
  return g;
}

std::string SweepShard::name() const { return std::to_string(index) + "/" + std::to_string(count); }

bool SweepShard::holds(std::size_t grid_index) const {
  return grid_index % static_cast<size_t>(count) == static_cast<size_t>(index);
}

Result<SweepShard> parseSweepShard(const std::string& text) {
  if (text.empty()) return SweepShard{};
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
  return SweepShard{i, n};
}

Result<int> parseSweepJobs(const std::string& text) {
  if (text.empty()) return 0;
  auto v = parseIntegers<int>(text, "--jobs", 0);
  if (!v || v.value().size() != 1)
    return Error{"--jobs: '" + text + "' is not a count >= 0 (0: one per core)"};
  return v.value().front();
}

SweepRow sweepRow(const SweepGrid& g, std::size_t index, const SweepShard& shard,
                  const MapStats& stats, const Evaluation& accuracy, double wall_s,
                  long process_peak_rss_kib) {
  const SweepPoint p = g.pointAt(index);
  const NoiseRegime& noise = g.noises[p.noise];
  SweepRow r;
  r.grid = g.fingerprint;
  r.grid_index = index;
  r.grid_size = g.size();
  r.shard = shard.name();
  r.scene = g.scenes[p.scene].arg;
  r.model = objectModelName(p.model);
  r.explore = p.explore;
  r.noise = noise.name;
  r.sigma_r = noise.sigma_r;
  r.sigma_phi = noise.sigma_phi;
  r.schedule_steps = p.schedule_steps;
  r.sweeps = p.sweeps;
  r.working_memory = p.working_memory;
  r.seed = p.seed;
  r.poses = stats.poses;
  r.shapelets = stats.shapelets;
  r.whisks = stats.poses;
  r.accuracy = accuracy;
  r.proposals = stats.proposals;
  r.peak_live_tables = stats.peak_live_tables;
  r.peak_live_legs = stats.peak_live_legs;
  r.wall_s = wall_s;
  r.process_peak_rss_kib = process_peak_rss_kib;
  return r;
}

std::string sweepRowsCsv(const std::vector<SweepRow>& rows) {
  std::string out;
  for (size_t c = 0; c < kSweepColumns.size(); ++c) out += (c ? "," : "") + kSweepColumns[c];
  out += "\n";
  for (const SweepRow& r : rows) {
    const Json row = rowJson(r);
    for (size_t c = 0; c < kSweepColumns.size(); ++c) {
      if (c) out += ",";
      out += csvField(row.at(kSweepColumns[c]));
    }
    out += "\n";
  }
  return out;
}

std::string sweepRowsJson(const std::vector<SweepRow>& rows) {
  Json arr = Json::array();
  for (const SweepRow& r : rows) arr.push_back(rowJson(r));
  return arr.dump(1) + "\n";
}

namespace {

// The first column of `row` whose JSON type is not the writer's (a default row's, where a
// number may also be null: NaN), or "" when every type matches.
std::string mistypedColumn(const Json& row) {
  static const Json reference = Json::parse(sweepRowsJson({SweepRow{}}))[0];
  for (const std::string& c : kSweepColumns) {
    const Json& want = reference.at(c);
    const Json& got = row.at(c);
    const bool ok = want.is_string()              ? got.is_string()
                    : want.is_number_unsigned()   ? got.is_number_unsigned()
                    : want.is_number_integer()    ? got.is_number_integer()
                                                  : got.is_number() || got.is_null();
    if (!ok) return c;
  }
  return "";
}

// A row's values in the ranges the writer produces: the shard is "i/n" and holds the row's grid
// point, fractions in [0, 1] (or NaN: nothing to measure), counts and costs non-negative.
Status checkRowRanges(const SweepRow& r) {
  if (r.grid_size < 1 || r.grid_index >= r.grid_size)
    return Error{"grid_index: " + std::to_string(r.grid_index) + " is not a point of a grid of " +
                 std::to_string(r.grid_size)};
  auto shard = parseSweepShard(r.shard);
  if (!shard || r.shard.empty()) return Error{"shard: '" + r.shard + "' is not i/n"};
  if (r.grid_index % static_cast<size_t>(shard.value().count) !=
      static_cast<size_t>(shard.value().index))
    return Error{"shard: grid point " + std::to_string(r.grid_index) + " is not in shard " +
                 r.shard};
  const Evaluation& e = r.accuracy;
  const std::pair<const char*, double> fractions[] = {
      {"precision", e.precision}, {"recall", e.recall}, {"f1", e.f1},
      {"per_pose_match_fraction", e.per_pose_match_fraction}};
  for (const auto& [name, v] : fractions)
    if (!std::isnan(v) && !(v >= 0.0 && v <= 1.0))
      return Error{std::string(name) + ": " + std::to_string(v) + " is not in [0, 1]"};
  const std::pair<const char*, double> nonnegative[] = {
      {"sigma_r", r.sigma_r},
      {"sigma_phi", r.sigma_phi},
      {"travel_m", std::isnan(r.travel_m) ? 0.0 : r.travel_m},
      {"mean_position_error_m", std::isnan(e.mean_position_error) ? 0.0 : e.mean_position_error},
      {"mean_angle_error_rad", std::isnan(e.mean_angle_error) ? 0.0 : e.mean_angle_error},
      {"wall_s", r.wall_s},
      {"schedule_steps", r.schedule_steps},
      {"sweeps", r.sweeps},
      {"working_memory", r.working_memory},
      {"poses", r.poses},
      {"shapelets", r.shapelets},
      {"whisks", r.whisks},
      {"fused_tables", e.fused_tables},
      {"true_tables", e.true_tables},
      {"matched", e.matched},
      {"phantoms_near_walls", e.phantoms_near_walls},
      {"phantoms_elsewhere", e.phantoms_elsewhere},
      {"proposals", static_cast<double>(r.proposals)},
      {"peak_live_tables", r.peak_live_tables},
      {"peak_live_legs", r.peak_live_legs},
      {"process_peak_rss_kib", static_cast<double>(r.process_peak_rss_kib)}};
  for (const auto& [name, v] : nonnegative)
    if (!(v >= 0.0 && std::isfinite(v)))
      return Error{std::string(name) + ": " + std::to_string(v) + " is not a finite number >= 0"};
  if (e.matched > e.fused_tables || e.matched > e.true_tables)
    return Error{"matched: " + std::to_string(e.matched) + " is more than fused_tables or "
                 "true_tables"};
  return okStatus();
}

}  // namespace

Result<std::vector<SweepRow>> parseSweepRows(const std::string& text, const std::string& source) {
  if (auto st = checkStrictJson(text, source); !st) return st.error();
  const Json arr = Json::parse(text, nullptr, false);
  if (arr.is_discarded() || !arr.is_array()) return Error{source + ": not a JSON array"};
  std::vector<SweepRow> rows;
  for (size_t k = 0; k < arr.size(); ++k) {
    const Json& row = arr[k];
    const std::string where = source + ": row " + std::to_string(k + 1);
    bool ok = row.is_object() && row.size() == kSweepColumns.size();
    for (const std::string& c : kSweepColumns) ok = ok && row.contains(c);
    if (!ok) return Error{where + ": not a sweep row (its columns differ from sweep.json's)"};
    if (const std::string c = mistypedColumn(row); !c.empty())
      return Error{where + ": " + c + ": not the type sweep.json gives it"};
    try {
      rows.push_back(rowFromJson(row));
    } catch (const nlohmann::json::exception&) {  // a number out of its type's range
      return Error{where + ": a value does not fit its column"};
    }
    if (Status st = checkRowRanges(rows.back()); !st)
      return Error{where + ": " + st.error().message};
  }
  return rows;
}

namespace {

// One curves.csv line into fields (the writer quotes a field holding a comma or a quote).
std::vector<std::string> csvLineFields(const std::string& line) {
  std::vector<std::string> out(1);
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted && c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
      out.back() += '"';
      ++i;
    } else if (c == '"') {
      quoted = !quoted;
    } else if (c == ',' && !quoted) {
      out.emplace_back();
    } else {
      out.back() += c;
    }
  }
  return out;
}

// A shard's curves.csv back into the curves of its rows (by grid_index). Errors name the file.
Status readShardCurves(const std::string& dir, std::vector<std::optional<SweepRow>>& slots) {
  const std::string path = dir + "/curves.csv";
  auto text = readFile(path);
  if (!text) return Error{text.error().message + " (an explore shard writes one)"};
  std::istringstream in(text.value());
  std::string line, header;
  for (size_t c = 0; c < kCurveColumns.size(); ++c) header += (c ? "," : "") + kCurveColumns[c];
  if (!std::getline(in, line) || line != header)
    return Error{path + ": line 1 is not curves.csv's header"};
  for (int n = 2; std::getline(in, line); ++n) {
    if (line.empty()) continue;
    const std::vector<std::string> f = csvLineFields(line);
    const std::string where = path + ": line " + std::to_string(n);
    if (f.size() != kCurveColumns.size()) return Error{where + ": not " + std::to_string(kCurveColumns.size()) + " fields"};
    try {
      const size_t index = std::stoul(f[0]);
      if (index >= slots.size() || !slots[index])
        return Error{where + ": grid_index " + f[0] + " is not a row of its sweep.json"};
      auto num = [](const std::string& s) {
        return s == "null" ? std::numeric_limits<double>::quiet_NaN() : std::stod(s);
      };
      slots[index]->curve.push_back(
          {num(f[7]), std::stoi(f[8]), num(f[9]), num(f[10]), num(f[11])});
    } catch (const std::exception&) {
      return Error{where + ": a number column does not read"};
    }
  }
  return okStatus();
}

}  // namespace

Result<std::vector<SweepRow>> mergeSweepShards(const std::vector<std::string>& dirs) {
  if (dirs.empty()) return Error{"no shard directories given"};
  std::optional<std::string> grid;
  std::optional<size_t> grid_size;
  std::string grid_from;
  std::optional<int> shard_count;
  std::string shard_from;
  std::vector<std::optional<SweepRow>> slots;
  std::vector<std::string> explored_dirs;
  for (const std::string& dir : dirs) {
    const std::string path = dir + "/sweep.json";
    auto text = readFile(path);
    if (!text) return Error{text.error().message + " (not a sweep output directory)"};
    auto parsed = parseSweepRows(text.value(), path);
    if (!parsed) return parsed.error();
    if (std::any_of(parsed.value().begin(), parsed.value().end(),
                    [](const SweepRow& r) { return r.explore != "none"; }))
      explored_dirs.push_back(dir);
    for (SweepRow& row : parsed.value()) {
      if (!grid) {
        grid = row.grid;
        grid_size = row.grid_size;
        grid_from = dir;
        slots.resize(row.grid_size);
      }
      if (row.grid != *grid || row.grid_size != *grid_size)
        return Error{dir + " is a shard of another grid (fingerprint " + row.grid + ", " +
                     std::to_string(row.grid_size) + " points) than " + grid_from + " (" + *grid +
                     ", " + std::to_string(*grid_size) + " points)"};
      // Shards of one sweep split the grid the same way: 0/2 and 1/3 are not parts of one run.
      const int count = parseSweepShard(row.shard).value().count;  // parseSweepRows checked it
      if (!shard_count) {
        shard_count = count;
        shard_from = dir;
      }
      if (count != *shard_count)
        return Error{dir + ": shard " + row.shard + " is one of " + std::to_string(count) +
                     " shards, " + shard_from + "'s are of " + std::to_string(*shard_count) +
                     ": not parts of the same sweep"};
      const size_t index = row.grid_index;
      if (index >= row.grid_size)
        return Error{path + ": grid_index " + std::to_string(index) + " out of range"};
      if (slots[index])
        return Error{"grid point " + std::to_string(index) + " appears twice (again in " + dir + ")"};
      slots[index] = std::move(row);
    }
  }
  // The explore rows' curves: every shard that holds an explore row has its curves.csv.
  for (const std::string& dir : explored_dirs)
    if (Status st = readShardCurves(dir, slots); !st) return st.error();
  if (!grid) return Error{"the shards hold no rows"};
  std::vector<SweepRow> rows;
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
    return Error{std::to_string(missing.size()) + " of " + std::to_string(slots.size()) +
                 " grid points missing (" + list + "): is a shard left out?"};
  }
  return rows;
}

std::string sweepCurvesCsv(const std::vector<SweepRow>& rows) {
  std::string out;
  for (size_t c = 0; c < kCurveColumns.size(); ++c) out += (c ? "," : "") + kCurveColumns[c];
  out += "\n";
  for (const SweepRow& r : rows) {
    for (size_t k = 0; k < r.curve.size(); ++k) {
      const SweepCurvePoint& p = r.curve[k];
      Json v = Json::array({r.grid_index, r.scene, r.model, r.explore, r.noise, r.seed, k,
                            p.travel_m, p.whisks, p.recall, p.precision, p.f1, r.travel_m,
                            r.accuracy.recall, r.accuracy.f1});
      for (size_t c = 0; c < v.size(); ++c) {
        if (c) out += ',';
        out += csvField(v[c]);
      }
      out += "\n";
    }
  }
  return out;
}

Status writeSweepFiles(const std::vector<SweepRow>& rows, const std::string& out_dir) {
  if (auto s = ensureDirectory(out_dir); !s) return s;
  const std::string dir = out_dir + "/";
  if (auto s = writeFileAtomic(dir + "sweep.csv", sweepRowsCsv(rows)); !s) return s;
  if (auto s = writeFileAtomic(dir + "sweep.json", sweepRowsJson(rows)); !s) return s;
  const bool explored =
      std::any_of(rows.begin(), rows.end(), [](const SweepRow& r) { return r.explore != "none"; });
  if (!explored) return okStatus();
  return writeFileAtomic(dir + "curves.csv", sweepCurvesCsv(rows));
}

}  // namespace crunch
