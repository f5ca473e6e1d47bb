#include "sweep_chart.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <ostream>
#include <sstream>
#include <system_error>
#include <utility>

#include "crunch/core/atomic_file.h"
#include "crunch/render/chart.h"

namespace crunch::app {

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

std::string settingName(const SettingSummary& s) {
  return std::to_string(s.schedule_steps) + " T x " + std::to_string(s.sweeps) + " sweep" +
         (s.sweeps == 1 ? "" : "s") + ", WM " + std::to_string(s.working_memory);
}

const ChartColour kRed{0.84, 0.15, 0.16};
const ChartColour kBlack{0.1, 0.1, 0.1};
const ChartColour kGrey{0.45, 0.45, 0.45};
const std::string kPaperLabel =
    "paper's setting: 16 temperatures, 1 sweep, WM 7 (docs/BLACKBOARD.md)";

// One noise regime's settings against one cost.
Chart paretoChart(const std::vector<SettingSummary>& set, bool proposals, const std::string& noise,
                  const std::vector<size_t>& front) {
  Chart c;
  const double sigma_mm = set.front().sigma_r * 1e3;
  c.options.title = "Accuracy against cost: noise '" + noise + "' (sigma_r " +
                    fmt("%g", sigma_mm) + " mm), " + set.front().scene + " scene, mean of " +
                    std::to_string(set.front().runs) + " seeds";
  c.options.x_label = proposals ? "Metropolis-Hastings proposals per run (thousands, mean)"
                                : "wall time per run (s, mean)";
  c.options.y_label = "F1 of the fused map (bars: +-1 sd over seeds)";
  c.options.width_px = 1000;
  c.options.height_px = 640;
  c.options.y_min = 0.0;
  c.options.y_max = 1.05;
  c.options.x_min = 0.0;
  double best = 0.0;
  for (const SettingSummary& s : set) best = std::max(best, s.f1_mean);
  c.options.legend = best < 0.6 ? LegendPosition::kTopRight : LegendPosition::kBottomRight;
  auto cost = [&](const SettingSummary& s) {
    return proposals ? s.proposals_mean / 1e3 : s.wall_s_mean;
  };

  std::vector<int> steps;
  std::vector<std::pair<int, int>> combos;
  for (const SettingSummary& s : set) {
    if (std::find(steps.begin(), steps.end(), s.schedule_steps) == steps.end()) {
      steps.push_back(s.schedule_steps);
    }
    const std::pair<int, int> k{s.sweeps, s.working_memory};
    if (std::find(combos.begin(), combos.end(), k) == combos.end()) combos.push_back(k);
  }
  std::sort(steps.begin(), steps.end());
  const MarkerShape shapes[] = {MarkerShape::kCircle, MarkerShape::kSquare, MarkerShape::kDiamond,
                                MarkerShape::kTriangle};
  auto colourOf = [&](int ss) {
    return chartPalette(
        static_cast<int>(std::find(steps.begin(), steps.end(), ss) - steps.begin()));
  };
  auto shapeOf = [&](int sw, int wm) {
    const auto i = std::find(combos.begin(), combos.end(), std::pair<int, int>{sw, wm}) -
                   combos.begin();
    return shapes[static_cast<size_t>(i) % 4];
  };

  ChartSeries line;
  line.label = "Pareto front (no other setting is both cheaper and more accurate)";
  line.style = SeriesStyle::kLine;
  line.colour = kBlack;
  line.line_width = 1.5;
  line.dashed = true;
  for (const size_t i : front) {
    line.x.push_back(cost(set[i]));
    line.y.push_back(set[i].f1_mean);
  }
  c.series.push_back(line);

  ChartSeries paper;
  paper.label = kPaperLabel;
  paper.style = SeriesStyle::kPoints;
  paper.marker = MarkerShape::kCircle;
  paper.marker_size = 10.0;
  paper.colour = kRed;
  for (const SettingSummary& s : set) {
    if (!s.isPaperSetting()) continue;
    paper.x.push_back(cost(s));
    paper.y.push_back(s.f1_mean);
  }
  if (!paper.x.empty()) c.series.push_back(paper);

  for (const SettingSummary& s : set) {
    ChartSeries p;
    p.style = SeriesStyle::kPoints;
    p.marker = shapeOf(s.sweeps, s.working_memory);
    p.marker_size = 5.0;
    p.colour = colourOf(s.schedule_steps);
    p.x = {cost(s)};
    p.y = {s.f1_mean};
    p.y_error = {s.f1_sd};
    c.series.push_back(p);
  }
  // Legend-only entries: colour = temperatures, marker = sweeps and working memory.
  for (const int ss : steps) {
    ChartSeries k;
    k.label = std::to_string(ss) + " temperatures (colour)";
    k.style = SeriesStyle::kPoints;
    k.colour = colourOf(ss);
    k.marker_size = 5.0;
    c.series.push_back(k);
  }
  for (const auto& [sw, wm] : combos) {
    ChartSeries k;
    k.label = std::to_string(sw) + " sweep" + (sw == 1 ? "" : "s") +
              " per temperature, working memory " + std::to_string(wm) + " (marker)";
    k.style = SeriesStyle::kPoints;
    k.marker = shapeOf(sw, wm);
    k.colour = kGrey;
    k.marker_size = 5.0;
    c.series.push_back(k);
  }
  return c;
}

constexpr double kNoiseYMax = 1.35;

Chart noiseChart(const std::vector<SettingSummary>& by_sigma) {
  Chart c;
  const SettingSummary& f = by_sigma.front();
  c.options.title = "Accuracy against sensor noise: " + f.scene + " scene, " + settingName(f) +
                    ", mean of " + std::to_string(f.runs) + " seeds";
  c.options.x_label = "sigma_r (mm); sigma_phi grows with it (5 mm : pi/32)";
  c.options.y_label = "recall, F1, precision (bars: +-1 sd over seeds)";
  c.options.width_px = 1000;
  c.options.height_px = 640;
  c.options.y_min = 0.0;
  c.options.y_max = kNoiseYMax;  // room above 1 for the legend
  c.options.x_min = 0.0;
  c.options.legend = LegendPosition::kTopRight;
  ChartSeries recall, f1, precision;
  recall.label = "recall (tables found / real tables)";
  recall.colour = chartPalette(0);
  recall.marker = MarkerShape::kCircle;
  f1.label = "F1 of the fused map";
  f1.colour = chartPalette(1);
  f1.marker = MarkerShape::kSquare;
  precision.label = "precision (mean)";
  precision.colour = chartPalette(2);
  precision.marker = MarkerShape::kDiamond;
  precision.dashed = true;
  precision.line_width = 1.5;
  for (const SettingSummary& s : by_sigma) {
    const double x = s.sigma_r * 1e3;
    recall.x.push_back(x);
    recall.y.push_back(s.recall_mean);
    recall.y_error.push_back(s.recall_sd);
    f1.x.push_back(x);
    f1.y.push_back(s.f1_mean);
    f1.y_error.push_back(s.f1_sd);
    precision.x.push_back(x);
    precision.y.push_back(s.precision_mean);
  }
  auto vline = [](const std::string& label, double x, ChartColour col) {
    ChartSeries v;
    v.label = label;
    v.style = SeriesStyle::kLine;
    v.colour = col;
    v.dashed = true;
    v.line_width = 1.5;
    v.x = {x, x};
    v.y = {0.0, kNoiseYMax};
    return v;
  };
  c.series.push_back(vline("paper's \"realistic\" (5 mm, pi/32)", kPaperRealisticSigmaR * 1e3,
                           kGrey));
  c.series.push_back(
      vline("paper's \"very noisy\" (25 mm, pi/8)", kPaperNoisySigmaR * 1e3, kRed));
  c.series.push_back(recall);
  c.series.push_back(f1);
  c.series.push_back(precision);
  return c;
}

std::string summaryCsv(const std::vector<SettingSummary>& all, const std::vector<bool>& on_wall,
                       const std::vector<bool>& on_props) {
  std::ostringstream o;
  o << "scene,noise,sigma_r_mm,schedule_steps,sweeps,working_memory,runs,f1_mean,f1_sd,"
       "recall_mean,recall_sd,precision_mean,precision_sd,wall_s_mean,proposals_mean,"
       "on_front_wall_s,on_front_proposals\n";
  for (size_t i = 0; i < all.size(); ++i) {
    const SettingSummary& s = all[i];
    o << s.scene << "," << s.noise << "," << fmt("%g", s.sigma_r * 1e3) << "," << s.schedule_steps
      << "," << s.sweeps << "," << s.working_memory << "," << s.runs << ","
      << fmt("%.4f", s.f1_mean) << "," << fmt("%.4f", s.f1_sd) << ","
      << fmt("%.4f", s.recall_mean) << "," << fmt("%.4f", s.recall_sd) << ","
      << fmt("%.4f", s.precision_mean) << "," << fmt("%.4f", s.precision_sd) << ","
      << fmt("%.4f", s.wall_s_mean) << "," << fmt("%.0f", s.proposals_mean) << ","
      << (on_wall[i] ? 1 : 0) << "," << (on_props[i] ? 1 : 0) << "\n";
  }
  return o.str();
}

}  // namespace

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
    if (!row.is_object()) return Error{where + " is not an object"};
    for (const std::string& col : kSweepChartColumns) {
      const auto it = row.find(col);
      if (it == row.end()) return Error{where + " has no column '" + col + "'"};
      const bool text = col == "scene" || col == "noise";
      const bool integer = col == "schedule_steps" || col == "sweeps" ||
                           col == "working_memory" || col == "seed";
      const bool ok = text ? it->is_string()
                           : integer ? it->is_number_integer()
                                     : it->is_number() && std::isfinite(it->get<double>());
      if (!ok) {
        return Error{where + ": column '" + col + "' must be " +
                     (text ? "a string" : integer ? "an integer" : "a finite number")};
      }
    }
    SettingSummary key;
    key.scene = row["scene"].get<std::string>();
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
      return a.s.noise == key.noise && a.s.schedule_steps == key.schedule_steps &&
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
  for (Acc& a : acc) {
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
    out.push_back(s);
  }
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

