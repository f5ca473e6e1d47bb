#include "crunch/robot/ramp_fit.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>
#include <string>

#include "crunch/core/range_check.h"

namespace crunch {

namespace {

// S(d) tabulated at 0.05 mm; the host's bisection (distanceFromRampSlope) run on it.
class ComplianceTable {
 public:
  explicit ComplianceTable(const WhiskerBeam& beam)
      : beam_(beam), n_(static_cast<int>(std::ceil(beam.external_length / 5e-5))) {
    step_ = beam.external_length / n_;
    s_.resize(static_cast<std::size_t>(n_) + 1);
    for (int i = 0; i <= n_; ++i) s_[static_cast<std::size_t>(i)] = beam.shaftCompliance(i * step_);
  }

  double shaft(double d) const {
    const double x = std::clamp(d / step_, 0.0, static_cast<double>(n_));
    const int i = std::min(static_cast<int>(x), n_ - 1);
    const double f = x - i;
    return (1.0 - f) * s_[static_cast<std::size_t>(i)] + f * s_[static_cast<std::size_t>(i) + 1];
  }
  double slope(double d, double lever, double gain, double scale) const {
    return gain * (lever + d) * d / (d * d + scale * beam_.follicle_stiffness * shaft(d));
  }
  // distanceFromRampSlope on the table.
  double distance(double slope_value, double lever, double gain, double scale) const {
    double lo = kMinRampContactDistance, hi = beam_.external_length;
    if (!(slope_value < slope(lo, lever, gain, scale))) return lo;
    if (!(slope_value > slope(hi, lever, gain, scale))) return hi;
    for (int i = 0; i < 50; ++i) {
      const double mid = 0.5 * (lo + hi);
      if (slope(mid, lever, gain, scale) > slope_value) lo = mid;
      else hi = mid;
    }
    return 0.5 * (lo + hi);
  }

