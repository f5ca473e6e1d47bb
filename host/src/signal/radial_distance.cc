#include "crunch/signal/radial_distance.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <string>

namespace crunch::signal {

namespace {

// Fits r = a1 f1 + a0. Requires n >= 3 and distinct f1 (checked by the caller). Returns the
// line and adds the residuals' squares to `ssr`.
RadialLine fitLine(const std::vector<double>& f1, const std::vector<double>& r, double& ssr) {
  const auto n = static_cast<Eigen::Index>(f1.size());
  Eigen::MatrixXd a(n, 2);
  Eigen::VectorXd b(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    a(i, 0) = f1[i];
    a(i, 1) = 1.0;
    b(i) = r[i];
  }
  const Eigen::Vector2d x = a.colPivHouseholderQr().solve(b);
  RadialLine line;
  line.a1 = x(0);
  line.a0 = x(1);
  line.samples = static_cast<int>(n);
  const double s = (a * x - b).squaredNorm();
  ssr = s;
  line.sigma = std::sqrt(s / static_cast<double>(n - 2));
  line.f1_min = *std::min_element(f1.begin(), f1.end());
  line.f1_max = *std::max_element(f1.begin(), f1.end());
  line.r_min = *std::min_element(r.begin(), r.end());
  line.r_max = *std::max_element(r.begin(), r.end());
  return line;
}

bool allEqual(const std::vector<double>& v) {
  return std::all_of(v.begin(), v.end(), [&](double x) { return x == v.front(); });
}

}  // namespace

Status RadialOptions::validate() const {
  if (!std::isfinite(external_length) || external_length <= 0.0) {
    return Error{"radial.external_length: expected a positive number of metres"};
  }
  if (!std::isfinite(tip_zone) || tip_zone <= 0.0 || tip_zone > external_length) {
    return Error{"radial.tip_zone: expected metres in (0, external_length]"};
  }
  return okStatus();
}

RadialEstimate RadialModel::estimate(int whisker, double f1) const {
  assert(whisker >= 0 && whisker < kWhiskers);
  const RadialLine& line = whiskers[whisker];
  RadialEstimate e;
  e.r = line.predict(f1);
  e.tip = isTip(e.r);
  e.extrapolated = !(f1 >= line.f1_min && f1 <= line.f1_max);
  return e;
}

Result<RadialFit> fitRadialModel(const std::vector<RadialTrainingSample>& data,
                                 const RadialOptions& options) {
  if (Status s = options.validate(); !s.ok()) return s.error();
  std::array<std::vector<double>, kWhiskers> f1, r;
  std::vector<double> all_f1, all_r;
  for (size_t i = 0; i < data.size(); ++i) {
    const RadialTrainingSample& d = data[i];
    const std::string where = "radial training sample " + std::to_string(i);
    if (d.whisker < 0 || d.whisker >= kWhiskers) {
      return Error{where + ": whisker " + std::to_string(d.whisker) + " is not in 0..3"};
    }
    if (!std::isfinite(d.f1)) return Error{where + ": f1 is not finite"};
    if (!std::isfinite(d.r)) return Error{where + ": r is not finite"};
    f1[d.whisker].push_back(d.f1);
    r[d.whisker].push_back(d.r);
    all_f1.push_back(d.f1);
    all_r.push_back(d.r);
  }
  RadialFit fit;
  fit.model.options = options;
  double ssr_total = 0.0;
  int n_total = 0;
  for (int w = 0; w < kWhiskers; ++w) {
    const std::string where = "radial training data, whisker " + std::to_string(w);
    if (f1[w].size() < 3) {
      return Error{where + ": " + std::to_string(f1[w].size()) +
                   " samples, at least 3 are needed to fit a line and its sigma"};
    }
    if (allEqual(f1[w])) return Error{where + ": every f1 is the same; the line is undefined"};
    double ssr = 0.0;
    fit.model.whiskers[w] = fitLine(f1[w], r[w], ssr);
    fit.summary.sigma[w] = fit.model.whiskers[w].sigma;
    fit.summary.samples[w] = fit.model.whiskers[w].samples;
    ssr_total += ssr;
    n_total += fit.model.whiskers[w].samples;
  }
  fit.summary.pooled_sigma = std::sqrt(ssr_total / (n_total - 2 * kWhiskers));
  double ssr_combined = 0.0;
  fit.summary.combined = fitLine(all_f1, all_r, ssr_combined);
  return fit;
}

}  // namespace crunch::signal
