#include "crunch/mapping/sweep_statistics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

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
  std::ifstream in(path);
  if (!in) return Error{path + ": cannot read (missing? run `crunchhost sweep --out DIR` first)"};
  Json rows;
  try {
    rows = Json::parse(in);
  } catch (const std::exception& e) {
    return Error{path + ": not valid JSON (" + std::string(e.what()) + ")"};
  }
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

}  // namespace crunch
