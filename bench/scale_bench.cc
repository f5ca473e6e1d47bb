// Scale benchmark (issue 6, "Scale"): cost per proposal and memory of the global inference
// against the number of shapelets N, from 10^2 to 10^5 (the large floor). Results and the
// command: docs/RESULTS.md ("Scale") and docs/BENCHMARKS.md.
//
// One point = one N, measured in a fresh child process (this program re-executed with
// --point N) so that its peak resident set is its own:
//   - a synthetic floor of ceil(N / 8K) tables (K = 10 shapelets per face by default) with random orientations on a square grid 2 m
//     apart (the floor grows with N at constant table density); each table is sensed on the two
//     outward faces of each of its four legs, K shapelets per face, N shapelets in all. A
//     shapelet lies at a uniform place along its face, displaced along the face normal by
//     N(0, 5 mm) (sigma_r) with its orientation perturbed by N(0, pi/32) (sigma_phi), sensed
//     from 0.1 m outside the face;
//   - a Blackboard holding all N shapelets in working memory, sized as the global inference of
//     host/src/mapping/mapper.cc sizes it: Blackboard(model, N, 4 N + 64), starting empty;
//   - a Sampler with the default options (the 16-temperature schedule beta = e^{7.5 - 0.5 i},
//     one sweep per temperature): anneal() is what is timed. Small N repeat the anneal on fresh
//     boards (built outside the timed region) until about 30 000 shapelets' worth of anneals
//     have run, so every point times a comparable amount of work.
// Measured: wall and thread-CPU ns per proposal (over all timed anneals), live tables and legs
// at the end of the first anneal, and the peak-RSS growth of the child across building and
// annealing the first board (getrusage ru_maxrss after minus before; the shapelet list is
// generated before the "before" reading). RSS counts resident pages, so it is what the board
// and sampler actually touched, rounded to pages: at small N it is dominated by page
// granularity and allocator slack.
//
// The baseline of the same run: N = 100 measured first and again last (drift check on a busy
// machine); the two must agree for the curve between them to be trusted.
//
// Usage: scale_bench [--max N] [--seed S] [--per-face K] [--chart PREFIX]
//   --max N        largest N of the list 1e2, 3e2, ..., 1e5 to run (default 100000)
//   --per-face K   shapelets per sensed leg face (default 10): the local density of evidence
//   --chart PREFIX writes PREFIX.png (ns per proposal against log10 N) and PREFIX_memory.png
//                  (resident bytes per shapelet against log10 N)
//   --point N      (internal) measure one point and print it as one line
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>
#include <vector>

#include "../test/blackboard/test_builders.h"
#include "crunch/blackboard/blackboard.h"
#include "crunch/blackboard/params.h"
#include "crunch/blackboard/sampler.h"
#include "crunch/core/rng.h"
#include "crunch/render/chart.h"

extern char** environ;

namespace {

using crunch::Blackboard;
using crunch::ModelParams;
using crunch::Pose2;
using crunch::Rng;
using crunch::Sampler;
using crunch::SamplerOptions;
using crunch::Shapelet;
using crunch::Vec2;

constexpr double kSpacing = 2.0;         // metres between table centres
int g_per_face = 10;  // shapelets per sensed leg face (--per-face); 8 faces per table
constexpr double kSigmaR = 0.005;
constexpr double kSigmaPhi = crunch::kPi / 32;
constexpr long long kWorkPerPoint = 30000;  // shapelets' worth of anneals per point

std::vector<Shapelet> floorShapelets(int n, const ModelParams& p, Rng& rng, int* n_tables) {
  const int per_table = 8 * g_per_face;
  const int tables = (n + per_table - 1) / per_table;
  const int side = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(tables))));
  *n_tables = tables;
  std::vector<Shapelet> out;
  out.reserve(static_cast<size_t>(n));
  for (int k = 0; k < tables && static_cast<int>(out.size()) < n; ++k) {
    const Pose2 t{1.0 + kSpacing * (k % side), 1.0 + kSpacing * (k / side),
                  rng.uniform(0.0, crunch::kPi)};
    for (int i = 0; i < per_table && static_cast<int>(out.size()) < n; ++i) {
      const int corner = i / (2 * g_per_face);
      const bool x_face = (i / g_per_face) % 2 == 0;
      const int face = x_face ? ((corner == 0 || corner == 3) ? 0 : 2) : (corner < 2 ? 1 : 3);
      const Pose2 leg = crunch::testing::LegOf(t, p, corner);
      const double along = rng.uniform(-0.5, 0.5) * p.leg_side;
      Shapelet s = crunch::testing::MakeShapelet(leg, p.leg_side, face, along);
      // Radial noise along the face normal (the sensing direction), orientation noise.
      const Vec2 normal = (Vec2{s.ox, s.oy} - Vec2{s.x, s.y}).normalized();
      const double dr = rng.normal(0.0, kSigmaR);
      s.x += dr * normal.x();
      s.y += dr * normal.y();
      s.phi = crunch::wrapPeriod(s.phi + rng.normal(0.0, kSigmaPhi), crunch::kPi);
      out.push_back(s);
    }
  }
  return out;
}

