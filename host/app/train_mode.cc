#include "train_mode.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <ostream>
#include <sstream>

#include "crunch/mapping/map_io.h"
#include "crunch/render/chart.h"
#include "crunch/signal/models_io.h"
#include "crunch/signal/orientation_templates.h"

namespace crunch::app {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using nlohmann::ordered_json;

constexpr double kDeg = 180.0 / kPi;
// Paper, Table 1 (mm) and Fig. 10 (degrees).
constexpr double kPaperSigmaMm[4] = {2.78, 1.82, 4.37, 5.68};
constexpr double kPaperComboMm = 4.98;
constexpr double kPaperMeanDeg = -2.2;
constexpr double kPaperSdDeg = 21.2;

std::string formatDuration(double s) {
  if (!std::isfinite(s) || s < 0) return "?";
  const long t = std::lround(s);
  std::ostringstream o;
  if (t >= 60) o << t / 60 << "m";
  o << (t % 60 < 10 && t >= 60 ? "0" : "") << t % 60 << "s";
  return o.str();
}

// The bar on stderr (or JSON lines on stdout) with the time left, estimated from the wall time
// per whisk so far.
class Progress {
 public:
  Progress(std::ostream& os, bool json) : os_(os), json_(json), t0_(Clock::now()) {}
  void operator()(const sim::TrainingProgress& p) {
    const double elapsed = std::chrono::duration<double>(Clock::now() - t0_).count();
    const double eta = p.done > 0 ? elapsed / p.done * (p.total - p.done) : -1.0;
    if (json_) {
      os_ << "{\"event\":\"progress\",\"done\":" << p.done << ",\"total\":" << p.total
          << ",\"phase\":\"" << p.phase << "\",\"elapsed_s\":" << std::lround(elapsed)
          << ",\"eta_s\":" << std::lround(std::max(eta, 0.0))
          << ",\"simulated_s\":" << std::lround(p.simulated_s) << "}\n"
          << std::flush;
      return;
    }
    const int width = 30;
    const int filled = p.total > 0 ? p.done * width / p.total : width;
    os_ << "\r[" << std::string(static_cast<size_t>(filled), '#')
        << std::string(static_cast<size_t>(width - filled), ' ') << "] " << p.done << "/" << p.total
        << " whisks, " << p.phase << ", " << formatDuration(elapsed) << " elapsed, ~"
        << formatDuration(eta) << " left   " << (p.done == p.total ? "\n" : "") << std::flush;
  }
  double elapsed() const { return std::chrono::duration<double>(Clock::now() - t0_).count(); }

 private:
  std::ostream& os_;
  bool json_;
  Clock::time_point t0_;
};

// A directory we can create files in: created if missing, then probed with a file that is
// removed again. The Error names the directory.
Status checkWritableDir(const std::string& dir) {
  if (auto s = ensureDirectory(dir); !s) return s;
  const fs::path probe = fs::path(dir) / (".crunch-train-probe-" + std::to_string(::getpid()));
  {
    std::ofstream f(probe);
    if (!f || !(f << "probe") || !f.flush()) {
      std::error_code ec;
      fs::remove(probe, ec);
      return Error{dir + ": cannot write files there"};
    }
  }
  std::error_code ec;
  fs::remove(probe, ec);
  return okStatus();
}

Status checkModelsOut(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) return Error{path + ": --models-out names a directory"};
  const fs::path parent = fs::path(path).parent_path();
  const std::string pdir = parent.empty() ? "." : parent.string();
  if (!fs::is_directory(pdir, ec)) {
    return Error{"--models-out " + path + ": the directory " + pdir + " does not exist"};
  }
  if (auto s = checkWritableDir(pdir); !s) {
    return Error{"--models-out " + path + ": " + s.error().message};
  }
  return okStatus();
}

ordered_json lineJson(const signal::RadialLine& l) {
  return {{"a1", l.a1},         {"a0", l.a0},         {"sigma_m", l.sigma}, {"samples", l.samples},
          {"f1_min", l.f1_min}, {"f1_max", l.f1_max}, {"r_min", l.r_min},   {"r_max", l.r_max}};
}

