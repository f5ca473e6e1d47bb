#include "crunch/mapping/sweep_statistics.h"
#include "crunch/core/json_input.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <tuple>

namespace crunch {

const std::vector<std::string> kSweepChartColumns = {
    "scene",     "noise",  "sigma_r", "schedule_steps", "sweeps", "working_memory", "seed",
    "precision", "recall", "f1",      "proposals",      "wall_s"};

namespace {

using Json = nlohmann::json;

struct Acc {
  SettingSummary s;
  std::vector<double> f1, recall, precision, wall, proposals;
};

double mean(const std::vector<double>& v) {
  double sum = 0.0;
  for (const double x : v) sum += x;
  return v.empty() ? 0.0 : sum / static_cast<double>(v.size());
}

double sd(const std::vector<double>& v) {
  if (v.size() < 2) return 0.0;
  const double m = mean(v);
  double ss = 0.0;
  for (const double x : v) ss += (x - m) * (x - m);
  return std::sqrt(ss / static_cast<double>(v.size() - 1));
}

std::string fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

// The row's columns present with the right types; an Error naming row and column otherwise.
Status checkRow(const Json& row, const std::string& where) {
  if (!row.is_object()) return Error{where + " is not an object"};
  for (const std::string& col : kSweepChartColumns) {
    const auto it = row.find(col);
    if (it == row.end()) return Error{where + " has no column '" + col + "'"};
    const bool text = col == "scene" || col == "noise";
    const bool integer =
        col == "schedule_steps" || col == "sweeps" || col == "working_memory" || col == "seed";
    const bool ok = text      ? it->is_string()
                    : integer ? it->is_number_integer()
                              : it->is_number() && std::isfinite(it->get<double>());
    if (!ok) {
      return Error{where + ": column '" + col + "' must be " +
                   (text ? "a string" : integer ? "an integer" : "a finite number")};
    }
  }
  if (const auto it = row.find("model"); it != row.end() && !it->is_string())
    return Error{where + ": column 'model' must be a string"};
  return okStatus();
}

SettingSummary summarise(const Acc& a) {
  SettingSummary s = a.s;
  s.runs = static_cast<int>(a.f1.size());
  s.f1_mean = mean(a.f1);
  s.f1_sd = sd(a.f1);
  s.recall_mean = mean(a.recall);
  s.recall_sd = sd(a.recall);
  s.precision_mean = mean(a.precision);
  s.precision_sd = sd(a.precision);
  s.wall_s_mean = mean(a.wall);
  s.proposals_mean = mean(a.proposals);
  return s;
}

}  // namespace

std::string settingName(const SettingSummary& s) {
  return (s.model == "paper" ? std::string() : s.model + ": ") + std::to_string(s.schedule_steps) + " T x " + std::to_string(s.sweeps) + " sweep" +
         (s.sweeps == 1 ? "" : "s") + ", WM " + std::to_string(s.working_memory);
}

Result<std::vector<SettingSummary>> loadSweepSummary(const std::string& path) {
  auto text = readInputFile(path, "sweep rows (missing? run `crunchhost sweep --out DIR` first)");
  if (!text) return text.error();
  auto parsed = parseStrictJson(text.value(), path);
  if (!parsed) return parsed.error();
  const Json rows = std::move(parsed.value());
  if (!rows.is_array()) return Error{path + ": not a JSON array of sweep rows"};
  if (rows.empty()) return Error{path + ": has no rows"};
  std::vector<Acc> acc;
  for (size_t r = 0; r < rows.size(); ++r) {
    const Json& row = rows[r];
    const std::string where = path + ": row " + std::to_string(r);
    if (auto st = checkRow(row, where); !st) return st.error();
    SettingSummary key;
    key.scene = row["scene"].get<std::string>();
    if (row.contains("model")) key.model = row["model"].get<std::string>();
    key.noise = row["noise"].get<std::string>();
    key.sigma_r = row["sigma_r"].get<double>();
    key.schedule_steps = row["schedule_steps"].get<int>();
    key.sweeps = row["sweeps"].get<int>();
    key.working_memory = row["working_memory"].get<int>();
    if (!acc.empty() && key.scene != acc.front().s.scene) {
      return Error{where + " is of scene '" + key.scene + "' but row 0 of '" +
                   acc.front().s.scene + "': sweep-chart draws one scene per sweep.json"};
    }
    auto it = std::find_if(acc.begin(), acc.end(), [&](const Acc& a) {
      return a.s.model == key.model && a.s.noise == key.noise && a.s.schedule_steps == key.schedule_steps &&
             a.s.sweeps == key.sweeps && a.s.working_memory == key.working_memory;
    });
    if (it == acc.end()) {
      acc.push_back(Acc{key, {}, {}, {}, {}, {}});
      it = acc.end() - 1;
    }
    it->f1.push_back(row["f1"].get<double>());
    it->recall.push_back(row["recall"].get<double>());
    it->precision.push_back(row["precision"].get<double>());
    it->wall.push_back(row["wall_s"].get<double>());
    it->proposals.push_back(row["proposals"].get<double>());
  }
  std::vector<SettingSummary> out;
  for (const Acc& a : acc) out.push_back(summarise(a));
  return out;
}

std::vector<size_t> paretoFront(const std::vector<double>& cost,
                                const std::vector<double>& accuracy) {
  std::vector<size_t> front;
  const size_t n = std::min(cost.size(), accuracy.size());
  auto finite = [&](size_t i) { return std::isfinite(cost[i]) && std::isfinite(accuracy[i]); };
  for (size_t i = 0; i < n; ++i) {
    if (!finite(i)) continue;
    bool beaten = false;
    for (size_t j = 0; j < n && !beaten; ++j) {
      if (j == i || !finite(j)) continue;
      beaten = cost[j] <= cost[i] && accuracy[j] >= accuracy[i] &&
               (cost[j] < cost[i] || accuracy[j] > accuracy[i]);
    }
    if (!beaten) front.push_back(i);
  }
  std::sort(front.begin(), front.end(), [&](size_t a, size_t b) {
    return cost[a] != cost[b] ? cost[a] < cost[b] : accuracy[a] < accuracy[b];
  });
  return front;
}

std::vector<NoiseFronts> sweepFronts(const std::vector<SettingSummary>& all) {
  std::vector<NoiseFronts> out;
  for (size_t i = 0; i < all.size(); ++i) {
    auto it = std::find_if(out.begin(), out.end(), [&](const NoiseFronts& f) {
      return f.model == all[i].model && f.noise == all[i].noise;
    });
    if (it == out.end()) {
      out.push_back({all[i].model, all[i].noise, {}, {}, {}});
      it = out.end() - 1;
    }
    it->settings.push_back(i);
  }
  for (NoiseFronts& f : out) {
    std::vector<double> wall, props, f1;
    for (const size_t i : f.settings) {
      wall.push_back(all[i].wall_s_mean);
      props.push_back(all[i].proposals_mean);
      f1.push_back(all[i].f1_mean);
    }
    for (const size_t k : paretoFront(wall, f1)) f.wall_front.push_back(f.settings[k]);
    for (const size_t k : paretoFront(props, f1)) f.proposals_front.push_back(f.settings[k]);
  }
  return out;
}

std::vector<std::string> sweepModels(const std::vector<SettingSummary>& all) {
  std::vector<std::string> models;
  for (const SettingSummary& s : all)
    if (std::find(models.begin(), models.end(), s.model) == models.end()) models.push_back(s.model);
  return models;
}

std::vector<SettingSummary> noiseLevels(const std::vector<SettingSummary>& every,
                                        const std::string& model) {
  std::vector<SettingSummary> all;
  for (const SettingSummary& s : every)
    if (s.model == model) all.push_back(s);
  if (all.empty()) return {};
  std::vector<double> sigmas;
  for (const SettingSummary& s : all) {
    if (std::find(sigmas.begin(), sigmas.end(), s.sigma_r) == sigmas.end()) {
      sigmas.push_back(s.sigma_r);
    }
  }
  if (sigmas.size() < 2) return {};
  auto levels = [&](const SettingSummary& pick) {
    std::vector<SettingSummary> v;
    for (const SettingSummary& s : all) {
      if (s.schedule_steps == pick.schedule_steps && s.sweeps == pick.sweeps &&
          s.working_memory == pick.working_memory) {
        v.push_back(s);
      }
    }
    std::stable_sort(v.begin(), v.end(), [](const SettingSummary& a, const SettingSummary& b) {
      return a.sigma_r < b.sigma_r;
    });
    return v;
  };
  std::vector<SettingSummary> by_sigma;
  for (const SettingSummary& s : all) {
    if (s.schedule_steps == kPaperScheduleSteps && s.sweeps == kPaperSweeps &&
        s.working_memory == kPaperWorkingMemory) {
      by_sigma = levels(s);
      break;
    }
  }
  if (by_sigma.size() < 2) by_sigma = levels(all.front());
  if (by_sigma.size() < 2) return {};
  return by_sigma;
}

std::string sweepSummaryCsv(const std::vector<SettingSummary>& all,
                            const std::vector<NoiseFronts>& fronts) {
  std::vector<bool> on_wall(all.size(), false), on_props(all.size(), false);
  for (const NoiseFronts& f : fronts) {
    for (const size_t i : f.wall_front) on_wall[i] = true;
    for (const size_t i : f.proposals_front) on_props[i] = true;
  }
  std::ostringstream o;
  o << "scene,model,noise,sigma_r_mm,schedule_steps,sweeps,working_memory,runs,f1_mean,f1_sd,"
       "recall_mean,recall_sd,precision_mean,precision_sd,wall_s_mean,proposals_mean,"
       "on_front_wall_s,on_front_proposals\n";
  for (size_t i = 0; i < all.size(); ++i) {
    const SettingSummary& s = all[i];
    o << s.scene << "," << s.model << "," << s.noise << "," << fmt("%g", s.sigma_r * 1e3) << "," << s.schedule_steps
      << "," << s.sweeps << "," << s.working_memory << "," << s.runs << ","
      << fmt("%.4f", s.f1_mean) << "," << fmt("%.4f", s.f1_sd) << ","
      << fmt("%.4f", s.recall_mean) << "," << fmt("%.4f", s.recall_sd) << ","
      << fmt("%.4f", s.precision_mean) << "," << fmt("%.4f", s.precision_sd) << ","
      << fmt("%.4f", s.wall_s_mean) << "," << fmt("%.0f", s.proposals_mean) << ","
      << (on_wall[i] ? 1 : 0) << "," << (on_props[i] ? 1 : 0) << "\n";
  }
  return o.str();
}

// ---- Exploration curves.

namespace {

// One CSV line into fields (RFC 4180 quotes: "a,b" and "" inside quotes).
std::vector<std::string> csvFields(const std::string& line) {
  std::vector<std::string> out;
  std::string f;
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        f += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        f += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      out.push_back(f);
      f.clear();
    } else {
      f += c;
    }
  }
  out.push_back(f);
  return out;
}

