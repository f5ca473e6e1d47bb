// beam_validation: the ODE whisker chain against tapered-cantilever theory (docs/WHISKERS.md).
//
//   beam_validation [OUT.png]
//
// Pushes whisker 2 sideways by 5 mm at distances d along it (crunch::sim::pushWhisker: a leg
// edge moved by the body whisk's rotation, then held while the whisker settles), with the
// default chain and a finer one, prints the simulated and predicted base angles, and charts them
// against WhiskerBeam::baseAngle, and their relative errors in OUT_error.png. Default output:
// docs/img/beam_validation.png (and beam_validation_error.png) in the source tree. Exit status 0 when every d in 90-140 mm is within 15 % with the default chain, 1 if
// not, 2 on a usage or file error.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "crunch/render/chart.h"
#include "crunch_sim/beam_probe.h"
#include "crunch_sim/whisker_physics.h"

namespace {

constexpr double kDelta = 0.005;  // sideways push, metres
constexpr double kDeg = 180.0 / crunch::kPi;
constexpr double kTolerance = 0.15;
const std::vector<double> kDistances = {0.020, 0.030, 0.050, 0.070, 0.090, 0.100,
                                        0.110, 0.120, 0.130, 0.135, 0.138};

}  // namespace

int main(int argc, char** argv) {
  using crunch::sim::WhiskeredRobot;
  if (argc > 2 || (argc == 2 && std::string(argv[1]).rfind("-", 0) == 0)) {
    std::fprintf(stderr, "usage: %s [OUT.png]\n", argv[0]);
    return 2;
  }
  const std::string out =
      argc == 2 ? argv[1] : std::string(CRUNCH_SOURCE_DIR) + "/docs/img/beam_validation.png";

  const WhiskeredRobot::Options coarse;  // the simulator's defaults
  WhiskeredRobot::Options fine;
  fine.elements = 10;

  crunch::ChartSeries theory, sim, sim_fine, err, err_fine;
  theory.label = "tapered cantilever on the follicle spring";
  theory.style = crunch::SeriesStyle::kLine;
  sim.label = "ODE chain, " + std::to_string(coarse.elements) + " elements (default)";
  sim.style = crunch::SeriesStyle::kPoints;
  sim.marker_size = 5.0;
  sim_fine.label = "ODE chain, " + std::to_string(fine.elements) + " elements";
  sim_fine.style = crunch::SeriesStyle::kPoints;
  sim_fine.marker = crunch::MarkerShape::kDiamond;
  sim_fine.marker_size = 4.0;
  for (double d = 0.015; d <= 0.1401; d += 0.0025) {
    theory.x.push_back(1000.0 * d);
    theory.y.push_back(kDeg * coarse.beam.baseAngle(kDelta, d));
  }

  std::printf("Base angle for a %.0f mm sideways push at d (friction off, settled 1 s)\n",
              1000.0 * kDelta);
  const std::string coarse_head = "N=" + std::to_string(coarse.elements) + " (deg)";
  const std::string fine_head = "N=" + std::to_string(fine.elements) + " (deg)";
  std::printf("%8s %12s %12s %9s %12s %9s %10s\n", "d (mm)", "theory(deg)", coarse_head.c_str(),
              "error", fine_head.c_str(), "error", "contact r");
  bool pass = true;
  double worst = 0.0;
  for (const double d : kDistances) {
    const auto a = crunch::sim::pushWhisker(coarse, d, kDelta);
    const auto b = crunch::sim::pushWhisker(fine, d, kDelta);
    if (!a || !b) {
      std::fprintf(stderr, "beam_validation: %s\n",
                   (!a ? a.error() : b.error()).message.c_str());
      return 2;
    }
    const crunch::sim::BeamPush& p = a.value();
    const crunch::sim::BeamPush& q = b.value();
    std::printf("%8.1f %12.3f %12.3f %+8.1f%% %12.3f %+8.1f%% %8.1f mm\n", 1000.0 * p.d,
                kDeg * p.predicted, kDeg * p.simulated, 100.0 * p.relativeError(),
                kDeg * q.simulated, 100.0 * q.relativeError(), 1000.0 * p.contact_r);
    sim.x.push_back(1000.0 * p.d);
    sim.y.push_back(kDeg * p.simulated);
    sim_fine.x.push_back(1000.0 * q.d);
    sim_fine.y.push_back(kDeg * q.simulated);
    err.x.push_back(1000.0 * p.d);
    err.y.push_back(100.0 * p.relativeError());
    err_fine.x.push_back(1000.0 * q.d);
    err_fine.y.push_back(100.0 * q.relativeError());
    if (d >= 0.09) {
      worst = std::max(worst, std::abs(p.relativeError()));
      pass = pass && std::abs(p.relativeError()) < kTolerance;
    }
  }
  std::printf("worst error over 90-140 mm with the default chain: %.1f %% (limit %.0f %%)\n",
              100.0 * worst, 100.0 * kTolerance);

  crunch::Chart chart;
  chart.options.title = "Whisker base angle for a 5 mm sideways push: ODE chain vs. beam theory";
  chart.options.x_label = "contact distance from the base d (mm)";
  chart.options.y_label = "base angle (deg)";
  chart.options.x_min = 0.0;
  chart.options.x_max = 140.0;
  chart.options.y_min = 0.0;
  chart.options.width_px = 900;
  chart.options.height_px = 540;
  chart.series = {theory, sim, sim_fine};
  // The same comparison as relative error, where the 90-140 mm band is legible.
  crunch::Chart errors;
  errors.options = chart.options;
  errors.options.title = "Relative error of the simulated base angle (5 mm push)";
  errors.options.y_label = "(simulated - theory) / theory (%)";
  errors.options.y_min = -20.0;
  errors.options.y_max = 20.0;
  errors.options.legend = crunch::LegendPosition::kTopLeft;
  err.label = sim.label;
  err.colour = crunch::chartPalette(1);
  err_fine.label = sim_fine.label;
  err_fine.colour = crunch::chartPalette(2);
  err_fine.marker = crunch::MarkerShape::kDiamond;
  crunch::ChartSeries upper, lower;
  upper.label = "the +-15 % tolerance, checked over 90-140 mm";
  upper.style = lower.style = crunch::SeriesStyle::kLine;
  upper.colour = lower.colour = crunch::ChartColour{0.5, 0.5, 0.5};
  upper.dashed = lower.dashed = true;
  upper.line_width = lower.line_width = 1.5;
  upper.x = lower.x = {90.0, 140.0};
  upper.y = {15.0, 15.0};
  lower.y = {-15.0, -15.0};
  errors.series = {upper, lower, err, err_fine};

  std::string out_err = out;
  const auto dot = out_err.rfind('.');
  out_err.insert(dot == std::string::npos ? out_err.size() : dot, "_error");
  for (const auto& [c, path] : {std::pair{&chart, out}, {&errors, out_err}}) {
    if (crunch::Status s = crunch::renderChartPng(*c, path); !s) {
      std::fprintf(stderr, "beam_validation: %s\n", s.error().message.c_str());
      return 2;
    }
    std::printf("wrote %s\n", path.c_str());
  }
  return pass ? 0 : 1;
}
