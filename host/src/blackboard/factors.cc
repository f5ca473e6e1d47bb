#include "crunch/blackboard/factors.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace crunch {

namespace {
constexpr double kMaxP = 1.0 - 1e-9;  // logPresenceOdds' cap on P(H)

double deltaTLAt(const Pose2& table, double c, double s, double width, double depth,
                 double leg_side, const LegHyp& leg, const ModelParams& p, int* corner) {
  double best = std::numeric_limits<double>::infinity();
  int best_i = 0;
  const Vec2 l = leg.pose.position();
  for (int i = 0; i < 4; ++i) {
    const double d2 =
        (table.toWorld(ModelParams::cornerOffset(i, width, depth, leg_side), c, s) - l)
            .squaredNorm();
    if (d2 < best) {
      best = d2;
      best_i = i;
    }
  }
  if (corner) *corner = best_i;
  const double dr = best / (p.sigma_r_leg * p.sigma_r_leg);
  const double dth = wrapPeriod(table.theta - leg.pose.theta, kPi / 2) / p.sigma_theta_leg;
  const double dw = (leg_side - leg.side) / p.sigma_w;
  return dr + dth * dth + dw * dw;
}
}  // namespace

FactorLogs::FactorLogs(const ModelParams& p)
    : c_S(std::log(p.c_S)),
      c_L(std::log(p.c_L)),
      alpha_L(std::log(p.alpha_L)),
      alpha_S(std::log(p.alpha_S)),
      alpha_W(std::log(p.alpha_W)),
      delta3(std::log(p.delta3)),
      p_miss(std::log(p.p_miss)),
      max_p(std::log(kMaxP)) {}

double deltaTL(const Pose2& table, const LegHyp& leg, const ModelParams& p, int* corner) {
  return deltaTLAt(table, std::cos(table.theta), std::sin(table.theta), p.table_width,
                   p.table_depth, p.leg_side, leg, p, corner);
}

double deltaTLSized(const TableHyp& table, const LegHyp& leg, const ModelParams& p, int* corner) {
  return deltaTLAt(table.pose, std::cos(table.pose.theta), std::sin(table.pose.theta),
                   table.width, table.depth, table.leg, leg, p, corner);
}

double deltaTLHeld(const TableHyp& table, const LegHyp& leg, const ModelParams& p, int* corner) {
  return deltaTLAt(table.pose, table.trig.c, table.trig.s, table.width, table.depth, table.leg,
                   leg, p, corner);
}

namespace {
double deltaLSAt(const LegHyp& leg, double c, double sn, const Shapelet& s,
                 const ModelParams& p) {
  if (p.perFaceKernel() && s.oriented) {  // the face the shapelet's line fits
    const Vec2 q = leg.pose.toLocal({s.x, s.y}, c, sn);
    const double h = 0.5 * leg.side;
    // how far past the corners along x and y (0 within the leg's extent)
    const double past_x = std::max(std::abs(q.x()) - h, 0.0);
    const double past_y = std::max(std::abs(q.y()) - h, 0.0);
    // faces x = +-h run along the leg's y axis, faces y = +-h along its x axis
    const double dx = std::min(std::abs(q.x() - h), std::abs(q.x() + h));
    const double dy = std::min(std::abs(q.y() - h), std::abs(q.y() + h));
    const double along_y = (dx * dx + past_y * past_y) / (p.sigma_r_shapelet * p.sigma_r_shapelet);
    const double along_x = (dy * dy + past_x * past_x) / (p.sigma_r_shapelet * p.sigma_r_shapelet);
    // angle to the x faces' line modulo pi, in [-pi/2, pi/2); the y faces' is a quarter turn off
    const double to_x = std::abs(wrapPeriod(leg.pose.theta - s.phi, kPi));
    const double ax = to_x / p.sigma_theta_shapelet;
    const double ay = (0.5 * kPi - to_x) / p.sigma_theta_shapelet;
    return std::min(along_y + ay * ay, along_x + ax * ax);
  }
  const OrientedRect outline{leg.pose, leg.side, leg.side};
  const PerimeterPoint pp = closestOnPerimeter(outline, {s.x, s.y}, c, sn);
  // Side m's surface runs along the leg's y axis for faces 0 and 2, along x for faces 1 and 3:
  // f(theta_L) = theta_L + m pi/2 + pi/2 as a line direction.
  const double side_dir = leg.pose.theta + (pp.side + 1) * (kPi / 2);
  const double dr = pp.distance / p.sigma_r_shapelet;
  if (!s.oriented) return dr * dr;  // an edge or point contact: no orientation to compare
  const double dth = wrapPeriod(side_dir - s.phi, kPi) / p.sigma_theta_shapelet;
  return dr * dr + dth * dth;
}
}  // namespace

