#include "crunch/render/sweep_charts.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace crunch {

namespace {

std::string fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

const ChartColour kRed{0.84, 0.15, 0.16};
const ChartColour kBlack{0.1, 0.1, 0.1};
const ChartColour kGrey{0.45, 0.45, 0.45};
const std::string kPaperLabel =
    "paper's setting: 16 temperatures, 1 sweep, WM 7 (docs/BLACKBOARD.md)";
constexpr double kNoiseYMax = 1.35;

// The series of the Pareto chart after the front and the paper's point: one point per setting
// (colour = temperatures, marker = sweeps and working memory), then legend-only entries.
void addSettingSeries(Chart& c, const std::vector<SettingSummary>& set, bool proposals) {
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
}

// The chart's file stem: pareto_<noise>, with _<model> for a model other than the paper's.
std::string paretoName(const NoiseFronts& f) {
  return "pareto_" + f.noise + (f.model == "paper" ? "" : "_" + f.model);
}

// The Pareto fronts (wall time) of every (model, noise regime) with two settings or more, and
// their charts; with two models or more, each noise regime's fronts side by side.
void addParetoCharts(const std::vector<SettingSummary>& all, const std::vector<NoiseFronts>& fronts,
                     SweepChartSet& out, std::ostringstream& report) {
  for (const NoiseFronts& f : fronts) {
    if (f.settings.size() < 2) continue;
    std::vector<SettingSummary> set;
    for (const size_t i : f.settings) set.push_back(all[i]);
    // The fronts index `all`; the charts index `set`.
    auto local = [&](const std::vector<size_t>& front) {
      std::vector<size_t> v;
      for (const size_t i : front)
        v.push_back(static_cast<size_t>(
            std::find(f.settings.begin(), f.settings.end(), i) - f.settings.begin()));
      return v;
    };
    const std::vector<size_t> fw = local(f.wall_front), fp = local(f.proposals_front);
    out.charts.push_back({paretoName(f), sweepParetoChart(set, false, f.noise, fw)});
    out.charts.push_back({paretoName(f) + "_proposals", sweepParetoChart(set, true, f.noise, fp)});
    report << (f.model == "paper" ? "" : f.model + ", ") << f.noise
           << ": Pareto front (wall time):";
    for (const size_t k : fw) {
      report << " [" << settingName(set[k]) << ": F1 " << fmt("%.3f", set[k].f1_mean) << ", "
             << fmt("%.2f", set[k].wall_s_mean) << " s]";
    }
    report << "\n";
  }
  if (sweepModels(all).size() < 2) return;
  std::vector<std::string> noises;
  for (const NoiseFronts& f : fronts)
    if (std::find(noises.begin(), noises.end(), f.noise) == noises.end()) noises.push_back(f.noise);
  for (const std::string& noise : noises) {
    std::vector<NoiseFronts> same;
    for (const NoiseFronts& f : fronts)
      if (f.noise == noise) same.push_back(f);
    if (same.size() >= 2)
      out.charts.push_back({"pareto_" + noise + "_models", sweepModelsChart(all, same)});
  }
}

}  // namespace

Chart sweepParetoChart(const std::vector<SettingSummary>& set, bool proposals,
                       const std::string& noise, const std::vector<size_t>& front) {
  Chart c;
  const double sigma_mm = set.front().sigma_r * 1e3;
  c.options.title = "Accuracy against cost" +
                    (set.front().model == "paper" ? std::string() : ", model " + set.front().model) +
                    ": noise '" + noise + "' (sigma_r " +
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
  addSettingSeries(c, set, proposals);
  return c;
}