double threadCpuNs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return 1e9 * static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec);
}

long maxRssKiB() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return ru.ru_maxrss;  // KiB on Linux
}

struct Point {
  int n = 0;
  int tables = 0;
  int runs = 0;
  long long proposals = 0;  // over all timed anneals
  double wall_ns = 0.0, cpu_ns = 0.0;
  int live_tables = 0, live_legs = 0;
  long rss_kib = 0;
  double seconds = 0.0;  // wall time of the whole child
};

// Child: one point, printed as "POINT n tables runs proposals wall_ns cpu_ns lt ll rss_kib".
int runPoint(int n, uint64_t seed) {
  const ModelParams p;
  Rng floor_rng(seed);
  int tables = 0;
  const std::vector<Shapelet> shapelets = floorShapelets(n, p, floor_rng, &tables);
  const long rss_before = maxRssKiB();
  const int runs = static_cast<int>(std::max<long long>(1, kWorkPerPoint / n));
  Point pt;
  pt.n = n;
  pt.tables = tables;
  pt.runs = runs;
  Rng rng(seed + 1);
  for (int r = 0; r < runs; ++r) {
    Blackboard board(p, n, 4 * static_cast<size_t>(n) + 64);
    for (const Shapelet& s : shapelets) board.pushShapelet(s);
    Sampler sampler(board, SamplerOptions{}, rng);
    const double c0 = threadCpuNs();
    const auto t0 = std::chrono::steady_clock::now();
    sampler.anneal();
    pt.wall_ns +=
        std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count();
    pt.cpu_ns += threadCpuNs() - c0;
    pt.proposals += sampler.stats().proposals;
    if (r == 0) {
      pt.live_tables = board.liveTables();
      pt.live_legs = board.liveLegs();
      pt.rss_kib = maxRssKiB() - rss_before;
    }
  }
  std::printf("POINT %d %d %d %lld %.0f %.0f %d %d %ld\n", pt.n, pt.tables, pt.runs, pt.proposals,
              pt.wall_ns, pt.cpu_ns, pt.live_tables, pt.live_legs, pt.rss_kib);
  return 0;
}

