#include "crunch_sim/training_report.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <nlohmann/json.hpp>
#include <utility>

namespace crunch::sim {

namespace {

using nlohmann::ordered_json;

constexpr double kDeg = 180.0 / kPi;

// One bar per whisker (x = 1..4, 5 = all together) shifted by `offset`, drawn as thick lines.
ChartSeries barSeries(const std::string& label, ChartColour colour, double offset,
                      const std::array<double, 5>& values, double line_width) {
  ChartSeries s;
  s.label = label;
  s.style = SeriesStyle::kLine;
  s.colour = colour;
  s.line_width = line_width;
  for (int i = 0; i < 5; ++i) {
    const double x = i + 1 + offset;
    s.x.insert(s.x.end(), {x, x, NAN});
    s.y.insert(s.y.end(), {0.0, values[static_cast<size_t>(i)], NAN});
  }
  return s;
}

ordered_json facesJson(const FaceEvaluation& f);

ordered_json lineJson(const signal::RadialLine& l) {
  return {{"a1", l.a1},         {"a0", l.a0},         {"sigma_m", l.sigma}, {"samples", l.samples},
          {"f1_min", l.f1_min}, {"f1_max", l.f1_max}, {"r_min", l.r_min},   {"r_max", l.r_max}};
}

ordered_json variantJson(const RadialEvaluation& ev) {
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
  return {{"f1", f1SourceName(ev.variant.source)},
          {"feature", radialFeatureName(ev.variant.feature)},
          {"label", radialLabelName(ev.variant.label)},
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

RadialCounts countRadial(const std::vector<RadialContact>& contacts) {
  RadialCounts c;
  bool first = true;
  for (const RadialContact& r : contacts) {
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

ordered_json radialDataJson(const std::vector<RadialContact>& contacts) {
  ordered_json a = ordered_json::array();
  for (const RadialContact& c : contacts) {
    ordered_json eps = ordered_json::array();
    for (const EpisodeRecord& e : c.episodes) {
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

OrientationSummary summariseOrientation(const std::vector<OrientationContact>& cs) {
  OrientationSummary s;
  for (const OrientationContact& c : cs) {
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

ChartColour grey() { return {0.55, 0.55, 0.55}; }


ordered_json radialJson(const TrainingOptions& proto, const TrainingData& data,
                        const TrainingFit& fit, const RadialCounts& rc) {
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
  radial["saved_variant"] = static_cast<int>(fit.saved);
  ordered_json vs = ordered_json::array();
  for (const RadialEvaluation& ev : fit.variants) vs.push_back(variantJson(ev));
  radial["variants"] = vs;
  radial["data"] = radialDataJson(data.radial);
  return radial;
}

ordered_json crossValidationJson(const signal::CrossValidation& cv) {
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
  return {{"mean_error_deg", cv.mean_error * kDeg},
          {"sd_error_deg", cv.sd_error * kDeg},
          {"accuracy", cv.accuracy},
          {"per_angle", per},
          {"trials", trials}};
}

ordered_json orientationDataJson(const std::vector<OrientationContact>& contacts) {
  ordered_json od = ordered_json::array();
  for (const OrientationContact& c : contacts) {
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
  return od;
}

ordered_json orientationJson(const TrainingOptions& proto, const TrainingData& data,
                             const TrainingFit& fit, const OrientationSummary& os) {
  ordered_json orient;
  std::vector<double> angles_deg;
  for (double x : proto.angles) angles_deg.push_back(x * kDeg);
  orient["protocol"] = {{"angles_deg", angles_deg},
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
  orient["leave_one_repeat_out"] = crossValidationJson(fit.cv);
  orient["faces_from_ramps"] = facesJson(fit.faces);
  orient["paper"] = {{"mean_error_deg", kPaperMeanDeg}, {"sd_error_deg", kPaperSdDeg}};
  const signal::OrientationModel& om = fit.models.orientation;
  orient["final_templates"] = {
      {"classes", om.templates.size()}, {"decimation", om.decimation}, {"columns", om.columns}};
  orient["data"] = orientationDataJson(data.orientation);
  return orient;
}

ordered_json statsJson(const ErrorStats& e) {
  ordered_json per = ordered_json::array();
  for (int w = 0; w < signal::kWhiskers; ++w) {
    const auto i = static_cast<size_t>(w);
    per.push_back({{"whisker", w}, {"rms_mm", e.rms[i] * 1e3}, {"mean_mm", e.mean[i] * 1e3},
                   {"contacts", e.n[i]}});
  }
  return {{"rms_mm", e.rms_all * 1e3},       {"mean_mm", e.mean_all * 1e3},
          {"median_abs_mm", e.median_abs * 1e3}, {"p90_abs_mm", e.p90_abs * 1e3},
          {"contacts", e.n_all},             {"per_whisker", per}};
}

ordered_json rampJson(const TrainingOptions& proto, const TrainingData& data,
                      const TrainingFit& fit) {
  const RampEvaluation& ev = fit.ramp;
  ordered_json r;
  r["protocol"] = {{"whiskers", proto.ramp_whiskers},
                   {"nominal_distances_m", proto.ramp_distances},
                   {"objects", {"leg 5 cm (a table's), met at its edge", "post 2 cm, met at its edge"}},
                   {"directions", proto.ramp_both_directions ? 2 : 1},
                   {"repeats", proto.ramp_repeats},
                   {"eps_range_rad", {proto.eps_min, proto.eps_max}},
                   {"edge_range_rad", {proto.edge_min, proto.edge_max}},
                   {"distance_jitter_m", proto.distance_jitter},
                   {"label", "true distance at the contact's first step (r_at_touch)"}};
  r["fit"] = {{"objective", "least squares of the distance read (clamped as the host reads it) "
                            "minus the truth"},
              {"gain", ev.fit.gain},
              {"compliance_scale", ev.fit.compliance_scale},
              {"gain_se", ev.fit.gain_se},
              {"compliance_scale_se", ev.fit.compliance_scale_se},
              {"samples", ev.fit.samples},
              {"used", ev.fit.used},
              {"outliers", ev.fit.outliers},
              {"iterations", ev.fit.iterations},
              {"training_rms_nominal_mm", ev.fit.rms_nominal * 1e3},
              {"training_mean_nominal_mm", ev.fit.mean_nominal * 1e3},
              {"training_rms_mm", ev.fit.rms * 1e3},
              {"training_mean_mm", ev.fit.mean * 1e3}};
  r["heldout"] = {{"contacts", ev.heldout_contacts},
                  {"not_seen_touching", ev.heldout_not_seen},
                  {"no_ramp", ev.heldout_no_ramp},
                  {"ramp_nominal", statsJson(ev.nominal)},
                  {"ramp_fitted", statsJson(ev.fitted)},
                  {"eq2_truth_at_peak", statsJson(ev.eq2)}};
  r["radial_protocol_heldout"] = {{"ramp_nominal", statsJson(ev.radial_nominal)},
                                  {"ramp_fitted", statsJson(ev.radial_fitted)}};
  ordered_json a = ordered_json::array();
  const signal::RampCalibration nominal;
  for (const RampContact& c : data.ramp) {
    const LocatedContact& l = c.contact;
    ordered_json e = {{"set", c.set == 0 ? "training" : "heldout"},
                      {"whisker", c.whisker},
                      {"object", rampObjectName(c.object)},
                      {"direction", c.direction},
                      {"nominal_d", c.nominal_d},
                      {"d", c.d},
                      {"eps", c.eps},
                      {"edge", c.edge},
                      {"pose", {c.pose.x, c.pose.y, c.pose.theta}},
                      {"detected", l.detected},
                      {"truth_touched", l.truth_touched},
                      {"r_touch", l.r_touch},
                      {"r_peak", l.r_peak},
                      {"f1", l.f1},
                      {"ramp_valid", l.ramp.valid},
                      {"other_whiskers_touched_mask", c.other_touched}};
    if (l.ramp.valid) {
      e["slope"] = l.ramp.slope;
      e["ramp_points"] = l.ramp.points;
      e["ramp_residual_rms"] = l.ramp.residual_rms;
      e["r_ramp_nominal"] = rampDistance(l, c.lever, nominal);
      e["r_ramp_fitted"] = rampDistance(l, c.lever, ev.calibration);
    }
    a.push_back(e);
  }
  r["data"] = a;
  return r;
}

ordered_json facesJson(const FaceEvaluation& f) {
  ordered_json t = ordered_json::array();
  for (const FaceTrial& x : f.trials) {
    ordered_json e = {{"repeat", x.repeat}, {"true_deg", x.true_angle * kDeg},
                      {"located", x.located}, {"reports", x.reports}, {"tip_reports", x.tips}};
    if (x.located) e["error_deg"] = x.error * kDeg;
    t.push_back(e);
  }
  return {{"method", "two whiskers' tip contacts located by their ramps (WhiskEvidence)"},
          {"whisks", f.trials.size()},
          {"located", f.located},
          {"mean_error_deg", f.mean_error * kDeg},
          {"sd_error_deg", f.sd_error * kDeg},
          {"rms_error_deg", f.rms_error * kDeg},
          {"max_abs_error_deg", f.max_abs_error * kDeg},
          {"trials", t}};
}

}  // namespace

// ---- Charts.


Chart fig9Chart(const std::vector<RadialContact>& contacts, const RadialEvaluation& ev) {
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
    for (const RadialContact& r : contacts) {
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

Chart table1Chart(const RadialEvaluation& protocol, const RadialEvaluation& first) {
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
    return barSeries(label, colour, offset, values, 16.0);
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

Chart fig10Chart(const signal::CrossValidation& cv, const FaceEvaluation* faces) {
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
  if (faces != nullptr && faces->located > 0) {
    ChartSeries f;
    char label[160];
    std::snprintf(label, sizeof label,
                  "ramp: face from two whiskers' tips (%d of %zu whisks; mean %.2f, sd %.2f)",
                  faces->located, faces->trials.size(), faces->mean_error * kDeg,
                  faces->sd_error * kDeg);
    f.label = label;
    f.style = SeriesStyle::kPoints;
    f.marker = MarkerShape::kDiamond;
    f.colour = chartPalette(2);
    f.marker_size = 3.5;
    for (const FaceTrial& t : faces->trials) {
      if (!t.located) continue;
      f.x.push_back(t.true_angle * kDeg - 1.5 * (t.repeat - 1.5));
      f.y.push_back(t.error * kDeg);
    }
    c.series.push_back(f);
  }
  c.series.push_back(hline("paper: mean -2.2, +-1 sd (21.2)", kPaperMeanDeg, red, true));
  c.series.push_back(hline("", kPaperMeanDeg + kPaperSdDeg, red, true));
  c.series.push_back(hline("", kPaperMeanDeg - kPaperSdDeg, red, true));
  return c;
}

Chart rampDistanceChart(const TrainingData& data, const TrainingFit& fit) {
  Chart c;
  c.options.title = "Distance from the ramp against the true distance (held-out: legs, posts, both turns)";
  c.options.x_label = "true contact distance from the follicle (mm)";
  c.options.y_label = "estimated distance (mm)";
  c.options.width_px = 900;
  c.options.height_px = 620;
  c.options.legend = LegendPosition::kTopLeft;
  c.options.x_min = 0.0;
  c.options.x_max = 150.0;
  c.options.y_min = 0.0;
  c.options.y_max = 200.0;  // room for the legend; eq. 2 reads up to ~190 mm near the follicle
  ChartSeries diag;
  diag.label = "estimate = truth";
  diag.style = SeriesStyle::kLine;
  diag.colour = ChartColour{0, 0, 0};
  diag.line_width = 1.0;
  diag.dashed = true;
  diag.x = {0.0, 150.0};
  diag.y = {0.0, 150.0};
  ChartSeries eq2;
  eq2.label = "eq. 2 on f1 (saved lines; truth at the peak)";
  eq2.style = SeriesStyle::kPoints;
  eq2.marker = MarkerShape::kTriangle;
  eq2.colour = ChartColour{0.8, 0.1, 0.1};
  eq2.marker_size = 2.5;
  ChartSeries nominal;
  nominal.label = "ramp, nominal calibration";
  nominal.style = SeriesStyle::kPoints;
  nominal.colour = grey();
  nominal.marker_size = 2.0;
  ChartSeries leg, post;
  char label[160];
  std::snprintf(label, sizeof label, "ramp, fitted (gain %.3f, compliance x %.3f): legs",
                fit.ramp.calibration.gain, fit.ramp.calibration.compliance_scale);
  leg.label = label;
  leg.style = SeriesStyle::kPoints;
  leg.colour = chartPalette(0);
  leg.marker_size = 3.0;
  post.label = "ramp, fitted: 2 cm posts";
  post.style = SeriesStyle::kPoints;
  post.marker = MarkerShape::kSquare;
  post.colour = chartPalette(1);
  post.marker_size = 3.0;
  const signal::RampCalibration nominal_cal;
  for (const RampContact& r : data.ramp) {
    const LocatedContact& l = r.contact;
    if (r.set != 1 || !l.detected || !l.truth_touched) continue;
    const auto wi = static_cast<std::size_t>(r.whisker);
    eq2.x.push_back(l.r_peak * 1e3);
    eq2.y.push_back(fit.models.radial.whiskers[wi].predict(l.f1) * 1e3);
    if (!l.ramp.valid) continue;
    nominal.x.push_back(l.r_touch * 1e3);
    nominal.y.push_back(rampDistance(l, r.lever, nominal_cal) * 1e3);
    ChartSeries& s = r.object == RampObject::kLeg ? leg : post;
    s.x.push_back(l.r_touch * 1e3);
    s.y.push_back(rampDistance(l, r.lever, fit.ramp.calibration) * 1e3);
  }
  c.series = {diag, eq2, nominal, leg, post};
  return c;
}

Chart table1RampChart(const TrainingFit& fit) {
  Chart c;
  c.options.title = "Table 1 re-measured: sigma of r on held-out contacts";
  c.options.x_label = "whisker (5 = all whiskers together)";
  c.options.y_label = "rms of r error (mm)";
  c.options.width_px = 1000;
  c.options.height_px = 560;
  c.options.x_min = 0.4;
  c.options.x_max = 5.6;
  c.options.y_min = 0.0;
  c.options.y_max = 12.0;
  c.options.legend = LegendPosition::kTopLeft;
  auto bars = [](const std::string& label, ChartColour colour, double offset,
                 const std::array<double, 5>& values) {
    return barSeries(label, colour, offset, values, 11.0);
  };
  auto mm = [](const ErrorStats& e) {
    std::array<double, 5> v{};
    for (int w = 0; w < 4; ++w) v[static_cast<size_t>(w)] = e.rms[static_cast<size_t>(w)] * 1e3;
    v[4] = e.rms_all * 1e3;
    return v;
  };
  std::array<double, 5> paper{}, today{};
  const RadialEvaluation& first = fit.variants[fit.first_pass];
  for (int w = 0; w < 4; ++w) {
    paper[static_cast<size_t>(w)] = kPaperSigmaMm[w];
    today[static_cast<size_t>(w)] = first.heldout_rms[static_cast<size_t>(w)] * 1e3;
  }
  paper[4] = kPaperComboMm;
  today[4] = first.heldout_rms_all * 1e3;
  char eq2_label[160];
  std::snprintf(eq2_label, sizeof eq2_label,
                "eq. 2 over the whole length (off the scale: all %.0f mm)",
                fit.ramp.eq2.rms_all * 1e3);
  c.series.push_back(bars("paper (CrunchBot, 85-135 mm, eq. 2)", grey(), -0.35, paper));
  c.series.push_back(bars("today: eq. 2 at the peak, paper's pole protocol (85-135 mm)",
                          chartPalette(3), -0.21, today));
  c.series.push_back(bars("ramp, fitted, paper's pole protocol (truth at the touch)",
                          chartPalette(4), -0.07, mm(fit.ramp.radial_fitted)));
  c.series.push_back(bars("ramp, nominal, whole length (legs, posts, both turns)",
                          ChartColour{0.7, 0.7, 0.7}, 0.07, mm(fit.ramp.nominal)));
  c.series.push_back(bars("ramp, fitted, whole length", chartPalette(0), 0.21, mm(fit.ramp.fitted)));
  c.series.push_back(bars(eq2_label, ChartColour{0.8, 0.1, 0.1}, 0.35, mm(fit.ramp.eq2)));
  return c;
}

Result<F1Source> f1SourceByName(const std::string& name) {
  if (name == "max") return F1Source::kMaxOverWhisk;
  if (name == "first") return F1Source::kFirstEpisode;
  return Error{"--radial-f1: '" + name + "' (expected max or first)"};
}

Result<TrainingFit> fitTrainingModels(const TrainingData& data, const TrainingOptions& proto,
                                      F1Source saved_source) {
  TrainingFit fit;
  fit.saved_source = saved_source;
  for (const RadialVariant& v : allRadialVariants()) {
    auto ev = evaluateRadial(data.radial, v);
    if (!ev) return ev.error();
    fit.variants.push_back(std::move(ev).value());
  }
  for (size_t i = 0; i < fit.variants.size(); ++i) {
    const RadialVariant& v = fit.variants[i].variant;
    if (v.feature != RadialFeature::kF1 || v.label != RadialLabel::kTruthAtPeak) continue;
    if (v.source == saved_source) fit.saved = i;
    if (v.source == F1Source::kFirstEpisode) fit.first_pass = i;
  }
  const std::vector<signal::LabelledWindow> windows = labelledWindows(data.orientation);
  auto cv = signal::leaveOneRepeatOut(windows);
  if (!cv) return Error{"orientation cross-validation: " + cv.error().message};
  fit.cv = std::move(cv).value();
  auto templates = signal::trainOrientationTemplates(windows);
  if (!templates) return Error{"orientation templates: " + templates.error().message};
  fit.models.radial = fit.variants[fit.saved].fit.model;
  fit.models.orientation = std::move(templates).value();
  fit.models.pipeline = proto.rig.pipeline;  // what the models were trained with travels with them
  if (!data.ramp.empty()) {
    auto ramp = evaluateRamp(data, fit.models.radial);
    if (!ramp) return ramp.error();
    fit.ramp = std::move(ramp).value();
    fit.has_ramp = true;
    fit.models.ramp = fit.ramp.calibration;
  }
  if (auto s = signal::validateModels(fit.models); !s)
    return Error{"the fitted models are not valid: " + s.error().message};
  fit.faces = evaluateFaces(data.orientation, fit.models);
  return fit;
}

Status writeTrainingFigures(const std::string& dir, const TrainingData& data,
                            const TrainingFit& fit) {
  const std::pair<std::string, Chart> charts[] = {
      {"fig9_peak_deflection", fig9Chart(data.radial, fit.variants[fit.saved])},
      {"table1_radial_sigma", table1Chart(fit.variants.front(), fit.variants[fit.first_pass])},
      {"fig10_orientation_error", fig10Chart(fit.cv, &fit.faces)}};
  std::vector<std::pair<std::string, Chart>> all(std::begin(charts), std::end(charts));
  if (fit.has_ramp) {
    all.emplace_back("ramp_distance", rampDistanceChart(data, fit));
    all.emplace_back("table1_ramp_sigma", table1RampChart(fit));
  }
  for (const auto& [name, chart] : all) {
    if (Status s = renderChartPng(chart, dir + "/" + name + ".png"); !s) return s;
    if (Status s = renderChartSvg(chart, dir + "/" + name + ".svg"); !s) return s;
  }
  return okStatus();
}

std::string trainingReportJson(const TrainingOptions& proto, const TrainingData& data,
                               const TrainingFit& fit, double wall_s) {
  const WhiskerRig::Options& rig = proto.rig;
  const RadialCounts rc = countRadial(data.radial);
  const OrientationSummary os = summariseOrientation(data.orientation);
  ordered_json j;
  j["schema"] = "crunch.training_report/1";
  j["command"] = "crunchhost train --seed " + std::to_string(proto.seed) + " --radial-f1 " +
                 (fit.saved_source == F1Source::kFirstEpisode ? "first" : "max");
  j["seed"] = proto.seed;
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
  j["radial"] = radialJson(proto, data, fit, rc);
  j["orientation"] = orientationJson(proto, data, fit, os);
  if (fit.has_ramp) j["ramp"] = rampJson(proto, data, fit);
  return j.dump(1) + "\n";
}

}  // namespace crunch::sim
