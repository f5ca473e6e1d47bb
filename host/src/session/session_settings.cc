#include "crunch/session/session_settings.h"

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <stdexcept>
#include <utility>
#include <vector>

#include "crunch/mapping/sensor_model.h"
#include "crunch/robot/whiskers.h"

namespace crunch::session {

namespace {

using json = nlohmann::json;

// A metadata field that is missing, unknown or of the wrong type: `field` is its path.
struct FieldError : std::runtime_error {
  FieldError(const std::string& field, const std::string& what)
      : std::runtime_error(field + ": " + what) {}
};

// Strict reader of one JSON object: every key asked for must be there with its type, and
// finish() refuses the keys nobody asked for.
class Fields {
 public:
  Fields(const json& object, std::string path) : object_(object), path_(std::move(path)) {
    if (!object_.is_object()) throw FieldError(path_, "must be an object");
  }

  const json& at(const char* key) {
    asked_.insert(key);
    const auto it = object_.find(key);
    if (it == object_.end()) throw FieldError(name(key), "missing");
    return *it;
  }
  double number(const char* key) { return numberOf(at(key), name(key)); }
  bool boolean(const char* key) {
    const json& v = at(key);
    if (!v.is_boolean()) throw FieldError(name(key), "must be true or false");
    return v.get<bool>();
  }
  int integer(const char* key) {
    const json& v = at(key);
    if (v.is_number_unsigned() && v.get<std::uint64_t>() <= std::numeric_limits<int>::max()) {
      return static_cast<int>(v.get<std::uint64_t>());
    }
    if (v.is_number_integer() && !v.is_number_unsigned() &&
        v.get<std::int64_t>() >= std::numeric_limits<int>::min()) {
      return static_cast<int>(v.get<std::int64_t>());
    }
    throw FieldError(name(key), "must be a whole number within int range (got " + v.dump() + ")");
  }
  std::uint64_t unsignedInteger(const char* key) {
    const json& v = at(key);
    if (!v.is_number_unsigned()) {
      throw FieldError(name(key), "must be a non-negative whole number (got " + v.dump() + ")");
    }
    return v.get<std::uint64_t>();
  }
  // An array of exactly n numbers.
  std::vector<double> numbers(const char* key, std::size_t n) {
    const json& v = at(key);
    if (!v.is_array() || v.size() != n) {
      throw FieldError(name(key), "must be an array of " + std::to_string(n) + " numbers");
    }
    std::vector<double> out;
    for (std::size_t i = 0; i < n; ++i) {
      out.push_back(numberOf(v[i], name(key) + "[" + std::to_string(i) + "]"));
    }
    return out;
  }
  void finish() const {
    for (const auto& item : object_.items()) {
      if (!asked_.count(item.key())) throw FieldError(name(item.key().c_str()), "unknown setting");
    }
  }
  std::string name(const char* key) const { return path_ + "." + key; }

 private:
  // JSON has no NaN or infinity: nlohmann writes a non-finite double as null, which lands here.
  static double numberOf(const json& v, const std::string& field) {
    if (!v.is_number()) {
      throw FieldError(field, "must be a finite number (got " + v.dump() + ")");
    }
    const double d = v.get<double>();
    if (!std::isfinite(d)) throw FieldError(field, "must be a finite number");
    return d;
  }