ordered_json variantJson(const sim::RadialEvaluation& ev) {
  ordered_json per = ordered_json::array();
  for (int w = 0; w < signal::kWhiskers; ++w) {
    const auto i = static_cast<size_t>(w);
    per.push_back({{"whisker", w},
                   {"heldout_rms_mm", ev.heldout_rms[i] * 1e3},
                   {"heldout_mean_mm", ev.heldout_mean[i] * 1e3},
                   {"heldout_contacts", ev.heldout_n[i]},
                   {"training_fit_sigma_mm", ev.fit.summary.sigma[i] * 1e3},
                   {"line", lineJson(ev.fit.model.whiskers[i])}});
  }
  return {{"f1", sim::f1SourceName(ev.variant.source)},
          {"feature", sim::radialFeatureName(ev.variant.feature)},
          {"label", sim::radialLabelName(ev.variant.label)},
          {"per_whisker", per},
          {"heldout_rms_all_mm", ev.heldout_rms_all * 1e3},
          {"heldout_mean_all_mm", ev.heldout_mean_all * 1e3},
          {"heldout_contacts", ev.heldout_n_all},
          {"combo_line_heldout_rms_mm", ev.combo_heldout_rms * 1e3},
          {"training_pooled_sigma_mm", ev.fit.summary.pooled_sigma * 1e3},
          {"combo_line", lineJson(ev.fit.summary.combined)}};
}

struct RadialCounts {
  int training = 0, heldout = 0;
  int no_episode = 0;         // the whisk gave no episode at all
  int not_detected = 0;       // episodes, but none saw the whisker touch
  int truth_not_touched = 0;  // the peak episode's truth never saw the whisker touch
  int multi_episode = 0;      // the whisk gave more than one episode
  int peak_not_first = 0;     // the max f1 came from a later episode than the first
  int other_touched = 0;      // another whisker touched the pole
  int truncated = 0;
  double max_free_theta = 0.0;  // largest detector theta of a never-touching whisker, rad
  double min_f1 = 0.0;          // smallest detected contact f1, rad
};

RadialCounts countRadial(const std::vector<sim::RadialContact>& contacts) {
  RadialCounts c;
  bool first = true;
  for (const sim::RadialContact& r : contacts) {
    (r.set == 0 ? c.training : c.heldout)++;
    if (r.episodes.empty())
      ++c.no_episode;
    else if (!r.detected)
      ++c.not_detected;
    if (r.detected && !r.truth_touched) ++c.truth_not_touched;
    if (r.episodes.size() > 1) ++c.multi_episode;
    if (r.detected && r.peak_episode != r.first_episode) ++c.peak_not_first;
    if (r.other_touched != 0) ++c.other_touched;
    if (r.truncated) ++c.truncated;
    c.max_free_theta = std::max(c.max_free_theta, r.max_free_theta);
    if (r.detected) {
      c.min_f1 = first ? r.f1 : std::min(c.min_f1, r.f1);
      first = false;
    }
  }
  return c;
}

ordered_json radialDataJson(const std::vector<sim::RadialContact>& contacts) {
  ordered_json a = ordered_json::array();
  for (const sim::RadialContact& c : contacts) {
    ordered_json eps = ordered_json::array();
    for (const sim::EpisodeRecord& e : c.episodes) {
      eps.push_back({{"start_s", e.start_s},
                     {"duration_s", e.duration_s},
                     {"touched", e.touched},
                     {"f1", e.f1},
                     {"truth_touched", e.truth_touched},
                     {"r_at_peak", e.r_at_peak},
                     {"touched_mask", e.touched_mask}});
    }
    a.push_back({{"set", c.set == 0 ? "training" : "heldout"},
                 {"whisker", c.whisker},
                 {"repeat", c.repeat},
                 {"nominal_d", c.nominal_d},
                 {"d", c.d},
                 {"eps", c.eps},
                 {"pose", {c.pose.x, c.pose.y, c.pose.theta}},
                 {"detected", c.detected},
                 {"f1", c.f1},
                 {"r_truth_at_peak", c.r},
                 {"peak_episode", c.peak_episode},
                 {"first_f1", c.first_f1},
                 {"first_r_truth_at_peak", c.first_r},
                 {"first_episode", c.first_episode},
                 {"other_whiskers_touched_mask", c.other_touched},
                 {"max_free_theta", c.max_free_theta},
                 {"episodes", eps}});
  }
  return a;
}

struct OrientationSummary {
  int contacts = 0, windows = 0, no_episode = 0, incomplete = 0;
  double mean_onset_s = 0.0, max_onset_s = 0.0;
  double mean_onset_offset = 0.0, max_abs_onset_offset = 0.0;  // rad
  double max_free_theta = 0.0;
};