double deltaLS(const LegHyp& leg, const Shapelet& s, const ModelParams& p) {
  return deltaLSAt(leg, std::cos(leg.pose.theta), std::sin(leg.pose.theta), s, p);
}

double deltaLSHeld(const LegHyp& leg, const Shapelet& s, const ModelParams& p) {
  return deltaLSAt(leg, leg.trig.c, leg.trig.s, s, p);
}

double logLegDensity(double delta_tl, bool has_parent, const ModelParams& p) {
  return logLegDensity(delta_tl, has_parent, FactorLogs(p));
}

double logLegDensity(double delta_tl, bool has_parent, const FactorLogs& k) {
  if (!has_parent) return k.c_L;
  return logAddExp(k.c_L, k.alpha_L - delta_tl);
}

double logShapeletKernel(const LegHyp& leg, const Shapelet& s, const ModelParams& p) {
  if (!legCanCause(leg.side, s)) return -std::numeric_limits<double>::infinity();
  return std::log(p.alpha_S) - deltaLS(leg, s, p);
}

double logShapeletKernelHeld(const LegHyp& leg, const Shapelet& s, const ModelParams& p,
                             const FactorLogs& k) {
  if (!legCanCause(leg.side, s)) return -std::numeric_limits<double>::infinity();
  return k.alpha_S - deltaLSHeld(leg, s, p);
}

double deltaWS(const WallHyp& wall, const Shapelet& s, const ModelParams& p) {
  const double dr = distanceToSegment({s.x, s.y}, wall.a, wall.b) / p.sigma_r_shapelet;
  if (!s.oriented) return dr * dr;
  const double dth = wrapPeriod(wall.angle() - s.phi, kPi) / p.sigma_theta_shapelet;
  return dr * dr + dth * dth;
}

double logWallKernel(const WallHyp& wall, const Shapelet& s, const ModelParams& p) {
  return logWallKernel(wall, s, p, FactorLogs(p));
}

double logWallKernel(const WallHyp& wall, const Shapelet& s, const ModelParams& p,
                     const FactorLogs& k) {
  if (!wallFaces(wall, s)) return -std::numeric_limits<double>::infinity();
  return k.alpha_W - deltaWS(wall, s, p);
}

double logShapeletDensity(std::span<const double> log_kernels, const ModelParams& p) {
  double acc = std::log(p.c_S);
  for (double k : log_kernels) acc = logAddExp(acc, k);
  return acc;
}

double logPresenceOdds(double log_density, const ModelParams& p) {
  return logPresenceOdds(log_density, FactorLogs(p));
}

double logPresenceOdds(double log_density, const FactorLogs& k) {
  const double log_p = std::min(k.delta3 + log_density, k.max_p);
  return log_p - std::log1p(-std::exp(log_p));
}

double logAddExp(double a, double b) {
  if (a == -std::numeric_limits<double>::infinity()) return b;
  if (b == -std::numeric_limits<double>::infinity()) return a;
  return a > b ? a + std::log1p(std::exp(b - a)) : b + std::log1p(std::exp(a - b));
}

double temperedAcceptance(double delta, double beta) {
  const double z = beta * delta;
  if (z >= 0) return 1.0 / (1.0 + std::exp(-z));
  const double e = std::exp(z);
  return e / (1.0 + e);
}

double literalAcceptance(double delta, double beta) {
  // P(new | mb) = sigmoid(delta); raised to beta in log space.
  const double log_sig = delta >= 0 ? -std::log1p(std::exp(-delta)) : delta - std::log1p(std::exp(delta));
  return std::exp(beta * log_sig);
}

}  // namespace crunch
