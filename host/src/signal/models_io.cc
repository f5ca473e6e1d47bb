#include "crunch/signal/models_io.h"

#include <cassert>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <system_error>

#include "core/json_fields.h"
#include "crunch/core/atomic_file.h"  // writeFileAtomic, ensureDirectory
#include "crunch/core/json_input.h"

namespace crunch::signal {

namespace {

using OrderedJson = nlohmann::ordered_json;
using Json = json_fields::Json;
using namespace json_fields;

std::string whiskerPath(int w) { return element("radial.whiskers", static_cast<size_t>(w)); }
std::string templatePath(size_t k) { return element("orientation.templates", k); }

}  // namespace

Status validateModels(const SignalModels& models) {
  const RadialModel& radial = models.radial;
  if (Status s = radial.options.validate(); !s.ok()) return s;
  for (int w = 0; w < kWhiskers; ++w) {
    const RadialLine& l = radial.whiskers[w];
    const std::string p = whiskerPath(w);
    const std::pair<const char*, double> numbers[] = {
        {"a1", l.a1},         {"a0", l.a0},       {"sigma", l.sigma}, {"f1_min", l.f1_min},
        {"f1_max", l.f1_max}, {"r_min", l.r_min}, {"r_max", l.r_max}};
    for (const auto& [key, v] : numbers) {
      if (!std::isfinite(v)) return Error{member(p, key) + ": not a finite number"};
    }
    if (l.samples < 0) return Error{member(p, "samples") + ": negative"};
    // Physical ranges (issue 16), from the whisker's own length L = external_length: a fit's
    // residual is a positive distance no longer than the whisker (sigma 0 would make every
    // other reading impossible); f1 is a Hall angle; the training contacts lie on the whisker;
    // and the line, over its own training range, predicts distances within one whisker length
    // of the whisker (a1 = 1e308 does not).
    const double L = radial.options.external_length;
    if (!(l.sigma > 0.0 && l.sigma <= L)) {
      return Error{member(p, "sigma") + ": expected a residual in (0, " + std::to_string(L) +
                   "] m (the whisker's external_length), got " + std::to_string(l.sigma)};
    }
    if (!(l.f1_min <= l.f1_max && std::abs(l.f1_min) <= kPi && std::abs(l.f1_max) <= kPi)) {
      return Error{p + ": f1_min, f1_max: expected angles in [-pi, pi] with f1_min <= f1_max"};
    }
    if (!(0.0 <= l.r_min && l.r_min <= l.r_max && l.r_max <= L)) {
      return Error{p + ": r_min, r_max: expected 0 <= r_min <= r_max <= external_length (" +
                   std::to_string(L) + " m)"};
    }
    for (const double f1 : {l.f1_min, l.f1_max}) {
      const double r = l.predict(f1);
      if (!(r >= -L && r <= 2.0 * L)) {
        return Error{p + ": a1, a0: the line predicts r = " + std::to_string(r) + " m at f1 = " +
                     std::to_string(f1) + ", more than a whisker length (" + std::to_string(L) +
                     " m) off the whisker"};
      }
    }
  }
  const OrientationModel& o = models.orientation;
  if (o.decimation < 1) return Error{"orientation.decimation: expected >= 1"};
  if (o.columns < 1) return Error{"orientation.columns: expected >= 1"};
  if (o.templates.empty()) return Error{"orientation.templates: expected at least one template"};
  for (size_t k = 0; k < o.templates.size(); ++k) {
    const OrientationTemplate& t = o.templates[k];
    if (!std::isfinite(t.angle)) return Error{member(templatePath(k), "angle") + ": not finite"};
    if (t.windows < 0) return Error{member(templatePath(k), "windows") + ": negative"};
    if (t.mean.cols() != o.columns) {
      return Error{member(templatePath(k), "data") + ": " + std::to_string(t.mean.cols()) +
                   " columns, the model declares " + std::to_string(o.columns)};
    }
    if (!t.mean.allFinite()) return Error{member(templatePath(k), "data") + ": not finite"};
  }
  if (Status s = models.pipeline.validate(); !s.ok()) {
    return Error{"pipeline." + s.error().message};
  }
  // The file's two halves agree: the templates were trained on the windows this pipeline
  // records (SignalPipeline::setModels refuses them otherwise; found by metadata_fuzz).
  const WindowOptions& w = models.pipeline.window;
  if (o.decimation != w.decimation || o.columns != w.columns()) {
    return Error{"orientation: templates of decimation " + std::to_string(o.decimation) + " and " +
                 std::to_string(o.columns) + " columns, but pipeline.window records decimation " +
                 std::to_string(w.decimation) + " and " + std::to_string(w.columns()) +
                 " columns: the templates were trained with another window"};
  }
  if (Status s = models.ramp.validate(); !s.ok()) return Error{"ramp." + s.error().message};
  return okStatus();
}

namespace {

OrderedJson pipelineJson(const PipelineOptions& p) {
  const ContactDetectorOptions& d = p.detector;
  const SmoothingFilter::Options& f = d.smoothing;
  return {{"detector",
           {{"radians_per_code", d.radians_per_code},
            {"smoothing",
             {{"order", f.low_pass.order},
              {"cutoff_hz", f.low_pass.cutoff_hz},
              {"sample_rate_hz", f.low_pass.sample_rate_hz},
              {"moving_average", f.moving_average}}},
            {"settle_samples", d.settle_samples},
            {"calibration_samples", d.calibration_samples},
            {"max_noise_sigma", d.max_noise_sigma},
            {"onset_sigmas", d.onset_sigmas},
            {"release_sigmas", d.release_sigmas},
            {"min_onset_threshold", d.min_onset_threshold},
            {"release_samples", d.release_samples},
            {"baseline_time_constant_s", d.baseline_time_constant_s},
            {"max_held_samples", d.max_held_samples},
            {"accept_dropped", d.accept_dropped}}},
          {"window", {{"samples", p.window.samples}, {"decimation", p.window.decimation}}},
          {"max_episode_samples", p.max_episode_samples},
          {"max_held_fraction", p.max_held_fraction},
          {"ramp",
           {{"theta_low", p.ramp.theta_low},
            {"theta_high", p.ramp.theta_high},
            {"min_points", p.ramp.min_points},
            {"min_span", p.ramp.min_span},
            {"max_translation", p.ramp.max_translation}}}};
}

}  // namespace

std::string modelsToJson(const SignalModels& models) {
  assert(validateModels(models).ok());
  OrderedJson whiskers = OrderedJson::array();
  for (const RadialLine& l : models.radial.whiskers) {
    whiskers.push_back({{"a1", l.a1},
                        {"a0", l.a0},
                        {"sigma", l.sigma},
                        {"samples", l.samples},
                        {"f1_min", l.f1_min},
                        {"f1_max", l.f1_max},
                        {"r_min", l.r_min},
                        {"r_max", l.r_max}});
  }
  OrderedJson templates = OrderedJson::array();
  for (const OrientationTemplate& t : models.orientation.templates) {
    OrderedJson rows = OrderedJson::array();
    for (int c = 0; c < kChannels; ++c) {
      OrderedJson row = OrderedJson::array();
      for (Eigen::Index j = 0; j < t.mean.cols(); ++j) row.push_back(t.mean(c, j));
      rows.push_back(std::move(row));
    }
    templates.push_back({{"angle", t.angle}, {"windows", t.windows}, {"data", std::move(rows)}});
  }
  const OrderedJson doc = {{"format", kModelsFormat},
                           {"version", kModelsVersion},
                           {"radial",
                            {{"external_length", models.radial.options.external_length},
                             {"tip_zone", models.radial.options.tip_zone},
                             {"whiskers", std::move(whiskers)}}},
                           {"orientation",
                            {{"channels", kChannels},
                             {"decimation", models.orientation.decimation},
                             {"columns", models.orientation.columns},
                             {"templates", std::move(templates)}}},
                           {"pipeline", pipelineJson(models.pipeline)},
                           {"ramp",
                            {{"gain", models.ramp.gain},
                             {"compliance_scale", models.ramp.compliance_scale}}}};
  // Templates are long rows of numbers: no indentation keeps the file compact; nlohmann writes
  // doubles with enough digits to read back bit-exact.
  return doc.dump() + "\n";
}

namespace {

RadialModel parseRadial(const Json& j) {
  const std::string path = "radial";
  expectObject(j, path, {"external_length", "tip_zone", "whiskers"});
  RadialModel m;
  m.options.external_length = requiredNumber(j, path, "external_length");
  m.options.tip_zone = requiredNumber(j, path, "tip_zone");
  if (Status s = m.options.validate(); !s.ok()) {
    // The option's own message starts with "radial.<field>: ".
    const std::string& msg = s.error().message;
    const size_t colon = msg.find(": ");
    fail(msg.substr(0, colon), msg.substr(colon + 2));
  }
  const Json& whiskers = array(required(j, path, "whiskers"), "radial.whiskers", kWhiskers);
  for (int w = 0; w < kWhiskers; ++w) {
    const std::string p = whiskerPath(w);
    const Json& o = whiskers[static_cast<size_t>(w)];
    expectObject(o, p, {"a1", "a0", "sigma", "samples", "f1_min", "f1_max", "r_min", "r_max"});
    RadialLine& l = m.whiskers[w];
    l.a1 = requiredNumber(o, p, "a1");
    l.a0 = requiredNumber(o, p, "a0");
    l.sigma = requiredNumber(o, p, "sigma");
    if (l.sigma < 0.0) fail(member(p, "sigma"), "expected a non-negative number");
    l.samples = count(required(o, p, "samples"), member(p, "samples"));
    l.f1_min = requiredNumber(o, p, "f1_min");
    l.f1_max = requiredNumber(o, p, "f1_max");
    if (l.f1_max < l.f1_min) fail(member(p, "f1_max"), "less than f1_min");
    l.r_min = requiredNumber(o, p, "r_min");
    l.r_max = requiredNumber(o, p, "r_max");
    if (l.r_max < l.r_min) fail(member(p, "r_max"), "less than r_min");
  }
  return m;
}

OrientationModel parseOrientation(const Json& j) {
  const std::string path = "orientation";
  expectObject(j, path, {"channels", "decimation", "columns", "templates"});
  const int channels = count(required(j, path, "channels"), "orientation.channels");
  if (channels != kChannels) {
    fail("orientation.channels",
         "expected " + std::to_string(kChannels) + ", got " + std::to_string(channels));
  }
  OrientationModel m;
  // A window is at most a few minutes at 2 kHz: bound the sizes so a corrupt file cannot ask
  // for gigabytes.
  constexpr int kMaxColumns = 1 << 20;
  m.decimation = count(required(j, path, "decimation"), "orientation.decimation", kMaxColumns);
  if (m.decimation < 1) fail("orientation.decimation", "expected at least 1");
  m.columns = count(required(j, path, "columns"), "orientation.columns", kMaxColumns);
  if (m.columns < 1) fail("orientation.columns", "expected at least 1");
  const Json& templates = required(j, path, "templates");
  expectArray(templates, "orientation.templates");
  if (templates.empty()) fail("orientation.templates", "expected at least one template");
  for (size_t k = 0; k < templates.size(); ++k) {
    const std::string p = templatePath(k);
    const Json& t = templates[k];
    expectObject(t, p, {"angle", "windows", "data"});
    OrientationTemplate tmpl;
    tmpl.angle = requiredNumber(t, p, "angle");
    tmpl.windows = count(required(t, p, "windows"), member(p, "windows"));
    const std::string dp = member(p, "data");
    const Json& rows = array(required(t, p, "data"), dp, kChannels);
    tmpl.mean.resize(kChannels, m.columns);
    for (int c = 0; c < kChannels; ++c) {
      const std::string rp = element(dp, static_cast<size_t>(c));
      const Json& row = array(rows[static_cast<size_t>(c)], rp, static_cast<size_t>(m.columns));
      for (int col = 0; col < m.columns; ++col) {
        tmpl.mean(c, col) =
            number(row[static_cast<size_t>(col)], element(rp, static_cast<size_t>(col)));
      }
    }
    m.templates.push_back(std::move(tmpl));
  }
  return m;
}

PipelineOptions parsePipeline(const Json& j, bool with_ramp) {
  const std::string path = "pipeline";
  if (with_ramp) {
    expectObject(j, path, {"detector", "window", "max_episode_samples", "max_held_fraction", "ramp"});
  } else {
    expectObject(j, path, {"detector", "window", "max_episode_samples", "max_held_fraction"});
  }
  PipelineOptions p;
  const std::string dp = "pipeline.detector";
  const Json& d = required(j, path, "detector");
  expectObject(d, dp, {"radians_per_code", "smoothing", "settle_samples", "calibration_samples",
                       "max_noise_sigma", "onset_sigmas", "release_sigmas",
                       "min_onset_threshold", "release_samples", "baseline_time_constant_s",
                       "max_held_samples", "accept_dropped"});
  ContactDetectorOptions& o = p.detector;
  o.radians_per_code = requiredNumber(d, dp, "radians_per_code");
  const std::string sp = "pipeline.detector.smoothing";
  const Json& sm = required(d, dp, "smoothing");
  expectObject(sm, sp, {"order", "cutoff_hz", "sample_rate_hz", "moving_average"});
  o.smoothing.low_pass.order = count(required(sm, sp, "order"), member(sp, "order"), 64);
  o.smoothing.low_pass.cutoff_hz = requiredNumber(sm, sp, "cutoff_hz");
  o.smoothing.low_pass.sample_rate_hz = requiredNumber(sm, sp, "sample_rate_hz");
  o.smoothing.moving_average =
      count(required(sm, sp, "moving_average"), member(sp, "moving_average"), 1 << 16);
  // Counts of samples: at most 10 minutes at 2 kHz, so a corrupt file cannot ask for gigabytes.
  constexpr int kMaxSamples = 1200000;
  o.settle_samples = count(required(d, dp, "settle_samples"), member(dp, "settle_samples"),
                           kMaxSamples);
  o.calibration_samples = count(required(d, dp, "calibration_samples"),
                                member(dp, "calibration_samples"), kMaxSamples);
  o.max_noise_sigma = requiredNumber(d, dp, "max_noise_sigma");
  o.onset_sigmas = requiredNumber(d, dp, "onset_sigmas");
  o.release_sigmas = requiredNumber(d, dp, "release_sigmas");
  o.min_onset_threshold = requiredNumber(d, dp, "min_onset_threshold");
  o.release_samples = count(required(d, dp, "release_samples"), member(dp, "release_samples"),
                            kMaxSamples);
  o.baseline_time_constant_s = requiredNumber(d, dp, "baseline_time_constant_s");
  o.max_held_samples = count(required(d, dp, "max_held_samples"), member(dp, "max_held_samples"),
                             kMaxSamples);
  o.accept_dropped = requiredBool(d, dp, "accept_dropped");
  const std::string wp = "pipeline.window";
  const Json& w = required(j, path, "window");
  expectObject(w, wp, {"samples", "decimation"});
  p.window.samples = count(required(w, wp, "samples"), member(wp, "samples"), kMaxSamples);
  p.window.decimation = count(required(w, wp, "decimation"), member(wp, "decimation"), kMaxSamples);
  p.max_episode_samples = count(required(j, path, "max_episode_samples"),
                                member(path, "max_episode_samples"), kMaxSamples);
  p.max_held_fraction = requiredNumber(j, path, "max_held_fraction");
  if (with_ramp) {
    const std::string rp = "pipeline.ramp";
    const Json& r = required(j, path, "ramp");
    expectObject(r, rp, {"theta_low", "theta_high", "min_points", "min_span", "max_translation"});
    p.ramp.theta_low = requiredNumber(r, rp, "theta_low");
    p.ramp.theta_high = requiredNumber(r, rp, "theta_high");
    p.ramp.min_points = count(required(r, rp, "min_points"), member(rp, "min_points"), kMaxSamples);
    p.ramp.min_span = requiredNumber(r, rp, "min_span");
    p.ramp.max_translation = requiredNumber(r, rp, "max_translation");
  }
  return p;
}

RampCalibration parseRampCalibration(const Json& j) {
  expectObject(j, "ramp", {"gain", "compliance_scale"});
  RampCalibration c;
  c.gain = requiredNumber(j, "ramp", "gain");
  c.compliance_scale = requiredNumber(j, "ramp", "compliance_scale");
  return c;
}

// What a version-1 file's models were trained with (models_io.h).
PipelineOptions version1Pipeline() {
  PipelineOptions p;
  p.detector.min_onset_threshold = kVersion1OnsetThreshold;
  return p;
}

SignalModels parseDocument(const Json& doc) {
  expectObject(doc, "");
  const Json& format = required(doc, "", "format");
  if (!format.is_string() || format.get<std::string>() != kModelsFormat) {
    fail("format", std::string("expected \"") + kModelsFormat + "\", got " + format.dump());
  }
  // The version first: another version may lay out everything else differently.
  const Json& version = required(doc, "", "version");
  if (!version.is_number_integer() || version.get<std::int64_t>() < 1 ||
      version.get<std::int64_t>() > kModelsVersion) {
    fail("version", "unsupported version " + version.dump() + " (this build reads versions 1 to " +
                        std::to_string(kModelsVersion) + ")");
  }
  const std::int64_t v = version.get<std::int64_t>();
  if (v == 1) {
    expectObject(doc, "", {"format", "version", "radial", "orientation"});
  } else if (v == 2) {
    expectObject(doc, "", {"format", "version", "radial", "orientation", "pipeline"});
  } else {
    expectObject(doc, "", {"format", "version", "radial", "orientation", "pipeline", "ramp"});
  }
  SignalModels models;
  models.radial = parseRadial(required(doc, "", "radial"));
  models.orientation = parseOrientation(required(doc, "", "orientation"));
  models.pipeline = v == 1 ? version1Pipeline() : parsePipeline(required(doc, "", "pipeline"), v >= 3);
  if (v >= 3) models.ramp = parseRampCalibration(required(doc, "", "ramp"));
  if (Status s = validateModels(models); !s.ok()) {
    const std::string& msg = s.error().message;
    const size_t colon = msg.find(": ");
    fail(msg.substr(0, colon), colon == std::string::npos ? "invalid" : msg.substr(colon + 2));
  }
  return models;
}

}  // namespace

Result<SignalModels> parseModelsJson(const std::string& text, const std::string& source) {
  if (auto st = checkStrictJson(text, source); !st) return st.error();
  Json doc;
  try {
    doc = Json::parse(text);
  } catch (const Json::exception& e) {
    return Error{source + ": " + withoutExceptionTag(e.what())};
  }
  try {
    return parseDocument(doc);
  } catch (const FieldError& e) {
    return Error{describe(source, e)};
  }
}

Status saveModels(const SignalModels& models, const std::string& path) {
  if (Status s = validateModels(models); !s.ok()) {
    return Error{path + ": signal models not written: " + s.error().message};
  }
  return writeFileAtomic(path, modelsToJson(models));
}

Result<SignalModels> loadModels(const std::string& path) {
  auto text = readInputFile(path, "signal models file");
  if (!text) return text.error();
  return parseModelsJson(text.value(), path);
}

std::string shippedModelsPath(const std::string& source_tree_path) {
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const std::filesystem::path installed =
        exe.parent_path().parent_path() / "share" / "crunchbot" / "models" / "sim_models.json";
    if (std::filesystem::is_regular_file(installed, ec)) return installed.string();
  }
  return source_tree_path;
}

}  // namespace crunch::signal