bool parseDouble(const std::string& s, double& v) {
  if (s.empty()) return false;
  char* end = nullptr;
  v = std::strtod(s.c_str(), &end);
  return end == s.c_str() + s.size();
}

double interpolateCurve(const ExploreCurve& c, const std::vector<double>& value, double at) {
  return curveValueAt(c.travel_m, value, at);
}

// The first travel at which `value` (on `travel`) reaches `target`; NaN if never.
double firstReach(const std::vector<double>& travel, const std::vector<double>& value,
                  double target) {
  for (size_t i = 0; i < value.size(); ++i)
    if (value[i] >= target) return travel[i];
  return std::numeric_limits<double>::quiet_NaN();
}

}  // namespace

Result<std::vector<ExploreCurve>> parseExploreCurves(const std::string& text,
                                                     const std::string& source) {
  std::istringstream in(text);
  std::string line;
  if (!std::getline(in, line)) return Error{source + ": empty (no header line)"};
  if (!line.empty() && line.back() == '\r') line.pop_back();
  const std::vector<std::string> header = csvFields(line);
  const char* needed[] = {"scene", "model", "explore", "noise",    "seed",
                          "travel_m", "whisks", "recall", "precision", "f1"};
  std::vector<size_t> col;
  for (const char* name : needed) {
    const auto it = std::find(header.begin(), header.end(), name);
    if (it == header.end())
      return Error{source + ": line 1 (header) has no column '" + std::string(name) + "'"};
    col.push_back(static_cast<size_t>(it - header.begin()));
  }
  std::optional<size_t> run_col;  // optional: curves.csv before the column
  if (const auto it = std::find(header.begin(), header.end(), "run_travel_m"); it != header.end())
    run_col = static_cast<size_t>(it - header.begin());
  auto optionalColumn = [&](const char* name) -> std::optional<size_t> {
    const auto it = std::find(header.begin(), header.end(), name);
    if (it == header.end()) return std::nullopt;
    return static_cast<size_t>(it - header.begin());
  };
  const std::optional<size_t> recall_col = optionalColumn("run_recall");
  const std::optional<size_t> f1_col = optionalColumn("run_f1");
  std::vector<ExploreCurve> curves;
  for (int n = 2; std::getline(in, line); ++n) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    const std::vector<std::string> f = csvFields(line);
    const std::string where = source + ": line " + std::to_string(n);
    if (f.size() != header.size())
      return Error{where + " has " + std::to_string(f.size()) + " fields, the header " +
                   std::to_string(header.size())};
    auto num = [&](int k, double& v, bool unit, bool may_be_empty) -> Status {
      const std::string& t = f[col[k]];
      if (may_be_empty && (t.empty() || t == "null")) {
        v = std::numeric_limits<double>::quiet_NaN();
        return okStatus();
      }
      if (!parseDouble(t, v) || !std::isfinite(v) || v < 0 || (unit && v > 1))
        return Error{where + ": column '" + std::string(needed[k]) + "' must be " +
                     (unit ? "a number in [0, 1]" : "a finite number >= 0") + ", not '" + t + "'"};
      return okStatus();
    };
    double seed = 0, travel = 0, whisks = 0, recall = 0, precision = 0, f1 = 0;
    for (const auto& [k, v, unit, empty] :
         {std::tuple<int, double*, bool, bool>{4, &seed, false, false},
          {5, &travel, false, false},
          {6, &whisks, false, false},
          {7, &recall, true, false},
          {8, &precision, true, true},
          {9, &f1, true, false}}) {
      if (Status st = num(k, *v, unit, empty); !st) return st.error();
    }
    ExploreCurve key;
    key.scene = f[col[0]];
    key.model = f[col[1]];
    key.explore = f[col[2]];
    key.noise = f[col[3]];
    key.seed = static_cast<std::uint64_t>(seed);
    auto it = std::find_if(curves.begin(), curves.end(), [&](const ExploreCurve& c) {
      return c.scene == key.scene && c.model == key.model && c.explore == key.explore &&
             c.noise == key.noise && c.seed == key.seed;
    });
    if (it == curves.end()) {
      curves.push_back(key);
      it = curves.end() - 1;
    }
    if (run_col) {
      double run = 0;
      const std::string& t = f[*run_col];
      if (!parseDouble(t, run) || !std::isfinite(run) || run < 0)
        return Error{where + ": column 'run_travel_m' must be a finite number >= 0, not '" + t +
                     "'"};
      it->run_travel_m = run;
    }
    for (const auto& [col_index, out] :
         {std::pair<std::optional<size_t>, double*>{recall_col, &it->run_recall},
          {f1_col, &it->run_f1}}) {
      if (!col_index) continue;
      double v = 0;
      const std::string& t = f[*col_index];
      if (!parseDouble(t, v) || !std::isfinite(v) || v < 0 || v > 1)
        return Error{where + ": columns 'run_recall' and 'run_f1' must be numbers in [0, 1], not '" +
                     t + "'"};
      *out = v;
    }
    if (!it->travel_m.empty() && travel < it->travel_m.back())
      return Error{where + ": column 'travel_m' goes down within a run (" + fmt("%g", travel) +
                   " after " + fmt("%g", it->travel_m.back()) + ")"};
    it->travel_m.push_back(travel);
    it->whisks.push_back(static_cast<int>(whisks));
    it->recall.push_back(recall);
    it->precision.push_back(precision);
    it->f1.push_back(f1);
    if (!run_col) it->run_travel_m = travel;
  }
  for (const ExploreCurve& c : curves)
    if (c.run_travel_m < c.travel_m.back())
      return Error{source + ": run " + c.explore + " seed " + std::to_string(c.seed) + " of " +
                   c.scene + ": run_travel_m " + fmt("%g", c.run_travel_m) +
                   " is below its last whisk's travel_m " + fmt("%g", c.travel_m.back())};
  return curves;
}