Chart sweepModelsChart(const std::vector<SettingSummary>& all,
                       const std::vector<NoiseFronts>& fronts) {
  Chart c;
  const SettingSummary& first = all[fronts.front().settings.front()];
  c.options.title = "Accuracy against cost by object model: noise '" + first.noise +
                    "' (sigma_r " + fmt("%g", first.sigma_r * 1e3) + " mm), " + first.scene +
                    " scene, mean of " + std::to_string(first.runs) + " seeds";
  c.options.x_label = "wall time per run (s, mean)";
  c.options.y_label = "F1 of the fused map (bars: +-1 sd over seeds)";
  c.options.width_px = 1000;
  c.options.height_px = 640;
  c.options.y_min = 0.0;
  c.options.y_max = 1.05;
  c.options.x_min = 0.0;
  c.options.legend = LegendPosition::kBottomRight;
  const MarkerShape shapes[] = {MarkerShape::kCircle, MarkerShape::kSquare, MarkerShape::kDiamond,
                                MarkerShape::kTriangle};
  for (size_t m = 0; m < fronts.size(); ++m) {
    const NoiseFronts& f = fronts[m];
    ChartSeries every;  // every setting of the model, unlabelled points
    every.style = SeriesStyle::kPoints;
    every.colour = chartPalette(static_cast<int>(m));
    every.marker = shapes[m % 4];
    every.marker_size = 3.0;
    for (const size_t i : f.settings) {
      every.x.push_back(all[i].wall_s_mean);
      every.y.push_back(all[i].f1_mean);
    }
    ChartSeries front;
    front.label = "--model " + f.model + ": Pareto front (points: every setting)";
    front.colour = every.colour;
    front.marker = every.marker;
    front.marker_size = 5.0;
    for (const size_t i : f.wall_front) {
      front.x.push_back(all[i].wall_s_mean);
      front.y.push_back(all[i].f1_mean);
      front.y_error.push_back(all[i].f1_sd);
    }
    c.series.push_back(every);
    c.series.push_back(front);
  }
  return c;
}

