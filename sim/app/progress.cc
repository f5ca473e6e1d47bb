#include "progress.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <ostream>

namespace crunch::app {

namespace {
using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}
// "[####      ] " (appended piece by piece: GCC 12 warns -Wrestrict falsely on "[" + ...).
std::string bar(std::size_t filled, std::size_t width) {
  std::string b(1, '[');
  b.append(filled, '#');
  b.append(width - filled, ' ');
  b.append("] ");
  return b;
}
}  // namespace

std::string formatDuration(double s) {
  if (!std::isfinite(s) || s < 0) return "?";
  const long t = std::lround(s);
  char buf[32];
  if (t >= 3600) std::snprintf(buf, sizeof buf, "%ldh%02ldm", t / 3600, (t / 60) % 60);
  else if (t >= 60) std::snprintf(buf, sizeof buf, "%ldm%02lds", t / 60, t % 60);
  else std::snprintf(buf, sizeof buf, "%lds", t);
  return buf;
}

void PoseProgress::operator()(int done, int total) {
  if (json_) {
    if (done == total || done % 20 == 0)
      // Flushed per line: a program reading the pipe sees each event as it happens.
      os_ << "{\"event\":\"progress\",\"done\":" << done << ",\"total\":" << total << "}"
          << std::endl;
    return;
  }
  const int width = 40;
  const int filled = total > 0 ? done * width / total : width;
  if (filled == last_ && done != total) return;
  last_ = filled;
  os_ << "\r" << bar(static_cast<size_t>(filled), width) << done << "/" << total << " poses"
      << (done == total ? "\n" : "") << std::flush;
}

RunProgress::RunProgress(std::ostream& os, bool json, std::size_t total)
    : os_(os), json_(json), total_(total), t0_(Clock::now()) {}

void RunProgress::operator()(std::size_t done) {
  const double elapsed = since(t0_);
  const double left = done > 0 ? elapsed / static_cast<double>(done) *
                                     static_cast<double>(total_ - done)
                               : NAN;
  if (json_) {
    nlohmann::ordered_json j;
    j["event"] = "progress";
    j["done"] = done;
    j["total"] = total_;
    j["elapsed_s"] = elapsed;
    j["eta_s"] = left;
    os_ << j.dump() << "\n" << std::flush;
    return;
  }
  const size_t width = 30;
  os_ << "\r" << bar(total_ > 0 ? done * width / total_ : width, width) << done << "/" << total_
      << " runs, " << formatDuration(elapsed) << " elapsed, " << formatDuration(left)
      << " left   " << (done == total_ ? "\n" : "") << std::flush;
}

WhiskProgress::WhiskProgress(std::ostream& os, bool json) : os_(os), json_(json), t0_(Clock::now()) {}

double WhiskProgress::elapsed() const { return since(t0_); }

void WhiskProgress::operator()(const sim::TrainingProgress& p) {
  const double elapsed = since(t0_);
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
  os_ << "\r" << bar(static_cast<size_t>(filled), width) << p.done << "/" << p.total
      << " whisks, " << p.phase << ", " << formatDuration(elapsed) << " elapsed, ~"
      << formatDuration(eta) << " left   " << (p.done == p.total ? "\n" : "") << std::flush;
}

}  // namespace crunch::app