OrientationSummary summariseOrientation(const std::vector<sim::OrientationContact>& cs) {
  OrientationSummary s;
  for (const sim::OrientationContact& c : cs) {
    ++s.contacts;
    s.max_free_theta = std::max(s.max_free_theta, c.max_free_theta);
    if (c.episodes == 0) {
      ++s.no_episode;
      continue;
    }
    if (!c.has_window)
      ++s.incomplete;
    else
      ++s.windows;
    s.mean_onset_s += c.onset_s;
    s.max_onset_s = std::max(s.max_onset_s, c.onset_s);
    s.mean_onset_offset += c.onset_offset;
    s.max_abs_onset_offset = std::max(s.max_abs_onset_offset, std::abs(c.onset_offset));
  }
  const int n = s.contacts - s.no_episode;
  if (n > 0) {
    s.mean_onset_s /= n;
    s.mean_onset_offset /= n;
  }
  return s;
}

// ---- Charts.

ChartColour grey() { return {0.55, 0.55, 0.55}; }

Chart fig9Chart(const std::vector<sim::RadialContact>& contacts, const sim::RadialEvaluation& ev) {
  Chart c;
  c.options.title = "Fig. 9: peak deflection against radial distance (training set, eq. 2 fits)";
  c.options.x_label = "true radial distance at the peak r (mm)";
  c.options.y_label = "peak deflection f1 (rad)";
  c.options.width_px = 900;
  c.options.height_px = 560;
  c.options.legend = LegendPosition::kBottomLeft;
  c.options.x_min = 85.0;
  c.options.x_max = 145.0;
  c.options.y_min = 0.1;
  c.options.y_max = 0.5;
  const MarkerShape shapes[] = {MarkerShape::kCircle, MarkerShape::kSquare, MarkerShape::kDiamond,
                                MarkerShape::kTriangle};
  ChartSeries later;
  later.label = "peak on a later pass (slipped past the pole's end)";
  later.style = SeriesStyle::kPoints;
  later.colour = ChartColour{0, 0, 0};
  later.marker_size = 2.0;
  for (int w = 0; w < signal::kWhiskers; ++w) {
    ChartSeries pts;
    pts.label = "whisker " + std::to_string(w + 1);
    pts.style = SeriesStyle::kPoints;
    pts.marker = shapes[w];
    pts.colour = chartPalette(w);
    for (const sim::RadialContact& r : contacts) {
      if (r.set != 0 || r.whisker != w || !r.detected) continue;
      pts.x.push_back(r.r * 1e3);
      pts.y.push_back(r.f1);
      if (r.peak_episode != r.first_episode) {
        later.x.push_back(r.r * 1e3);
        later.y.push_back(r.f1);
      }
    }
    c.series.push_back(pts);
  }
  for (int w = 0; w < signal::kWhiskers; ++w) {
    const signal::RadialLine& l = ev.fit.model.whiskers[static_cast<size_t>(w)];
    ChartSeries line;
    line.label = w == 0 ? "eq. 2 fit per whisker (r = a1 f1 + a0)" : "";
    line.style = SeriesStyle::kLine;
    line.colour = chartPalette(w);
    line.line_width = 1.5;
    line.dashed = true;
    if (l.a1 != 0.0) {
      for (const double r : {l.r_min, l.r_max}) {
        line.x.push_back(r * 1e3);
        line.y.push_back((r - l.a0) / l.a1);
      }
    }
    c.series.push_back(line);
  }
  if (!later.x.empty()) c.series.push_back(later);
  return c;
}