int runSweepChart(const SweepChartOptions& options, std::ostream& out, std::ostream& err) {
  const std::string in_path = options.in_dir + "/sweep.json";
  auto loaded = loadSweepSummary(in_path);
  if (!loaded) {
    err << "crunchhost sweep-chart: " << loaded.error().message << "\n";
    return 2;
  }
  const std::vector<SettingSummary>& all = loaded.value();
  const std::string dir = (options.out_dir.empty() ? options.in_dir : options.out_dir) + "/";

  // Pareto charts: per noise regime with two settings or more.
  std::vector<std::pair<std::string, Chart>> charts;
  std::vector<bool> on_wall(all.size(), false), on_props(all.size(), false);
  std::vector<std::string> noises;
  for (const SettingSummary& s : all) {
    if (std::find(noises.begin(), noises.end(), s.noise) == noises.end()) noises.push_back(s.noise);
  }
  std::ostringstream report;
  for (const std::string& noise : noises) {
    std::vector<size_t> idx;
    for (size_t i = 0; i < all.size(); ++i) {
      if (all[i].noise == noise) idx.push_back(i);
    }
    std::vector<SettingSummary> set;
    std::vector<double> wall, props, f1;
    for (const size_t i : idx) {
      set.push_back(all[i]);
      wall.push_back(all[i].wall_s_mean);
      props.push_back(all[i].proposals_mean);
      f1.push_back(all[i].f1_mean);
    }
    const std::vector<size_t> fw = paretoFront(wall, f1);
    const std::vector<size_t> fp = paretoFront(props, f1);
    for (const size_t k : fw) on_wall[idx[k]] = true;
    for (const size_t k : fp) on_props[idx[k]] = true;
    if (set.size() < 2) continue;
    charts.push_back({"pareto_" + noise, paretoChart(set, false, noise, fw)});
    charts.push_back({"pareto_" + noise + "_proposals", paretoChart(set, true, noise, fp)});
    report << noise << ": Pareto front (wall time):";
    for (const size_t k : fw) {
      report << " [" << settingName(set[k]) << ": F1 " << fmt("%.3f", set[k].f1_mean) << ", "
             << fmt("%.2f", set[k].wall_s_mean) << " s]";
    }
    report << "\n";
  }

  // Noise chart: one setting across the noise levels.
  std::vector<double> sigmas;
  for (const SettingSummary& s : all) {
    if (std::find(sigmas.begin(), sigmas.end(), s.sigma_r) == sigmas.end()) {
      sigmas.push_back(s.sigma_r);
    }
  }
  if (sigmas.size() >= 2) {
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
      if (s.isPaperSetting()) {
        by_sigma = levels(s);
        break;
      }
    }
    if (by_sigma.size() < 2) by_sigma = levels(all.front());
    if (by_sigma.size() >= 2) {
      charts.push_back({"noise", noiseChart(by_sigma)});
      report << "noise (" << settingName(by_sigma.front()) << "): recall";
      for (const SettingSummary& s : by_sigma) {
        report << " " << fmt("%g", s.sigma_r * 1e3) << " mm " << fmt("%.2f", s.recall_mean);
      }
      const auto fail = std::find_if(by_sigma.begin(), by_sigma.end(), [](const SettingSummary& s) {
        return s.recall_mean < 0.5;
      });
      if (fail != by_sigma.end()) {
        report << "; mean recall below 0.5 from sigma_r = " << fmt("%g", fail->sigma_r * 1e3)
               << " mm";
      } else {
        report << "; mean recall stays >= 0.5 at every level";
      }
      report << "\n";
    }
  }

  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) {
    err << "crunchhost sweep-chart: cannot create " << dir << ": " << ec.message() << "\n";
    return 1;
  }
  std::vector<std::string> written;
  for (const auto& [name, chart] : charts) {
    for (const bool png : {true, false}) {
      const std::string path = dir + name + (png ? ".png" : ".svg");
      const Status s = png ? renderChartPng(chart, path) : renderChartSvg(chart, path);
      if (!s) {
        err << "crunchhost sweep-chart: " << s.error().message << "\n";
        return 1;
      }
    }
    written.push_back(name);
  }
  if (const Status s = writeFileAtomic(dir + "summary.csv", summaryCsv(all, on_wall, on_props));
      !s) {
    err << "crunchhost sweep-chart: " << s.error().message << "\n";
    return 1;
  }
  out << report.str() << "wrote " << dir << "{";
  for (const std::string& n : written) out << n << ",";
  out << "summary}" << (written.empty() ? " (no chart: one setting and one noise level)" : "")
      << " (.png and .svg; summary.csv)\n";
  return 0;
}

}  // namespace crunch::app