// Parent: runs one point in a fresh process and parses its line. False on failure.
bool measure(const char* self, int n, uint64_t seed, Point* out) {
  int fds[2];
  if (pipe(fds) != 0) return false;
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_adddup2(&fa, fds[1], STDOUT_FILENO);
  posix_spawn_file_actions_addclose(&fa, fds[0]);
  const std::string n_s = std::to_string(n), seed_s = std::to_string(seed);
  const std::string pf_s = std::to_string(g_per_face);
  std::string a0 = self, a1 = "--point", a3 = "--seed", a5 = "--per-face";
  char* argv[] = {a0.data(), a1.data(), const_cast<char*>(n_s.c_str()), a3.data(),
                  const_cast<char*>(seed_s.c_str()), a5.data(), const_cast<char*>(pf_s.c_str()),
                  nullptr};
  pid_t pid = 0;
  const auto t0 = std::chrono::steady_clock::now();
  const int rc = posix_spawn(&pid, self, &fa, nullptr, argv, environ);
  posix_spawn_file_actions_destroy(&fa);
  close(fds[1]);
  if (rc != 0) {
    close(fds[0]);
    std::fprintf(stderr, "scale_bench: cannot spawn %s: %s\n", self, std::strerror(rc));
    return false;
  }
  std::string text;
  char buf[512];
  ssize_t got = 0;
  while ((got = read(fds[0], buf, sizeof buf)) > 0) text.append(buf, static_cast<size_t>(got));
  close(fds[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  out->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::fprintf(stderr, "scale_bench: point N=%d failed (status %d)\n", n, status);
    return false;
  }
  const size_t at = text.find("POINT ");
  if (at == std::string::npos ||
      std::sscanf(text.c_str() + at, "POINT %d %d %d %lld %lf %lf %d %d %ld", &out->n,
                  &out->tables, &out->runs, &out->proposals, &out->wall_ns, &out->cpu_ns,
                  &out->live_tables, &out->live_legs, &out->rss_kib) != 9) {
    std::fprintf(stderr, "scale_bench: point N=%d: unreadable output\n", n);
    return false;
  }
  return true;
}

double perProposal(double ns, const Point& p) {
  return p.proposals > 0 ? ns / static_cast<double>(p.proposals) : NAN;
}

bool writeCharts(const std::string& prefix, const std::vector<Point>& curve,
                 const Point& base0, const Point& base1) {
  using crunch::ChartSeries;
  crunch::Chart cost;
  cost.options.title = "Global inference: cost per proposal against shapelets N";
  cost.options.x_label = "log10 N (shapelets in working memory)";
  cost.options.y_label = "ns per proposal";
  cost.options.y_min = 0.0;
  cost.options.legend = crunch::LegendPosition::kBottomRight;
  ChartSeries wall, cpu;
  wall.label = "wall";
  cpu.label = "thread CPU";
  cpu.marker = crunch::MarkerShape::kSquare;
  crunch::Chart mem;
  mem.options.title = "Global inference: peak resident growth per shapelet";
  mem.options.x_label = "log10 N (shapelets in working memory)";
  mem.options.y_label = "bytes per shapelet (peak RSS delta / N)";
  mem.options.y_min = 0.0;
  mem.options.legend = crunch::LegendPosition::kTopRight;
  ChartSeries bytes;
  bytes.label = "peak RSS delta / N";
  for (const Point& p : curve) {
    const double x = std::log10(static_cast<double>(p.n));
    wall.x.push_back(x);
    wall.y.push_back(perProposal(p.wall_ns, p));
    cpu.x.push_back(x);
    cpu.y.push_back(perProposal(p.cpu_ns, p));
    bytes.x.push_back(x);
    bytes.y.push_back(1024.0 * static_cast<double>(p.rss_kib) / p.n);
  }
  ChartSeries drift;
  drift.label = "N = 100 baseline, first and last (wall)";
  drift.style = crunch::SeriesStyle::kPoints;
  drift.marker = crunch::MarkerShape::kDiamond;
  drift.marker_size = 6.0;
  for (const Point* b : {&base0, &base1}) {
    drift.x.push_back(2.0);
    drift.y.push_back(perProposal(b->wall_ns, *b));
  }
  cost.series = {wall, cpu, drift};
  mem.series = {bytes};
  for (auto [chart, path] : {std::pair{&cost, prefix + ".png"},
                             std::pair{&mem, prefix + "_memory.png"}}) {
    const crunch::Status st = crunch::renderChartPng(*chart, path);
    if (!st.ok()) {
      std::fprintf(stderr, "scale_bench: %s\n", st.error().message.c_str());
      return false;
    }
    std::printf("wrote %s\n", path.c_str());
  }
  return true;
}

void printRow(const char* tag, const Point& p) {
  std::printf("%-9s %7d %6d %5d %10lld %9.0f %9.0f %7d %7d %10ld %9.0f %7.1f\n", tag, p.n,
              p.tables, p.runs, p.proposals, perProposal(p.wall_ns, p), perProposal(p.cpu_ns, p),
              p.live_tables, p.live_legs, p.rss_kib, 1024.0 * static_cast<double>(p.rss_kib) / p.n,
              p.seconds);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  int max_n = 100000;
  int point = 0;
  uint64_t seed = 1;
  std::string chart;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has = i + 1 < argc;
    if (a == "--max" && has) max_n = std::atoi(argv[++i]);
    else if (a == "--point" && has) point = std::atoi(argv[++i]);
    else if (a == "--seed" && has) seed = std::strtoull(argv[++i], nullptr, 10);
    else if (a == "--chart" && has) chart = argv[++i];
    else if (a == "--per-face" && has) g_per_face = std::atoi(argv[++i]);
    else {
      std::fprintf(stderr, "usage: scale_bench [--max N] [--seed S] [--per-face K] [--chart PREFIX]\n");
      return 2;
    }
  }
  if (g_per_face < 1 || g_per_face > 1000) {
    std::fprintf(stderr, "scale_bench: --per-face must be in [1, 1000]\n");
    return 2;
  }
  if (point > 0) return runPoint(point, seed);
  if (max_n < 100) {
    std::fprintf(stderr, "scale_bench: --max must be >= 100\n");
    return 2;
  }

  const std::string self = "/proc/self/exe";
  char resolved[4096];
  const ssize_t len = readlink(self.c_str(), resolved, sizeof resolved - 1);
  if (len <= 0) {
    std::fprintf(stderr, "scale_bench: cannot resolve /proc/self/exe\n");
    return 1;
  }
  resolved[len] = '\0';

  std::printf("%-9s %7s %6s %5s %10s %9s %9s %7s %7s %10s %9s %7s\n", "point", "N", "tables",
              "runs", "proposals", "wall_ns", "cpu_ns", "tables", "legs", "rss_KiB",
              "B/shapelet", "child_s");
  std::vector<Point> curve;
  Point base0, base1;
  if (!measure(resolved, 100, seed, &base0)) return 1;
  printRow("baseline", base0);
  for (int n : {100, 300, 1000, 3000, 10000, 30000, 100000}) {
    if (n > max_n) break;
    Point p;
    if (!measure(resolved, n, seed, &p)) return 1;
    printRow("curve", p);
    curve.push_back(p);
  }
  if (!measure(resolved, 100, seed, &base1)) return 1;
  printRow("baseline", base1);
  const double w0 = perProposal(base0.wall_ns, base0), w1 = perProposal(base1.wall_ns, base1);
  std::printf("drift: N=100 wall ns/proposal first %.0f, last %.0f (%+.1f%%)\n", w0, w1,
              100.0 * (w1 - w0) / w0);
  if (!chart.empty() && !writeCharts(chart, curve, base0, base1)) return 1;
  return 0;
}