Chart table1Chart(const sim::RadialEvaluation& protocol, const sim::RadialEvaluation& first) {
  Chart c;
  c.options.title = "Table 1: radial distance error on the held-out set";
  c.options.x_label = "whisker (5 = all whiskers together, the paper's 'Combo')";
  c.options.y_label = "sigma of r error (mm)";
  c.options.width_px = 900;
  c.options.height_px = 520;
  c.options.x_min = 0.4;
  c.options.x_max = 5.6;
  c.options.y_min = 0.0;
  c.options.y_max = 9.0;  // room for the legend above the bars
  c.options.legend = LegendPosition::kTopLeft;
  auto bars = [](const std::string& label, ChartColour colour, double offset,
                 const std::array<double, 5>& values) {
    ChartSeries s;
    s.label = label;
    s.style = SeriesStyle::kLine;
    s.colour = colour;
    s.line_width = 16.0;
    for (int i = 0; i < 5; ++i) {
      const double x = i + 1 + offset;
      s.x.insert(s.x.end(), {x, x, NAN});
      s.y.insert(s.y.end(), {0.0, values[static_cast<size_t>(i)], NAN});
    }
    return s;
  };
  std::array<double, 5> paper{}, ours{}, ours_first{};
  for (int w = 0; w < 4; ++w) {
    paper[static_cast<size_t>(w)] = kPaperSigmaMm[w];
    ours[static_cast<size_t>(w)] = protocol.heldout_rms[static_cast<size_t>(w)] * 1e3;
    ours_first[static_cast<size_t>(w)] = first.heldout_rms[static_cast<size_t>(w)] * 1e3;
  }
  paper[4] = kPaperComboMm;
  ours[4] = protocol.heldout_rms_all * 1e3;
  ours_first[4] = first.heldout_rms_all * 1e3;
  c.series.push_back(bars("paper (CrunchBot)", grey(), -0.25, paper));
  c.series.push_back(
      bars("sim, eq. 2, f1 = max over the whisk (saved)", chartPalette(0), 0.0, ours));
  c.series.push_back(bars("sim, eq. 2, f1 of the first pass", chartPalette(2), 0.25, ours_first));
  ChartSeries target;
  target.label = "target 5 mm";
  target.style = SeriesStyle::kLine;
  target.colour = ChartColour{0.8, 0.1, 0.1};
  target.dashed = true;
  target.line_width = 1.5;
  target.x = {0.4, 5.6};
  target.y = {5.0, 5.0};
  c.series.push_back(target);
  return c;
}

Chart fig10Chart(const signal::CrossValidation& cv) {
  Chart c;
  c.options.title = "Fig. 10: surface orientation error, leave one repeat out";
  c.options.x_label = "true wall angle (deg)";
  c.options.y_label = "estimated - true (deg)";
  c.options.width_px = 900;
  c.options.height_px = 560;
  c.options.x_min = 10.0;
  c.options.x_max = 170.0;
  c.options.legend = LegendPosition::kBottomLeft;
  ChartSeries trials;
  trials.label = "each test window";
  trials.style = SeriesStyle::kPoints;
  trials.colour = grey();
  trials.marker_size = 2.5;
  for (const signal::OrientationTrial& t : cv.trials) {
    trials.x.push_back(t.true_angle * kDeg + 1.5 * (t.repeat - 1.5));
    trials.y.push_back(t.error * kDeg);
  }
  ChartSeries per;
  per.label = "mean +- sd per angle (sim)";
  per.style = SeriesStyle::kPoints;
  per.colour = chartPalette(0);
  per.marker_size = 4.5;
  for (const signal::AngleErrors& a : cv.per_angle) {
    per.x.push_back(a.angle * kDeg);
    per.y.push_back(a.mean * kDeg);
    per.y_error.push_back(a.sd * kDeg);
  }
  auto hline = [](const std::string& label, double y, ChartColour colour, bool dashed) {
    ChartSeries s;
    s.label = label;
    s.style = SeriesStyle::kLine;
    s.colour = colour;
    s.dashed = dashed;
    s.line_width = 1.5;
    s.x = {10.0, 170.0};
    s.y = {y, y};
    return s;
  };
  const ChartColour red{0.8, 0.1, 0.1};
  c.series.push_back(trials);
  c.series.push_back(per);
  char ours[120];
  std::snprintf(ours, sizeof ours, "sim: mean %.1f over all trials (sd %.1f)", cv.mean_error * kDeg,
                cv.sd_error * kDeg);
  c.series.push_back(hline(ours, cv.mean_error * kDeg, chartPalette(0), false));
  c.series.push_back(hline("paper: mean -2.2, +-1 sd (21.2)", kPaperMeanDeg, red, true));
  c.series.push_back(hline("", kPaperMeanDeg + kPaperSdDeg, red, true));
  c.series.push_back(hline("", kPaperMeanDeg - kPaperSdDeg, red, true));
  return c;
}