  const json& object_;
  std::string path_;
  std::set<std::string> asked_;
};

// The settings a replay needs to give the same map: everything the session's result depends on.
json settingsJson(const RobotSessionOptions& s) {
  const SamplerOptions& so = s.mapping.sampler;
  return {{"seed", s.mapping.seed},
          {"start", {s.start.x, s.start.y, s.start.theta}},
          {"area", {s.area_lo.x(), s.area_lo.y(), s.area_hi.x(), s.area_hi.y()}},
          {"checksum_includes_header", s.checksum_includes_header},
          {"onset_threshold", s.pipeline.detector.min_onset_threshold},
          {"mapping",
           {{"working_memory", s.mapping.working_memory},
            {"schedule_steps", so.schedule_steps},
            {"sweeps", so.sweeps_per_temperature},
            {"smart_proposals", so.smart_parent},
            {"smart_gain", so.smart_parent_gain},
            {"min_support", s.mapping.fuse.min_support},
            {"global_sweeps", s.mapping.global_sweeps},
            {"global_chains", s.mapping.global_chains},
            {"sigma_r_shapelet", s.mapping.model.sigma_r_shapelet},
            {"sigma_theta_shapelet", s.mapping.model.sigma_theta_shapelet}}}};
}

// The settings object onto the models' session options. Throws FieldError.
void readSettings(const json& settings, RobotSessionOptions& s) {
  Fields st(settings, "settings");
  const std::vector<double> start = st.numbers("start", 3);
  const std::vector<double> area = st.numbers("area", 4);
  s.mapping.seed = st.unsignedInteger("seed");
  s.start = {start[0], start[1], start[2]};
  s.area_lo = {area[0], area[1]};
  s.area_hi = {area[2], area[3]};
  s.checksum_includes_header = st.boolean("checksum_includes_header");
  s.pipeline.detector.min_onset_threshold = st.number("onset_threshold");
  Fields mp(st.at("mapping"), st.name("mapping"));
  s.mapping.working_memory = mp.integer("working_memory");
  s.mapping.sampler.schedule_steps = mp.integer("schedule_steps");
  s.mapping.sampler.sweeps_per_temperature = mp.integer("sweeps");
  s.mapping.sampler.smart_parent = mp.boolean("smart_proposals");
  s.mapping.sampler.smart_parent_gain = mp.number("smart_gain");
  s.mapping.fuse.min_support = mp.integer("min_support");
  s.mapping.global_sweeps = mp.integer("global_sweeps");
  s.mapping.global_chains = mp.integer("global_chains");
  s.mapping.model.sigma_r_shapelet = mp.number("sigma_r_shapelet");
  s.mapping.model.sigma_theta_shapelet = mp.number("sigma_theta_shapelet");
  mp.finish();
  st.finish();
}

}  // namespace

RobotSessionOptions sessionOptions(const signal::SignalModels& models,
                                   const MappingOptions& mapping, std::uint64_t seed) {
  RobotSessionOptions s;
  s.models = models;
  s.pipeline = models.pipeline;  // the settings the models were trained with
  s.mounts = defaultWhiskerArray();
  s.mapping = mapping;
  s.mapping.seed = seed;
  s.mapping.progress = nullptr;
  s.mapping.model = withSensorNoise(s.mapping.model, NoiseRegime::classifiers());
  return s;
}

std::string recordingMetadata(const RobotSessionOptions& options,
                              const RecordingProvenance& provenance) {
  const json meta = {{"schema", kRecordingSchema},
                     {"crunchhost", provenance.program_version},
                     {"usb", provenance.usb},
                     {"create", provenance.create},
                     {"models_path", provenance.models_path},
                     {"models", json::parse(signal::modelsToJson(options.models))},
                     {"settings", settingsJson(options)}};
  return meta.dump();
}

Result<RobotSessionOptions> sessionFromMetadata(const std::string& metadata_json,
                                                const std::string& source) {
  json meta;
  try {
    meta = json::parse(metadata_json);
  } catch (const json::exception& e) {
    return Error{source + ": metadata is not JSON: " + e.what()};
  }
  if (!meta.is_object() || !meta.contains("schema") || meta["schema"] != kRecordingSchema) {
    return Error{source + ": metadata schema is not " + std::string(kRecordingSchema)};
  }
  if (!meta.contains("models")) return Error{source + ": metadata: models: missing"};
  auto models = signal::parseModelsJson(meta["models"].dump(), source + " (models)");
  if (!models) return models.error();
  RobotSessionOptions s = sessionOptions(models.value(), MappingOptions{}, 1);
  try {
    if (!meta.contains("settings")) throw FieldError("settings", "missing");
    readSettings(meta["settings"], s);
  } catch (const FieldError& e) {
    return Error{source + ": metadata: " + e.what()};
  } catch (const json::exception& e) {  // not expected: Fields checks types first
    return Error{source + ": metadata: " + e.what()};
  }
  if (auto st = s.validate(); !st) {
    return Error{source + ": metadata: settings: " + st.error().message};
  }
  return s;
}

}  // namespace crunch::session