Result<std::vector<ExploreCurve>> loadExploreCurves(const std::string& path) {
  auto text =
      readInputFile(path, "curves (missing? run `crunchhost sweep --explore ... --out DIR`)");
  if (!text) return text.error();
  auto curves = parseExploreCurves(text.value(), path);
  if (!curves) return curves.error();
  if (curves.value().empty()) return Error{path + ": has no curve point"};
  return curves;
}

double curveValueAt(const std::vector<double>& travel, const std::vector<double>& value,
                    double at) {
  // The last whisk at or before `at`: upper_bound finds the first point beyond it.
  const auto it = std::upper_bound(travel.begin(), travel.end(), at);
  if (it == travel.begin()) return 0.0;
  return value[static_cast<size_t>(it - travel.begin()) - 1];
}

std::vector<ExploreSummary> exploreSummaries(const std::vector<ExploreCurve>& curves, int samples,
                                             double recall_target) {
  samples = std::max(samples, 2);
  std::vector<ExploreSummary> out;
  std::vector<bool> done(curves.size(), false);
  for (size_t g = 0; g < curves.size(); ++g) {
    if (done[g]) continue;
    // The (scene, model, noise) group of curve g: its common travel axis.
    const ExploreCurve& head = curves[g];
    auto same_group = [&](const ExploreCurve& c) {
      return c.scene == head.scene && c.model == head.model && c.noise == head.noise;
    };
    double longest = 0.0;
    for (const ExploreCurve& c : curves)
      if (same_group(c)) longest = std::max(longest, c.run_travel_m);
    if (longest <= 0.0) longest = 1.0;  // only whisks at the start: any axis shows them
    std::vector<double> axis(static_cast<size_t>(samples));
    for (int i = 0; i < samples; ++i) axis[static_cast<size_t>(i)] = longest * i / (samples - 1);
    for (size_t p = g; p < curves.size(); ++p) {
      if (done[p] || !same_group(curves[p])) continue;
      // Every seed of policy curves[p].explore in this group.
      std::vector<const ExploreCurve*> runs;
      for (size_t k = p; k < curves.size(); ++k) {
        if (!done[k] && same_group(curves[k]) && curves[k].explore == curves[p].explore) {
          runs.push_back(&curves[k]);
          done[k] = true;
        }
      }
      ExploreSummary s;
      s.scene = head.scene;
      s.model = head.model;
      s.noise = head.noise;
      s.explore = curves[p].explore;
      s.runs = static_cast<int>(runs.size());
      s.travel = axis;
      s.recall_target = recall_target;
      std::vector<double> r(runs.size()), f(runs.size());
      for (const double t : axis) {
        for (size_t k = 0; k < runs.size(); ++k) {
          r[k] = interpolateCurve(*runs[k], runs[k]->recall, t);
          f[k] = interpolateCurve(*runs[k], runs[k]->f1, t);
        }
        s.recall_mean.push_back(mean(r));
        s.recall_sd.push_back(sd(r));
        s.f1_mean.push_back(mean(f));
        s.f1_sd.push_back(sd(f));
      }
      std::vector<double> travel, whisks, recall, f1, reach, map_recall, map_f1;
      for (const ExploreCurve* c : runs) {
        const bool any = !c->travel_m.empty();
        travel.push_back(c->run_travel_m);
        map_recall.push_back(c->run_recall);
        map_f1.push_back(c->run_f1);
        whisks.push_back(any ? c->whisks.back() : 0.0);
        recall.push_back(any ? c->recall.back() : 0.0);
        f1.push_back(any ? c->f1.back() : 0.0);
        const double t = firstReach(c->travel_m, c->recall, recall_target);
        if (std::isfinite(t)) reach.push_back(t);
      }
      s.final_travel_mean = mean(travel);
      s.final_whisks_mean = mean(whisks);
      s.final_recall_mean = mean(recall);
      s.final_recall_sd = sd(recall);
      s.final_f1_mean = mean(f1);
      s.final_f1_sd = sd(f1);
      s.map_recall_mean = mean(map_recall);  // NaN when a run lacks it
      s.map_recall_sd = sd(map_recall);
      s.map_f1_mean = mean(map_f1);
      s.map_f1_sd = sd(map_f1);
      s.reached = static_cast<int>(reach.size());
      s.travel_to_target_mean =
          reach.empty() ? std::numeric_limits<double>::quiet_NaN() : mean(reach);
      s.mean_curve_travel_to_target = firstReach(s.travel, s.recall_mean, recall_target);
      out.push_back(std::move(s));
    }
  }
  return out;
}