std::string reportJson(const TrainOptions& opt, const sim::TrainingOptions& proto,
                       const sim::TrainingData& data,
                       const std::vector<sim::RadialEvaluation>& variants, int saved_variant,
                       const signal::CrossValidation& cv, const signal::OrientationModel& om,
                       double wall_s) {
  const sim::WhiskerRig::Options& rig = proto.rig;
  const RadialCounts rc = countRadial(data.radial);
  const OrientationSummary os = summariseOrientation(data.orientation);
  ordered_json j;
  j["schema"] = "crunch.training_report/1";
  j["command"] =
      "crunchhost train --seed " + std::to_string(opt.seed) + " --radial-f1 " + opt.radial_f1;
  j["seed"] = opt.seed;
  j["timing"] = {{"wall_s", wall_s},
                 {"simulated_s", data.simulated_s},
                 {"real_time_factor", wall_s > 0 ? data.simulated_s / wall_s : 0.0},
                 {"whisks", proto.plannedWhisks()}};
  j["rig"] = {{"min_onset_threshold_rad", rig.pipeline.detector.min_onset_threshold},
              {"onset_sigmas", rig.pipeline.detector.onset_sigmas},
              {"window_samples", rig.pipeline.window.samples},
              {"window_decimation", rig.pipeline.window.decimation},
              {"max_episode_samples", rig.pipeline.max_episode_samples},
              {"whisk",
               {{"kind", "in place, counter-clockwise first"},
                {"rate_rad_s", kPi / 24},
                {"amplitude_rad", kPi / 12}}},
              {"max_settle_s", proto.max_settle_s},
              {"missing_bridge_frames", data.missing_frames}};
  j["detector_threshold_evidence"] = {
      {"max_free_whisker_theta_rad", std::max(rc.max_free_theta, os.max_free_theta)},
      {"min_detected_contact_f1_rad", rc.min_f1},
      {"onset_threshold_rad", rig.pipeline.detector.min_onset_threshold}};

  ordered_json radial;
  radial["protocol"] = {{"whiskers", proto.radial_whiskers},
                        {"nominal_distances_m", proto.radial_distances},
                        {"repeats", proto.radial_repeats},
                        {"eps_range_rad", {proto.eps_min, proto.eps_max}},
                        {"distance_jitter_m", proto.distance_jitter},
                        {"heldout_set", proto.radial_heldout}};
  radial["counts"] = {{"training_contacts", rc.training},
                      {"heldout_contacts", rc.heldout},
                      {"no_episode", rc.no_episode},
                      {"whisker_not_detected", rc.not_detected},
                      {"truth_did_not_touch", rc.truth_not_touched},
                      {"more_than_one_episode", rc.multi_episode},
                      {"peak_on_a_later_pass", rc.peak_not_first},
                      {"another_whisker_touched", rc.other_touched},
                      {"truncated_or_finished_early", rc.truncated}};
  radial["paper"] = {
      {"sigma_mm", {kPaperSigmaMm[0], kPaperSigmaMm[1], kPaperSigmaMm[2], kPaperSigmaMm[3]}},
      {"combo_mm", kPaperComboMm}};
  radial["saved_variant"] = saved_variant;
  ordered_json vs = ordered_json::array();
  for (const sim::RadialEvaluation& ev : variants) vs.push_back(variantJson(ev));
  radial["variants"] = vs;
  radial["data"] = radialDataJson(data.radial);
  j["radial"] = radial;

  ordered_json orient;
  orient["protocol"] = {{"angles_deg",
                         [&] {
                           std::vector<double> a;
                           for (double x : proto.angles) a.push_back(x * kDeg);
                           return a;
                         }()},
                        {"repeats", proto.orientation_repeats},
                        {"depth_range_m", {proto.depth_min, proto.depth_max}},
                        {"lateral_jitter_m", proto.lateral_jitter},
                        {"label", "wall tangent relative to the heading at the whisk's start"}};
  orient["counts"] = {{"contacts", os.contacts},
                      {"windows", os.windows},
                      {"no_episode", os.no_episode},
                      {"incomplete_window", os.incomplete}};
  orient["first_onset"] = {{"mean_s_after_start", os.mean_onset_s},
                           {"max_s_after_start", os.max_onset_s},
                           {"mean_heading_offset_deg", os.mean_onset_offset * kDeg},
                           {"max_abs_heading_offset_deg", os.max_abs_onset_offset * kDeg}};
  ordered_json per = ordered_json::array();
  for (const signal::AngleErrors& a : cv.per_angle) {
    std::vector<double> e;
    for (double x : a.errors) e.push_back(x * kDeg);
    per.push_back({{"angle_deg", a.angle * kDeg},
                   {"mean_deg", a.mean * kDeg},
                   {"sd_deg", a.sd * kDeg},
                   {"errors_deg", e}});
  }
  ordered_json trials = ordered_json::array();
  for (const signal::OrientationTrial& t : cv.trials) {
    trials.push_back({{"repeat", t.repeat},
                      {"true_deg", t.true_angle * kDeg},
                      {"estimated_deg", t.estimated_angle * kDeg},
                      {"error_deg", t.error * kDeg}});
  }
  orient["leave_one_repeat_out"] = {{"mean_error_deg", cv.mean_error * kDeg},
                                    {"sd_error_deg", cv.sd_error * kDeg},
                                    {"accuracy", cv.accuracy},
                                    {"per_angle", per},
                                    {"trials", trials}};
  orient["paper"] = {{"mean_error_deg", kPaperMeanDeg}, {"sd_error_deg", kPaperSdDeg}};
  orient["final_templates"] = {
      {"classes", om.templates.size()}, {"decimation", om.decimation}, {"columns", om.columns}};
  ordered_json od = ordered_json::array();
  for (const sim::OrientationContact& c : data.orientation) {
    od.push_back({{"repeat", c.repeat},
                  {"angle_deg", c.angle * kDeg},
                  {"depth", c.depth},
                  {"lateral", c.lateral},
                  {"pose", {c.pose.x, c.pose.y, c.pose.theta}},
                  {"episodes", c.episodes},
                  {"has_window", c.has_window},
                  {"onset_s", c.onset_s},
                  {"onset_heading_offset_deg", c.onset_offset * kDeg},
                  {"touched_mask", c.touched_mask},
                  {"max_free_theta", c.max_free_theta}});
  }
  orient["data"] = od;
  j["orientation"] = orient;
  return j.dump(1) + "\n";
}

}  // namespace