 private:
  const WhiskerBeam& beam_;
  int n_;
  double step_ = 0.0;
  std::vector<double> s_;
};

struct Errors {
  double rms = 0.0, mean = 0.0, cost = 0.0;
};

Errors errorsOf(const ComplianceTable& t, const std::vector<RampSample>& xs, double gain,
                double scale) {
  Errors e;
  for (const RampSample& x : xs) {
    const double r = t.distance(x.slope, x.lever_offset, gain, scale) - x.r;
    e.cost += r * r;
    e.mean += r;
  }
  if (!xs.empty()) {
    e.mean /= static_cast<double>(xs.size());
    e.rms = std::sqrt(e.cost / static_cast<double>(xs.size()));
  }
  return e;
}

struct LmResult {
  std::array<double, 2> p{};  // ln gain, ln compliance_scale
  std::array<double, 3> jtj{};  // normal matrix at the solution: [00, 01, 11]
  double cost = 0.0;
  int iterations = 0;
};

// Levenberg-Marquardt on the two log parameters, numeric (central) Jacobian.
LmResult levenbergMarquardt(const ComplianceTable& t, const std::vector<RampSample>& xs) {
  const std::size_t n = xs.size();
  std::vector<double> res(n), j0(n), j1(n);
  auto residuals = [&](const std::array<double, 2>& p, std::vector<double>& out) {
    const double g = std::exp(p[0]), c = std::exp(p[1]);
    double cost = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      out[i] = t.distance(xs[i].slope, xs[i].lever_offset, g, c) - xs[i].r;
      cost += out[i] * out[i];
    }
    return cost;
  };
  constexpr double kH = 1e-5;  // in the log parameters: 0.001 %
  std::vector<double> plus(n), minus(n);
  auto jacobian = [&](const std::array<double, 2>& p) {
    for (int k = 0; k < 2; ++k) {
      std::array<double, 2> a = p, b = p;
      a[static_cast<std::size_t>(k)] += kH;
      b[static_cast<std::size_t>(k)] -= kH;
      residuals(a, plus);
      residuals(b, minus);
      std::vector<double>& j = k == 0 ? j0 : j1;
      for (std::size_t i = 0; i < n; ++i) j[i] = (plus[i] - minus[i]) / (2.0 * kH);
    }
  };
  LmResult out;
  std::array<double, 2> p{0.0, 0.0};
  double cost = residuals(p, res);
  double lambda = 1e-3;
  for (out.iterations = 0; out.iterations < 200; ++out.iterations) {
    jacobian(p);
    double a00 = 0, a01 = 0, a11 = 0, g0 = 0, g1 = 0;
    for (std::size_t i = 0; i < n; ++i) {
      a00 += j0[i] * j0[i];
      a01 += j0[i] * j1[i];
      a11 += j1[i] * j1[i];
      g0 += j0[i] * res[i];
      g1 += j1[i] * res[i];
    }
    out.jtj = {a00, a01, a11};
    bool improved = false;
    double step = 0.0;
    for (int tries = 0; tries < 30 && !improved; ++tries) {
      const double b00 = a00 * (1.0 + lambda), b11 = a11 * (1.0 + lambda);
      const double det = b00 * b11 - a01 * a01;
      if (!(std::abs(det) > 0.0)) {
        lambda *= 10.0;
        continue;
      }
      const std::array<double, 2> q{p[0] - (b11 * g0 - a01 * g1) / det,
                                    p[1] - (b00 * g1 - a01 * g0) / det};
      std::vector<double> trial(n);
      const double c = residuals(q, trial);
      if (std::isfinite(c) && c <= cost) {
        step = std::hypot(q[0] - p[0], q[1] - p[1]);
        const double gain_in_cost = cost - c;
        p = q;
        res.swap(trial);
        improved = true;
        lambda = std::max(lambda / 10.0, 1e-12);
        if (gain_in_cost <= 1e-14 * std::max(cost, 1e-30)) step = 0.0;
        cost = c;
      } else {
        lambda *= 10.0;
      }
    }
    if (!improved || step < 1e-10) break;
  }
  out.p = p;
  out.cost = cost;
  return out;
}

std::string text(double v) {
  std::ostringstream s;
  s.precision(6);
  s << v;
  return s.str();
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

}  // namespace

Status RampFitOptions::validate() const {
  if (auto s = checkAbove("gain_min", gain_min, 0.0, 100.0); !s) return s;
  if (auto s = checkRange("gain_max", gain_max, gain_min, 100.0); !s) return s;
  if (auto s = checkAbove("scale_min", scale_min, 0.0, 100.0); !s) return s;
  if (auto s = checkRange("scale_max", scale_max, scale_min, 100.0); !s) return s;
  if (auto s = checkCount("min_samples", min_samples, 3, 1000000); !s) return s;
  if (auto s = checkRange("outlier_sigmas", outlier_sigmas, 0.0, 100.0); !s) return s;
  return checkRange("min_outlier_sigma", min_outlier_sigma, 0.0, 0.1);
}

Result<RampFitSummary> fitRampCalibration(const WhiskerBeam& beam,
                                          const std::vector<RampSample>& samples,
                                          const RampFitOptions& options) {
  if (auto s = options.validate(); !s) return Error{"ramp fit options: " + s.error().message};
  if (auto s = beam.validate(); !s) return Error{"ramp fit: " + s.error().message};
  std::vector<RampSample> xs;
  for (const RampSample& x : samples) {
    if (std::isfinite(x.slope) && x.slope > 0.0 && std::isfinite(x.lever_offset) &&
        std::isfinite(x.r) && x.r > 0.0 && x.r <= beam.external_length) {
      xs.push_back(x);
    }
  }
  RampFitSummary out;
  out.samples = static_cast<int>(samples.size());
  if (static_cast<int>(xs.size()) < options.min_samples) {
    return Error{"ramp fit: " + std::to_string(xs.size()) + " usable contacts of " +
                 std::to_string(samples.size()) + " (need at least " +
                 std::to_string(options.min_samples) + ")"};
  }
  const ComplianceTable table(beam);
  LmResult lm = levenbergMarquardt(table, xs);
  if (options.outlier_sigmas > 0.0) {
    std::vector<double> e;
    for (const RampSample& x : xs) {
      e.push_back(table.distance(x.slope, x.lever_offset, std::exp(lm.p[0]), std::exp(lm.p[1])) -
                  x.r);
    }
    const double mid = median(e);
    std::vector<double> dev;
    for (double v : e) dev.push_back(std::abs(v - mid));
    const double sigma = std::max(1.4826 * median(dev), options.min_outlier_sigma);
    std::vector<RampSample> kept;
    for (std::size_t i = 0; i < xs.size(); ++i) {
      if (std::abs(e[i] - mid) <= options.outlier_sigmas * sigma) kept.push_back(xs[i]);
    }
    out.outliers = static_cast<int>(xs.size() - kept.size());
    if (static_cast<int>(kept.size()) < options.min_samples) {
      return Error{"ramp fit: " + std::to_string(kept.size()) +
                   " contacts left after dropping outliers (need at least " +
                   std::to_string(options.min_samples) + ")"};
    }
    if (out.outliers > 0) {
      xs.swap(kept);
      const int first_iterations = lm.iterations;
      lm = levenbergMarquardt(table, xs);
      lm.iterations += first_iterations;
    }
  }
  out.used = static_cast<int>(xs.size());
  out.iterations = lm.iterations;
  // Separability: the normal matrix scaled to unit diagonal; its smaller eigenvalue is
  // 1 - |correlation|. Contacts all at one distance give a correlation of ~1.
  const auto& a = lm.jtj;
  if (!(a[0] > 0.0 && a[2] > 0.0)) {
    return Error{"ramp fit: the contacts do not constrain gain and compliance_scale (every "
                 "contact reads as the tip or the follicle whatever they are)"};
  }
  const double corr = a[1] / std::sqrt(a[0] * a[2]);
  if (1.0 - std::abs(corr) < 1e-6) {
    return Error{"ramp fit: gain and compliance_scale cannot be told apart from these contacts "
                 "(correlation " + text(corr) +
                 "): contacts near the follicle and near the tip are both needed"};
  }
  out.gain = std::exp(lm.p[0]);
  out.compliance_scale = std::exp(lm.p[1]);
  const double dof = std::max(1, out.used - 2);
  const double var = lm.cost / dof;
  const double det = a[0] * a[2] - a[1] * a[1];
  out.gain_se = out.gain * std::sqrt(var * a[2] / det);
  out.compliance_scale_se = out.compliance_scale * std::sqrt(var * a[0] / det);
  const Errors nominal = errorsOf(table, xs, 1.0, 1.0);
  const Errors fitted = errorsOf(table, xs, out.gain, out.compliance_scale);
  out.rms_nominal = nominal.rms;
  out.mean_nominal = nominal.mean;
  out.rms = fitted.rms;
  out.mean = fitted.mean;
  if (auto s = checkRange("gain", out.gain, options.gain_min, options.gain_max); !s) {
    return Error{"ramp fit: the fitted " + s.error().message + ": outside the physical range"};
  }
  if (auto s = checkRange("compliance_scale", out.compliance_scale, options.scale_min,
                          options.scale_max);
      !s) {
    return Error{"ramp fit: the fitted " + s.error().message + ": outside the physical range"};
  }
  return out;
}

}  // namespace crunch