Chart sweepNoiseChart(const std::vector<std::vector<SettingSummary>>& models) {
  Chart c;
  const SettingSummary& f = models.front().front();
  const bool several = models.size() > 1;
  SettingSummary setting = f;  // the sampler setting's name without the model
  setting.model = "paper";
  c.options.title = "Accuracy against sensor noise: " + f.scene + " scene, " +
                    (several ? "each model at " : "") + settingName(several ? setting : f) +
                    ", mean of " + std::to_string(f.runs) + " seeds";
  c.options.x_label = "sigma_r (mm); sigma_phi grows with it (5 mm : pi/32)";
  c.options.y_label = "recall, F1, precision (bars: +-1 sd over seeds)";
  c.options.width_px = 1000;
  c.options.height_px = 640;
  c.options.y_min = 0.0;
  c.options.y_max = kNoiseYMax;  // room above 1 for the legend
  c.options.x_min = 0.0;
  c.options.legend = LegendPosition::kTopRight;
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
  // One model: recall, F1, precision in three colours. Several: a colour per model, the metric
  // by marker and line (recall solid circles, F1 solid squares, precision dashed diamonds).
  for (size_t m = 0; m < models.size(); ++m) {
    const std::string prefix = several ? "--model " + models[m].front().model + ": " : "";
    ChartSeries recall, f1, precision;
    recall.label = prefix + "recall (tables found / real tables)";
    recall.marker = MarkerShape::kCircle;
    f1.label = prefix + "F1 of the fused map";
    f1.marker = MarkerShape::kSquare;
    precision.label = prefix + "precision (mean)";
    precision.marker = MarkerShape::kDiamond;
    precision.dashed = true;
    precision.line_width = 1.5;
    if (several) {
      recall.colour = f1.colour = precision.colour = chartPalette(static_cast<int>(m));
      f1.line_width = 1.0;
    } else {
      recall.colour = chartPalette(0);
      f1.colour = chartPalette(1);
      precision.colour = chartPalette(2);
    }
    for (const SettingSummary& s : models[m]) {
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
    c.series.push_back(recall);
    c.series.push_back(f1);
    c.series.push_back(precision);
  }
  if (several) {
    // Three lines a model make the legend tall: the x axis runs on past the noisiest point so
    // that the legend stands right of the data, not over its precision at that point.
    double widest = kPaperNoisySigmaR * 1e3;
    for (const auto& m : models)
      for (const SettingSummary& s : m) widest = std::max(widest, s.sigma_r * 1e3);
    c.options.x_max = 1.8 * widest;
  }
  return c;
}

SweepChartSet sweepCharts(const std::vector<SettingSummary>& all) {
  SweepChartSet out;
  const std::vector<NoiseFronts> fronts = sweepFronts(all);
  std::ostringstream report;
  addParetoCharts(all, fronts, out, report);
  std::vector<std::vector<SettingSummary>> by_model;
  for (const std::string& model : sweepModels(all)) {
    std::vector<SettingSummary> by_sigma = noiseLevels(all, model);
    if (!by_sigma.empty()) by_model.push_back(std::move(by_sigma));
  }
  if (!by_model.empty()) out.charts.push_back({"noise", sweepNoiseChart(by_model)});
  for (const std::vector<SettingSummary>& by_sigma : by_model) {
    report << "noise (" << settingName(by_sigma.front()) << "): recall";
    for (const SettingSummary& s : by_sigma) {
      report << " " << fmt("%g", s.sigma_r * 1e3) << " mm " << fmt("%.2f", s.recall_mean);
    }
    const auto fail = std::find_if(by_sigma.begin(), by_sigma.end(),
                                   [](const SettingSummary& s) { return s.recall_mean < 0.5; });
    if (fail != by_sigma.end()) {
      report << "; mean recall below 0.5 from sigma_r = " << fmt("%g", fail->sigma_r * 1e3)
             << " mm";
    } else {
      report << "; mean recall stays >= 0.5 at every level";
    }
    report << "\n";
  }
  out.summary_csv = sweepSummaryCsv(all, fronts);
  out.report = report.str();
  return out;
}

// ---- Exploration: recall and F1 against metres driven.

namespace {

// A fixed colour per policy name, so that a policy has the same colour in every chart.
ChartColour policyColour(const std::string& explore) {
  static const char* const kOrder[] = {"grid", "random", "frontier", "entropy", "infogain", "none"};
  for (int i = 0; i < 6; ++i)
    if (explore == kOrder[i]) return chartPalette(i);
  int h = 0;
  for (const char c : explore) h = (h * 31 + c) & 0xffff;
  return chartPalette(6 + h % 2);
}

bool sameGroup(const ExploreSummary& a, const ExploreSummary& b) {
  return a.scene == b.scene && a.model == b.model && a.noise == b.noise;
}

}  // namespace

std::string exploreChartStem(const ExploreSummary& s) {
  std::string stem = s.scene;
  if (const auto slash = stem.find_last_of('/'); slash != std::string::npos)
    stem = stem.substr(slash + 1);
  if (stem.size() > 5 && stem.compare(stem.size() - 5, 5, ".json") == 0)
    stem.resize(stem.size() - 5);
  if (s.model != "paper") stem += "_" + s.model;
  if (s.noise != "realistic") stem += "_" + s.noise;
  return stem;
}

Chart exploreChart(const std::vector<ExploreSummary>& group, bool f1) {
  Chart c;
  const ExploreSummary& h = group.front();
  int runs = 0;
  for (const ExploreSummary& s : group) runs = std::max(runs, s.runs);
  const std::string what = f1 ? "F1" : "recall";
  c.options.title = exploreChartStem(h) + ": " + what + " against metres driven, mean of " +
                    std::to_string(runs) + " seeds (dashed +-1 sd; square: final map)";
  c.options.x_label = "metres driven";
  c.options.y_label = "fused-map " + what +
                      std::string(f1 ? " (of precision and recall)" : " (tables found / real tables)");
  c.options.width_px = 1000;
  c.options.height_px = 620;
  c.options.x_min = 0.0;
  c.options.y_min = 0.0;
  c.options.y_max = 1.3;  // room above 1 for the legend
  c.options.legend = LegendPosition::kTopLeft;
  if (!f1 && !h.travel.empty()) {
    ChartSeries target;
    target.label = "recall " + fmt("%g", h.recall_target) + " (issue 14's target)";
    target.style = SeriesStyle::kLine;
    target.colour = kBlack;
    target.dashed = true;
    target.line_width = 1.0;
    target.x = {0.0, h.travel.back()};
    target.y = {h.recall_target, h.recall_target};
    c.series.push_back(target);
  }
  for (const ExploreSummary& s : group) {
    const std::vector<double>& m = f1 ? s.f1_mean : s.recall_mean;
    const std::vector<double>& d = f1 ? s.f1_sd : s.recall_sd;
    ChartSeries line, lo, hi;
    line.label = s.explore + " (" + std::to_string(s.runs) + " seeds; drove " +
                 fmt("%.1f", s.final_travel_mean) + " m; curve " +
                 fmt("%.2f", f1 ? s.final_f1_mean : s.final_recall_mean) + ")";
    line.style = lo.style = hi.style = SeriesStyle::kLine;
    line.colour = lo.colour = hi.colour = policyColour(s.explore);
    lo.dashed = hi.dashed = true;
    lo.line_width = hi.line_width = 1.0;
    line.x = lo.x = hi.x = s.travel;
    line.y = m;
    for (size_t i = 0; i < m.size(); ++i) {
      lo.y.push_back(std::max(0.0, m[i] - d[i]));
      hi.y.push_back(std::min(1.0, m[i] + d[i]));
    }
    const double map_mean = f1 ? s.map_f1_mean : s.map_recall_mean;
    const double map_sd = f1 ? s.map_f1_sd : s.map_recall_sd;
    if (std::isfinite(map_mean)) line.label += ", final map " + fmt("%.2f", map_mean);
    c.series.push_back(line);
    if (s.runs > 1) {
      c.series.push_back(lo);
      c.series.push_back(hi);
    }
    if (std::isfinite(map_mean)) {
      // The final fused map (global inference at the end): a square at the run's mean travel.
      ChartSeries end;
      end.style = SeriesStyle::kPoints;
      end.marker = MarkerShape::kSquare;
      end.marker_size = 6.0;
      end.colour = line.colour;
      end.x = {s.final_travel_mean};
      end.y = {map_mean};
      end.y_error = {map_sd};
      c.series.push_back(end);
    }
  }
  return c;
}

SweepChartSet exploreCharts(const std::vector<ExploreSummary>& all) {
  SweepChartSet out;
  std::ostringstream report;
  std::vector<bool> done(all.size(), false);
  for (size_t g = 0; g < all.size(); ++g) {
    if (done[g]) continue;
    std::vector<ExploreSummary> group;
    for (size_t k = g; k < all.size(); ++k) {
      if (!done[k] && sameGroup(all[g], all[k])) {
        group.push_back(all[k]);
        done[k] = true;
      }
    }
    const std::string stem = exploreChartStem(all[g]);
    out.charts.push_back({"explore_" + stem + "_recall", exploreChart(group, false)});
    out.charts.push_back({"explore_" + stem + "_f1", exploreChart(group, true)});
    report << "explore " << stem << ":";
    for (const ExploreSummary& s : group) {
      report << " " << s.explore << " recall " << fmt("%.2f", s.final_recall_mean) << " after "
             << fmt("%.1f", s.final_travel_mean) << " m";
      if (std::isfinite(s.mean_curve_travel_to_target))
        report << " (mean >= " << fmt("%g", s.recall_target) << " at "
               << fmt("%.1f", s.mean_curve_travel_to_target) << " m)";
      report << ";";
    }
    report << "\n";
  }
  out.summary_csv = exploreSummaryCsv(all);
  out.report = report.str();
  return out;
}

}  // namespace crunch