int runTrain(const TrainOptions& opt, std::ostream& out, std::ostream& err) {
  // ---- Options and outputs, before anything is collected.
  sim::TrainingOptions proto = opt.protocol;
  proto.seed = opt.seed;
  if (opt.radial_f1 != "max" && opt.radial_f1 != "first") {
    err << "crunchhost train: --radial-f1: '" << opt.radial_f1 << "' (expected max or first)\n";
    return 2;
  }
  if (auto s = proto.validate(); !s) {
    err << "crunchhost train: " << s.error().message << "\n";
    return 2;
  }
  if (opt.out_dir.empty()) {
    err << "crunchhost train: --out: the directory name is empty\n";
    return 2;
  }
  if (auto s = checkWritableDir(opt.out_dir); !s) {
    err << "crunchhost train: --out: " << s.error().message << "\n";
    return 2;
  }
  if (!opt.models_out.empty()) {
    if (auto s = checkModelsOut(opt.models_out); !s) {
      err << "crunchhost train: " << s.error().message << "\n";
      return 2;
    }
  }

  // ---- Collect.
  Progress progress(opt.json_progress ? out : err, opt.json_progress);
  proto.progress = [&progress](const sim::TrainingProgress& p) { progress(p); };
  auto collected = sim::collectTrainingData(proto);
  if (!collected) {
    err << "crunchhost train: " << collected.error().message << "\n";
    return 1;
  }
  const sim::TrainingData& data = collected.value();

  // ---- Fit and evaluate.
  std::vector<sim::RadialEvaluation> variants;
  for (const sim::RadialVariant& v : sim::allRadialVariants()) {
    auto ev = sim::evaluateRadial(data.radial, v);
    if (!ev) {
      err << "crunchhost train: " << ev.error().message << "\n";
      return 1;
    }
    variants.push_back(std::move(ev).value());
  }
  const sim::F1Source saved_source =
      opt.radial_f1 == "first" ? sim::F1Source::kFirstEpisode : sim::F1Source::kMaxOverWhisk;
  int saved = -1, first_pass = -1;
  for (size_t i = 0; i < variants.size(); ++i) {
    const sim::RadialVariant& v = variants[i].variant;
    if (v.feature != sim::RadialFeature::kF1 || v.label != sim::RadialLabel::kTruthAtPeak) continue;
    if (v.source == saved_source) saved = static_cast<int>(i);
    if (v.source == sim::F1Source::kFirstEpisode) first_pass = static_cast<int>(i);
  }
  const sim::RadialEvaluation& protocol_ev = variants.front();  // max, f1, truth
  const std::vector<signal::LabelledWindow> windows = sim::labelledWindows(data.orientation);
  auto cv = signal::leaveOneRepeatOut(windows);
  if (!cv) {
    err << "crunchhost train: orientation cross-validation: " << cv.error().message << "\n";
    return 1;
  }
  auto templates = signal::trainOrientationTemplates(windows);
  if (!templates) {
    err << "crunchhost train: orientation templates: " << templates.error().message << "\n";
    return 1;
  }
  signal::SignalModels models;
  models.radial = variants[static_cast<size_t>(saved)].fit.model;
  models.orientation = std::move(templates).value();
  models.pipeline = proto.rig.pipeline;  // what the models were trained with travels with them
  if (auto s = signal::validateModels(models); !s) {
    err << "crunchhost train: the fitted models are not valid: " << s.error().message << "\n";
    return 1;
  }

  // ---- Write: each file complete or not at all, stopping at the first failure.
  const std::string dir = opt.out_dir + "/";
  const Chart fig9 = fig9Chart(data.radial, variants[static_cast<size_t>(saved)]);
  const Chart table1 = table1Chart(protocol_ev, variants[static_cast<size_t>(first_pass)]);
  const Chart fig10 = fig10Chart(cv.value());
  const double wall_s = progress.elapsed();
  const std::string report =
      reportJson(opt, proto, data, variants, saved, cv.value(), models.orientation, wall_s);
  std::vector<std::pair<std::string, std::function<Status()>>> writes = {
      {"fig9", [&] { return renderChartPng(fig9, dir + "fig9_peak_deflection.png"); }},
      {"fig9", [&] { return renderChartSvg(fig9, dir + "fig9_peak_deflection.svg"); }},
      {"table1", [&] { return renderChartPng(table1, dir + "table1_radial_sigma.png"); }},
      {"table1", [&] { return renderChartSvg(table1, dir + "table1_radial_sigma.svg"); }},
      {"fig10", [&] { return renderChartPng(fig10, dir + "fig10_orientation_error.png"); }},
      {"fig10", [&] { return renderChartSvg(fig10, dir + "fig10_orientation_error.svg"); }},
      {"report", [&] { return writeFileAtomic(dir + "training_report.json", report); }},
      {"models", [&] { return signal::saveModels(models, dir + "models.json"); }}};
  if (!opt.models_out.empty()) {
    writes.push_back({"models-out", [&] { return signal::saveModels(models, opt.models_out); }});
  }
  for (const auto& [name, write] : writes) {
    if (const Status s = write(); !s) {
      err << "crunchhost train: " << s.error().message << "\n";
      return 1;
    }
  }

  const sim::RadialEvaluation& sv = variants[static_cast<size_t>(saved)];
  if (opt.json_progress) {
    out << "{\"event\":\"done\",\"radial_sigma_all_mm\":" << sv.heldout_rms_all * 1e3
        << ",\"orientation_mean_deg\":" << cv.value().mean_error * kDeg
        << ",\"orientation_sd_deg\":" << cv.value().sd_error * kDeg << ",\"wall_s\":" << wall_s
        << ",\"out\":\"" << opt.out_dir << "\"}\n";
  } else {
    char line[400];
    out << "radial distance, held-out sigma (mm), f1 = " << opt.radial_f1
        << " (paper 2.78 1.82 4.37 5.68, combo 4.98):";
    for (int w = 0; w < 4; ++w) {
      std::snprintf(line, sizeof line, " %.2f", sv.heldout_rms[static_cast<size_t>(w)] * 1e3);
      out << line;
    }
    std::snprintf(line, sizeof line, ", all %.2f\n", sv.heldout_rms_all * 1e3);
    out << line;
    std::snprintf(line, sizeof line,
                  "orientation, leave one repeat out: mean %.1f deg, sd %.1f deg, %.0f%% right "
                  "(paper -2.2, 21.2)\n",
                  cv.value().mean_error * kDeg, cv.value().sd_error * kDeg,
                  cv.value().accuracy * 100.0);
    out << line;
    out << "collected " << proto.plannedWhisks() << " whisks (" << std::lround(data.simulated_s)
        << " s simulated) in " << formatDuration(wall_s) << "; wrote " << dir
        << "{models.json,training_report.json,fig9_peak_deflection,table1_radial_sigma,"
           "fig10_orientation_error}"
        << (opt.models_out.empty() ? "" : " and " + opt.models_out) << "\n";
  }
  return 0;
}

}  // namespace crunch::app
