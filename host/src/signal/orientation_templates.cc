#include "crunch/signal/orientation_templates.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>
#include <set>
#include <string>

namespace crunch::signal {

namespace {

constexpr double kDegree = std::numbers::pi / 180.0;

std::string degrees(double radians) {
  return std::to_string(static_cast<long>(std::lround(radians / kDegree))) + " degrees";
}

// The class a label belongs to, or -1.
int classOf(double angle, const std::vector<double>& angles, double tolerance) {
  for (size_t k = 0; k < angles.size(); ++k) {
    if (std::abs(angle - angles[k]) <= tolerance) return static_cast<int>(k);
  }
  return -1;
}

}  // namespace

std::vector<double> defaultOrientationAngles() {
  std::vector<double> a;
  for (int deg = 20; deg <= 160; deg += 10) a.push_back(deg * kDegree);
  return a;
}

Status OrientationOptions::validate() const {
  if (angles.empty()) return Error{"orientation.angles: expected at least one class"};
  for (size_t i = 0; i < angles.size(); ++i) {
    if (!std::isfinite(angles[i])) {
      return Error{"orientation.angles[" + std::to_string(i) + "]: not finite"};
    }
  }
  if (!std::isfinite(label_tolerance) || label_tolerance < 0.0) {
    return Error{"orientation.label_tolerance: expected a non-negative number"};
  }
  for (size_t i = 0; i < angles.size(); ++i) {
    for (size_t j = i + 1; j < angles.size(); ++j) {
      if (std::abs(angles[i] - angles[j]) <= 2.0 * label_tolerance) {
        return Error{"orientation.angles: classes " + std::to_string(i) + " and " +
                     std::to_string(j) + " are closer than twice label_tolerance"};
      }
    }
  }
  return okStatus();
}

void OrientationModel::classify(const ContactWindow& w, OrientationEstimate& out) const {
  assert(!templates.empty() && accepts(w));
  out.errors.resize(templates.size());
  const double n = static_cast<double>(w.data.size());
  out.class_index = -1;
  double best = 0.0;
  for (size_t k = 0; k < templates.size(); ++k) {
    const double e = (w.data - templates[k].mean).squaredNorm() / n;  // eq. 3
    out.errors[k] = e;
    if (out.class_index < 0 || e < best) {
      best = e;
      out.class_index = static_cast<int>(k);
    }
  }
  out.angle = templates[out.class_index].angle;
}

OrientationEstimate OrientationModel::classify(const ContactWindow& w) const {
  OrientationEstimate e;
  classify(w, e);
  return e;
}

Result<OrientationModel> trainOrientationTemplates(const std::vector<LabelledWindow>& data,
                                                   const OrientationOptions& options) {
  if (Status s = options.validate(); !s.ok()) return s.error();
  if (data.empty()) return Error{"orientation training data: no windows"};
  OrientationModel model;
  model.decimation = data.front().window.decimation;
  model.columns = static_cast<int>(data.front().window.data.cols());
  if (model.columns < 1 || model.decimation < 1) {
    return Error{"orientation training window 0: empty window"};
  }
  model.templates.resize(options.angles.size());
  for (size_t k = 0; k < options.angles.size(); ++k) {
    model.templates[k].angle = options.angles[k];
    model.templates[k].mean = WindowMatrix::Zero(kChannels, model.columns);
  }
  for (size_t i = 0; i < data.size(); ++i) {
    const LabelledWindow& d = data[i];
    const std::string where = "orientation training window " + std::to_string(i);
    if (!model.accepts(d.window)) {
      return Error{where + ": shape (decimation " + std::to_string(d.window.decimation) + ", " +
                   std::to_string(d.window.data.cols()) + " columns) differs from window 0's"};
    }
    if (!d.window.data.allFinite()) return Error{where + ": a value is not finite"};
    const int k = classOf(d.angle, options.angles, options.label_tolerance);
    if (k < 0) {
      return Error{where + ": label " + std::to_string(d.angle / kDegree) +
                   " degrees is not one of the classes"};
    }
    model.templates[k].mean += d.window.data;
    ++model.templates[k].windows;
  }
  for (OrientationTemplate& t : model.templates) {
    if (t.windows == 0)
      return Error{"orientation training data: no window for " + degrees(t.angle)};
    t.mean /= t.windows;
  }
  return model;
}

Result<CrossValidation> leaveOneRepeatOut(const std::vector<LabelledWindow>& data,
                                          const OrientationOptions& options) {
  if (Status s = options.validate(); !s.ok()) return s.error();
  // Every window's shape, values and label are checked once, with its index in `data`.
  if (Result<OrientationModel> all = trainOrientationTemplates(data, options); !all.ok()) {
    return all.error();
  }
  std::set<int> repeats;
  for (const LabelledWindow& d : data) repeats.insert(d.repeat);
  if (repeats.size() < 2) {
    return Error{"orientation cross-validation: needs windows from at least 2 repeats, got " +
                 std::to_string(repeats.size())};
  }
  CrossValidation cv;
  cv.per_angle.resize(options.angles.size());
  for (size_t k = 0; k < options.angles.size(); ++k) cv.per_angle[k].angle = options.angles[k];
  int correct = 0;
  for (int test_repeat : repeats) {
    std::vector<LabelledWindow> train;
    for (const LabelledWindow& d : data) {
      if (d.repeat != test_repeat) train.push_back(d);
    }
    Result<OrientationModel> model = trainOrientationTemplates(train, options);
    if (!model.ok()) {
      return Error{"orientation cross-validation, leaving out repeat " +
                   std::to_string(test_repeat) + ": " + model.error().message};
    }
    OrientationEstimate estimate;
    for (const LabelledWindow& d : data) {
      if (d.repeat != test_repeat) continue;
      const int k = classOf(d.angle, options.angles, options.label_tolerance);
      assert(k >= 0 && model.value().accepts(d.window));  // checked above
      model.value().classify(d.window, estimate);
      OrientationTrial t;
      t.repeat = test_repeat;
      t.true_angle = options.angles[k];
      t.estimated_angle = estimate.angle;
      t.error = t.estimated_angle - t.true_angle;
      if (estimate.class_index == k) ++correct;
      cv.trials.push_back(t);
      cv.per_angle[k].errors.push_back(t.error);
    }
  }
  auto meanSd = [](const std::vector<double>& v, double& mean, double& sd) {
    mean = 0.0;
    sd = 0.0;
    if (v.empty()) return;
    for (double x : v) mean += x;
    mean /= static_cast<double>(v.size());
    if (v.size() < 2) return;
    for (double x : v) sd += (x - mean) * (x - mean);
    sd = std::sqrt(sd / static_cast<double>(v.size() - 1));
  };
  std::vector<double> all;
  for (const OrientationTrial& t : cv.trials) all.push_back(t.error);
  meanSd(all, cv.mean_error, cv.sd_error);
  for (AngleErrors& a : cv.per_angle) meanSd(a.errors, a.mean, a.sd);
  cv.accuracy = cv.trials.empty() ? 0.0 : static_cast<double>(correct) / cv.trials.size();
  return cv;
}

}  // namespace crunch::signal
