#include "crunch/session/session_settings.h"

#include <cmath>
#include <nlohmann/json.hpp>
#include <utility>
#include <vector>

#include "core/json_fields.h"
#include "crunch/mapping/sensor_model.h"
#include "crunch/robot/whiskers.h"
#include "crunch/core/json_input.h"

namespace crunch::session {

namespace {

using json = nlohmann::json;

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
            {"chain_fusion", chainFusionName(s.mapping.chain_fusion)},
            {"marginal_steps", s.mapping.marginal_steps},
            {"acceptance", acceptanceName(so.acceptance)},
            {"model", objectModelName(s.mapping.model.objects)},
            {"sigma_r_shapelet", s.mapping.model.sigma_r_shapelet},
            {"sigma_theta_shapelet", s.mapping.model.sigma_theta_shapelet},
            {"body_sweep", s.mapping.body_sweep},
            {"room_bounds", s.room_bounds}}}};
}

// The settings object onto the models' session options: every field required, unknown ones
// refused (they could change the map), types checked. Throws json_fields::FieldError.
void readSettings(const json& st, RobotSessionOptions& s) {
  using namespace json_fields;
  const std::string p = "settings";
  expectObject(st, p, {"seed", "start", "area", "checksum_includes_header", "onset_threshold",
                       "mapping"});
  auto numbers = [&p, &st](std::string_view key, std::size_t n) {
    const std::string path = member(p, key);
    const Json& a = array(required(st, p, key), path, n);
    std::vector<double> out;
    for (std::size_t i = 0; i < n; ++i) out.push_back(number(a[i], element(path, i)));
    return out;
  };
  const std::vector<double> start = numbers("start", 3);
  const std::vector<double> area = numbers("area", 4);
  s.mapping.seed = unsignedInteger(required(st, p, "seed"), member(p, "seed"));
  s.start = {start[0], start[1], start[2]};
  s.area_lo = {area[0], area[1]};
  s.area_hi = {area[2], area[3]};
  s.checksum_includes_header = requiredBool(st, p, "checksum_includes_header");
  s.pipeline.detector.min_onset_threshold = requiredNumber(st, p, "onset_threshold");
  const std::string mp = member(p, "mapping");
  const Json& m = required(st, p, "mapping");
  expectObject(m, mp, {"working_memory", "schedule_steps", "sweeps", "smart_proposals",
                       "smart_gain", "min_support", "global_sweeps", "global_chains",
                       "chain_fusion", "marginal_steps", "acceptance", "model", "sigma_r_shapelet",
                       "sigma_theta_shapelet", "body_sweep", "room_bounds"});
  auto whole = [&m, &mp](std::string_view key) {
    return integer(required(m, mp, key), member(mp, key));
  };
  s.mapping.working_memory = whole("working_memory");
  s.mapping.sampler.schedule_steps = whole("schedule_steps");
  s.mapping.sampler.sweeps_per_temperature = whole("sweeps");
  s.mapping.sampler.smart_parent = requiredBool(m, mp, "smart_proposals");
  s.mapping.sampler.smart_parent_gain = requiredNumber(m, mp, "smart_gain");
  s.mapping.fuse.min_support = whole("min_support");
  s.mapping.global_sweeps = whole("global_sweeps");
  s.mapping.global_chains = whole("global_chains");
  // Recordings made before it was recorded fused by the vote.
  s.mapping.chain_fusion = ChainFusion::kVote;
  if (m.contains("chain_fusion")) {
    const std::string path = member(mp, "chain_fusion");
    const Json& v = m["chain_fusion"];
    if (!v.is_string()) fail(path, "expected \"vote\", \"pool\" or \"marginal\"");
    const auto f = chainFusionByName(v.get<std::string>());
    if (!f) fail(path, "expected \"vote\", \"pool\" or \"marginal\"");
    s.mapping.chain_fusion = f.value();
  }
  // Recordings made before they were recorded: 4 coldest temperatures, the paper's acceptance.
  s.mapping.marginal_steps = MappingOptions{}.marginal_steps;
  if (m.contains("marginal_steps")) s.mapping.marginal_steps = whole("marginal_steps");
  s.mapping.sampler.acceptance = Acceptance::kTempered;
  if (m.contains("acceptance")) {
    const std::string path = member(mp, "acceptance");
    const Json& v = m["acceptance"];
    if (!v.is_string()) fail(path, "expected \"paper\", \"literal\" or \"rj\"");
    const auto a = acceptanceByName(v.get<std::string>());
    if (!a) fail(path, a.error().message);
    s.mapping.sampler.acceptance = a.value();
  }
  // Recordings made before it was recorded mapped with the paper's model.
  s.mapping.model.objects = ObjectModel::kPaper;
  if (m.contains("model")) {
    const std::string path = member(mp, "model");
    const Json& v = m["model"];
    if (!v.is_string()) fail(path, "expected \"paper\", \"walls\" or \"rooms\"");
    const auto model = objectModelByName(v.get<std::string>());
    if (!model) fail(path, model.error().message);
    s.mapping.model.objects = model.value();
  }
  // Recordings made before it was recorded mapped without the body's sweep.
  s.mapping.body_sweep = m.contains("body_sweep") && requiredBool(m, mp, "body_sweep");
  // ... and without the room's bounds (RobotSessionOptions::room_bounds).
  s.room_bounds = m.contains("room_bounds") && requiredBool(m, mp, "room_bounds");
  s.mapping.model.sigma_r_shapelet = requiredNumber(m, mp, "sigma_r_shapelet");
  s.mapping.model.sigma_theta_shapelet = requiredNumber(m, mp, "sigma_theta_shapelet");
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
  auto parsed = parseStrictJson(metadata_json, source + ": metadata");
  if (!parsed) return parsed.error();
  json meta = std::move(parsed.value());
  if (!meta.is_object() || !meta.contains("schema") || meta["schema"] != kRecordingSchema) {
    return Error{source + ": metadata schema is not " + std::string(kRecordingSchema)};
  }
  if (!meta.contains("models")) return Error{source + ": metadata: models: missing"};
  auto models = signal::parseModelsJson(meta["models"].dump(), source + " (models)");
  if (!models) return models.error();
  RobotSessionOptions s = sessionOptions(models.value(), MappingOptions{}, 1);
  try {
    readSettings(json_fields::required(meta, "", "settings"), s);
  } catch (const json_fields::FieldError& e) {
    return Error{source + ": metadata: " + e.path + ": " + e.what};
  } catch (const json::exception& e) {  // not expected: the readers check types first
    return Error{source + ": metadata: " + e.what()};
  }
  if (auto st = s.validate(); !st) {
    return Error{source + ": metadata: settings: " + st.error().message};
  }
  return s;
}

}  // namespace crunch::session