std::string exploreSummaryCsv(const std::vector<ExploreSummary>& all) {
  std::ostringstream o;
  o << "scene,model,noise,explore,runs,run_travel_m_mean,whisks_mean,recall_mean,recall_sd,f1_mean,"
       "f1_sd,recall_target,seeds_reaching_target,travel_to_target_mean_m,"
       "mean_curve_travel_to_target_m,map_recall_mean,map_recall_sd,map_f1_mean,map_f1_sd\n";
  auto num = [](double v, const char* f) { return std::isfinite(v) ? fmt(f, v) : std::string(); };
  for (const ExploreSummary& s : all) {
    o << s.scene << "," << s.model << "," << s.noise << "," << s.explore << "," << s.runs << ","
      << num(s.final_travel_mean, "%.2f") << "," << num(s.final_whisks_mean, "%.1f") << ","
      << num(s.final_recall_mean, "%.4f") << "," << num(s.final_recall_sd, "%.4f") << ","
      << num(s.final_f1_mean, "%.4f") << "," << num(s.final_f1_sd, "%.4f") << ","
      << fmt("%g", s.recall_target) << "," << s.reached << ","
      << num(s.travel_to_target_mean, "%.2f") << "," << num(s.mean_curve_travel_to_target, "%.2f")
      << "," << num(s.map_recall_mean, "%.4f") << "," << num(s.map_recall_sd, "%.4f") << ","
      << num(s.map_f1_mean, "%.4f") << "," << num(s.map_f1_sd, "%.4f") << "\n";
  }
  return o.str();
}

}  // namespace crunch
