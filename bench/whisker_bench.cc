// Google Benchmark targets for the bending-whisker physics (issue 4). Results and how to run
// them: docs/BENCHMARKS.md ("Whisker physics").
//
//   BM_WhiskAgainstWall   real-time factor of WhiskeredRobot with the four default whiskers
//                         during a body whisk against a wall (§2.3): place the base 0.31 m from
//                         the wall facing it, drive 30 mm closer at 0.1 m/s so the middle
//                         whiskers press on it, then turn toward at pi/24 rad/s by pi/12, away
//                         through the start to -pi/12 and back (8.3 s simulated per iteration).
//   BM_FreeWhiskers       the baseline in the same run: the same motion in the middle of an
//                         empty arena, no contact.
// Both take the number of beam elements per whisker (the default is 4) so speed can be set
// against accuracy: the counter beam_err_pct is the worst base-angle error against beam theory
// over d = 90..138 mm at that element count (crunch::sim::pushWhisker, measured once before
// timing, not timed).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <memory>
#include <vector>

#include "crunch/core/geometry.h"
#include "crunch/robot/shapelet.h"
#include "crunch/scene/scene.h"
#include "crunch_sim/beam_probe.h"
#include "crunch_sim/whisker_physics.h"
#include "crunch_sim/world.h"

namespace {

using crunch::kPi;
using crunch::sim::WhiskeredRobot;

crunch::Scene emptyArena() {
  crunch::Scene s;
  s.width = 4.0;
  s.depth = 4.0;
  return s;
}

WhiskeredRobot::Options optionsFor(const benchmark::State& state) {
  WhiskeredRobot::Options o;
  o.elements = static_cast<int>(state.range(0));
  return o;
}

double worstBeamError(const WhiskeredRobot::Options& o) {
  double worst = 0.0;
  for (const double d : {0.090, 0.100, 0.110, 0.120, 0.130, 0.138}) {
    const auto r = crunch::sim::pushWhisker(o, d, 0.005);
    if (!r) return NAN;
    worst = std::max(worst, std::abs(r.value().relativeError()));
  }
  return worst;
}

double threadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

struct RunStats {
  long long steps = 0;
  long long contact_steps = 0;  // steps in which some whisker touched
};

// One approach and body whisk from `start`; returns the simulated seconds.
double whisk(WhiskeredRobot& robot, const crunch::Pose2& start, RunStats& stats) {
  robot.place(start);
  const double rate = kPi / 24.0, amplitude = kPi / 12.0;
  const struct {
    double v, omega, seconds;
  } phases[] = {{0.1, 0.0, 0.3},
                {0.0, rate, amplitude / rate},
                {0.0, -rate, 2.0 * amplitude / rate},
                {0.0, rate, amplitude / rate}};
  double simulated = 0.0;
  for (const auto& ph : phases) {
    (void)robot.drive(ph.v, ph.omega);
    const int steps = static_cast<int>(std::lround(ph.seconds / robot.options().dt));
    for (int i = 0; i < steps; ++i) {
      robot.step();
      bool touching = false;
      for (int w = 0; w < robot.whiskerCount(); ++w) touching |= robot.contactCount(w) > 0;
      stats.contact_steps += touching ? 1 : 0;
    }
    stats.steps += steps;
    simulated += steps * robot.options().dt;
  }
  return simulated;
}

void runWhisk(benchmark::State& state, const crunch::Pose2& start) {
  const WhiskeredRobot::Options options = optionsFor(state);
  const auto world = crunch::sim::World::build(emptyArena());
  auto robot = std::move(
      WhiskeredRobot::create(*world, crunch::defaultWhiskerArray(), options).value());
  const double beam_err = worstBeamError(options);
  RunStats warm;
  whisk(*robot, start, warm);  // warm-up: ODE's step and contact arenas grown
  RunStats stats;
  double simulated = 0.0;
  const double cpu0 = threadCpuSeconds();
  for (auto _ : state) simulated += whisk(*robot, start, stats);
  const double cpu = threadCpuSeconds() - cpu0;
  // Simulated seconds per second of wall time, and per second of this thread's CPU time (the
  // latter is what one core delivers when the machine is shared and the thread gets preempted).
  state.counters["rtf"] = benchmark::Counter(simulated, benchmark::Counter::kIsRate);
  state.counters["rtf_cpu"] = simulated / cpu;
  // Microseconds of real time per 0.5 ms step: (steps / 1e6 per second) inverted.
  state.counters["us_per_step"] =
      benchmark::Counter(1e-6 * static_cast<double>(stats.steps),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["contact_frac"] =
      static_cast<double>(stats.contact_steps) / static_cast<double>(std::max(1LL, stats.steps));
  state.counters["refined_steps"] = static_cast<double>(robot->refinedSteps());
  state.counters["beam_err_pct"] = 100.0 * beam_err;
}

// The middle whiskers (+-11.25 deg) reach 0.299 m ahead: 0.31 m from the wall y = 4 they are
// clear, 30 mm closer they press 19 mm into it.
void BM_WhiskAgainstWall(benchmark::State& state) { runWhisk(state, {2.0, 3.69, 0.5 * kPi}); }
BENCHMARK(BM_WhiskAgainstWall)
    ->ArgName("elements")
    ->Arg(4)
    ->Arg(5)
    ->Arg(6)
    ->Arg(8)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_FreeWhiskers(benchmark::State& state) { runWhisk(state, {2.0, 2.0, 0.5 * kPi}); }
BENCHMARK(BM_FreeWhiskers)
    ->ArgName("elements")
    ->Arg(4)
    ->Arg(8)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
