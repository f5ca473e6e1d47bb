#include "crunch/mapping/posterior_marginals.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <unordered_map>

#include "crunch/core/range_check.h"

namespace crunch {

Status MarginalOptions::validate() const {
  const Status checks[] = {checkAbove("radius", radius, 0.0, 10.0),
                           checkAbove("angle", angle, 0.0, kPi),
                           checkAbove("angle_period", angle_period, 0.0, 2 * kPi),
                           checkRange("shape_tolerance", shape_tolerance, 0.0, 10.0)};
  for (const Status& s : checks) {
    if (!s) return s;
  }
  return okStatus();
}

namespace {

// The period of a cluster's angles: half of angle_period for a near-square table.
double periodOf(const std::array<double, 3>& shape, const MarginalOptions& opt) {
  const bool square = opt.square_half_period && std::abs(shape[0] - shape[1]) <= opt.shape_tolerance;
  return square ? opt.angle_period / 2 : opt.angle_period;
}

bool matches(const ObjectSample& a, const Pose2& centre, const std::array<double, 3>& shape,
             const MarginalOptions& opt) {
  if (std::hypot(a.pose.x - centre.x, a.pose.y - centre.y) > opt.radius) return false;
  if (std::abs(wrapPeriod(a.pose.theta - centre.theta, periodOf(shape, opt))) > opt.angle)
    return false;
  for (size_t i = 0; i < shape.size(); ++i)
    if (std::abs(a.shape[i] - shape[i]) > opt.shape_tolerance) return false;
  return true;
}

// Items by grid cell of side `radius`.
class Grid {
 public:
  Grid(std::span<const ObjectSample> items, double cell) : cell_(cell) {
    for (size_t i = 0; i < items.size(); ++i) cells_[key(items[i].pose.x, items[i].pose.y)].push_back(i);
  }
  template <typename F>
  void near(double x, double y, F&& f) const {
    const int64_t cx = idx(x), cy = idx(y);
    for (int64_t dx = -1; dx <= 1; ++dx)
      for (int64_t dy = -1; dy <= 1; ++dy) {
        const auto it = cells_.find(pack(cx + dx, cy + dy));
        if (it == cells_.end()) continue;
        for (size_t i : it->second) f(i);
      }
  }

 private:
  int64_t idx(double v) const { return static_cast<int64_t>(std::floor(v / cell_)); }
  static int64_t pack(int64_t a, int64_t b) { return (a << 32) ^ (b & 0xffffffff); }
  int64_t key(double x, double y) const { return pack(idx(x), idx(y)); }
  double cell_;
  std::unordered_map<int64_t, std::vector<size_t>> cells_;
};

struct Centre {
  Pose2 pose;
  std::array<double, 3> shape{};
};

Centre meanOf(std::span<const ObjectSample> items, const std::vector<size_t>& members,
              double period) {
  double x = 0, y = 0, c = 0, s = 0;
  std::array<double, 3> shape{};
  const double k = 2 * kPi / period;
  for (size_t i : members) {
    x += items[i].pose.x;
    y += items[i].pose.y;
    c += std::cos(k * items[i].pose.theta);
    s += std::sin(k * items[i].pose.theta);
    for (size_t j = 0; j < shape.size(); ++j) shape[j] += items[i].shape[j];
  }
  const double n = static_cast<double>(members.size());
  for (double& v : shape) v /= n;
  double th = std::atan2(s, c) / k;
  if (th < 0) th += period;
  return {{x / n, y / n, th}, shape};
}

}  // namespace

std::vector<MarginalObject> posteriorMarginals(std::span<const ObjectSample> items,
                                               int n_samples, const MarginalOptions& opt) {
  std::vector<MarginalObject> out;
  if (items.empty() || n_samples < 1) return out;
  const Grid grid(items, opt.radius);
  std::vector<int> count(items.size(), 0);
  for (size_t i = 0; i < items.size(); ++i)
    grid.near(items[i].pose.x, items[i].pose.y, [&](size_t j) {
      count[i] += matches(items[j], items[i].pose, items[i].shape, opt);
    });
  std::vector<size_t> order(items.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return count[a] > count[b]; });

  std::vector<bool> used(items.size(), false);
  std::vector<size_t> members, refined;
  // Per sample: the member nearest the centre (index into items), for the mean and the count.
  std::unordered_map<int, size_t> best;
  const auto gather = [&](const Centre& c, std::vector<size_t>& into) {
    into.clear();
    grid.near(c.pose.x, c.pose.y, [&](size_t j) {
      if (!used[j] && matches(items[j], c.pose, c.shape, opt)) into.push_back(j);
    });
  };
  const auto distance = [&](size_t j, const Centre& c) {
    return std::hypot(items[j].pose.x - c.pose.x, items[j].pose.y - c.pose.y);
  };
  for (size_t seed : order) {
    if (used[seed]) continue;
    const Centre at{items[seed].pose, items[seed].shape};
    gather(at, members);
    const Centre centre = meanOf(items, members, periodOf(at.shape, opt));
    gather(centre, refined);
    if (refined.size() >= members.size() && !refined.empty()) members.swap(refined);
    best.clear();
    for (size_t j : members) {
      used[j] = true;
      auto [it, fresh] = best.try_emplace(items[j].sample, j);
      if (!fresh && distance(j, centre) < distance(it->second, centre)) it->second = j;
    }
    std::vector<size_t> one;
    one.reserve(best.size());
    for (const auto& kv : best) one.push_back(kv.second);
    std::sort(one.begin(), one.end());  // deterministic sums
    const Centre mean = meanOf(items, one, periodOf(centre.shape, opt));
    MarginalObject o;
    o.pose = mean.pose;
    o.shape = mean.shape;
    o.samples = static_cast<int>(one.size());
    o.score = std::min(1.0, static_cast<double>(o.samples) / n_samples);
    out.push_back(o);
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const MarginalObject& a, const MarginalObject& b) { return a.score > b.score; });
  return out;
}

}  // namespace crunch
