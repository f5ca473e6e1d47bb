// session_settings.h: RobotSessionOptions <-> a recording's metadata. The round trip keeps every
// setting the map depends on; a bad value on the metadata road is an Error naming the field
// (ARCHITECTURE.md §3 "One road in"), never a crash.
#include "crunch/session/session_settings.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>

#include "crunch/signal/models_io.h"

namespace {

using namespace crunch;
using json = nlohmann::json;

signal::SignalModels shippedModels() {
  auto models = signal::loadModels(std::string(CRUNCH_SOURCE_DIR) + "/models/sim_models.json");
  REQUIRE(models);
  return models.value();
}

// Options with every recorded setting away from its default.
session::RobotSessionOptions unusualOptions() {
  MappingOptions m;
  m.working_memory = 11;
  m.sampler.schedule_steps = 9;
  m.sampler.sweeps_per_temperature = 3;
  m.sampler.smart_parent = false;
  m.sampler.smart_parent_gain = 4.5;
  m.fuse.min_support = 2;
  m.global_sweeps = 5;
  m.global_chains = 3;
  m.chain_fusion = ChainFusion::kMarginal;  // not the session's default (the vote)
  m.marginal_steps = 3;
  // Not the default (the paper's Gibbs conditional).
  m.sampler.acceptance = Acceptance::kLiteral;
  m.model.objects = ObjectModel::kRooms;  // not the default (the paper's)
  session::RobotSessionOptions s = session::sessionOptions(shippedModels(), m, 42);
  s.start = {0.3, 0.775, -0.25};
  s.area_lo = {0.0, 0.0};
  s.area_hi = {2.0, 2.5};
  s.checksum_includes_header = false;
  s.pipeline.detector.min_onset_threshold = 0.0095;
  return s;
}

std::string metadataOf(const session::RobotSessionOptions& s) {
  return session::recordingMetadata(s, {"1209:0001", "/dev/ttyUSB0", "models/sim_models.json"});
}

// `metadata` with settings.<path> replaced by `value` (path: "mapping.working_memory", "start").
std::string withSetting(const std::string& metadata, std::string path, const json& value) {
  json meta = json::parse(metadata);
  for (char& c : path) c = c == '.' ? '/' : c;
  meta["settings"][json::json_pointer("/" + path)] = value;
  return meta.dump();
}

std::string errorOf(const std::string& metadata) {
  auto r = session::sessionFromMetadata(metadata, "recording test.crec");
  REQUIRE_FALSE(r);
  return r.error().message;
}

}  // namespace

TEST_CASE("Session settings: metadata written and read back gives the same options", "[session]") {
  const session::RobotSessionOptions want = unusualOptions();
  auto got = session::sessionFromMetadata(metadataOf(want), "recording test.crec");
  REQUIRE(got);
  const session::RobotSessionOptions& s = got.value();
  CHECK(s.mapping.seed == 42);
  CHECK(s.start.x == want.start.x);
  CHECK(s.start.y == want.start.y);
  CHECK(s.start.theta == want.start.theta);
  CHECK(s.area_lo == want.area_lo);
  CHECK(s.area_hi == want.area_hi);
  CHECK(s.checksum_includes_header == false);
  CHECK(s.pipeline.detector.min_onset_threshold == 0.0095);
  CHECK(s.mapping.working_memory == 11);
  CHECK(s.mapping.sampler.schedule_steps == 9);
  CHECK(s.mapping.sampler.sweeps_per_temperature == 3);
  CHECK(s.mapping.sampler.smart_parent == false);
  CHECK(s.mapping.sampler.smart_parent_gain == 4.5);
  CHECK(s.mapping.fuse.min_support == 2);
  CHECK(s.mapping.global_sweeps == 5);
  CHECK(s.mapping.global_chains == 3);
  CHECK(s.mapping.chain_fusion == ChainFusion::kMarginal);
  CHECK(s.mapping.marginal_steps == 3);
  CHECK(s.mapping.sampler.acceptance == Acceptance::kLiteral);
  CHECK(s.mapping.model.objects == ObjectModel::kRooms);
  CHECK(s.mapping.model.sigma_r_shapelet == want.mapping.model.sigma_r_shapelet);
  CHECK(s.mapping.model.sigma_theta_shapelet == want.mapping.model.sigma_theta_shapelet);
  CHECK(s.mounts.size() == want.mounts.size());
  // The models (and the pipeline they carry) come back as written.
  CHECK(signal::modelsToJson(s.models) == signal::modelsToJson(want.models));
  // Written again, byte for byte the same document.
  CHECK(metadataOf(s) == metadataOf(want));
}

TEST_CASE("Session settings: the metadata keeps the recording format's keys", "[session]") {
  const json meta = json::parse(metadataOf(unusualOptions()));
  CHECK(meta["schema"] == "crunch.recording/1");
  CHECK(meta["crunchhost"] == "0.1.0");
  CHECK(meta["usb"] == "1209:0001");
  const json& st = meta["settings"];
  CHECK(st.size() == 6);
  for (const char* key :
       {"seed", "start", "area", "checksum_includes_header", "onset_threshold", "mapping"}) {
    CHECK(st.contains(key));
  }
  CHECK(st["mapping"].size() == 16);
  CHECK(st["mapping"]["body_sweep"] == true);
  CHECK(st["mapping"]["room_bounds"] == true);
  CHECK(st["mapping"]["chain_fusion"] == "marginal");
  CHECK(st["mapping"]["marginal_steps"] == 3);
  CHECK(st["mapping"]["acceptance"] == "literal");
  CHECK(st["mapping"]["model"] == "rooms");
}

TEST_CASE("Session settings: a bad value in the metadata is an error naming the field",
          "[session]") {
  static const std::string good = metadataOf(unusualOptions());  // once: SECTIONs re-enter
  SECTION("working_memory 0 (used to crash --replay)") {
    const std::string e = errorOf(withSetting(good, "mapping.working_memory", 0));
    CHECK(e.find("working_memory") != std::string::npos);
    CHECK(e.find("recording test.crec") != std::string::npos);
  }
  SECTION("working_memory -5") {
    CHECK(errorOf(withSetting(good, "mapping.working_memory", -5)).find("working_memory") !=
          std::string::npos);
  }
  SECTION("working_memory not a whole number") {
    CHECK(errorOf(withSetting(good, "mapping.working_memory", 7.5)).find("working_memory") !=
          std::string::npos);
  }
  SECTION("an unknown acceptance") {
    CHECK(errorOf(withSetting(good, "mapping.acceptance", "bogus")).find("acceptance") !=
          std::string::npos);
  }
  SECTION("an area of 1e308 m") {
    CHECK(errorOf(withSetting(good, "area", {0.0, 0.0, 1e308, 2.0})).find("area") !=
          std::string::npos);
  }
  SECTION("a NaN start (JSON writes it as null)") {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const std::string e = errorOf(withSetting(good, "start", {nan, 0.5, 0.0}));
    CHECK(e.find("settings.start[0]") != std::string::npos);
  }
  SECTION("a start outside any room") {
    CHECK(errorOf(withSetting(good, "start", {1e6, 0.5, 0.0})).find("start.x") !=
          std::string::npos);
  }
  SECTION("a missing setting") {
    json meta = json::parse(good);
    meta["settings"]["mapping"].erase("global_chains");
    const std::string e = errorOf(meta.dump());
    CHECK(e.find("settings.mapping.global_chains") != std::string::npos);
    CHECK(e.find("missing") != std::string::npos);
  }
  SECTION("a recording from before chain_fusion was recorded fused by the vote") {
    json meta = json::parse(good);
    meta["settings"]["mapping"].erase("chain_fusion");
    auto got = session::sessionFromMetadata(meta.dump(), "recording test.crec");
    REQUIRE(got);
    CHECK(got.value().mapping.chain_fusion == ChainFusion::kVote);
  }
  SECTION("body_sweep and room_bounds round-trip; a recording from before them has neither") {
    struct Flag {
      const char* key;
      bool (*get)(const session::RobotSessionOptions&);
      json bad;  // not a boolean
    };
    const Flag flags[] = {
        {"body_sweep", [](const session::RobotSessionOptions& o) { return o.mapping.body_sweep; }, 1},
        {"room_bounds", [](const session::RobotSessionOptions& o) { return o.room_bounds; }, "yes"}};
    for (const Flag& f : flags) {
      INFO(f.key);
      CHECK(json::parse(good)["settings"]["mapping"][f.key] == true);
      json meta = json::parse(good);
      meta["settings"]["mapping"][f.key] = false;
      auto off = session::sessionFromMetadata(meta.dump(), "recording test.crec");
      REQUIRE(off);
      CHECK_FALSE(f.get(off.value()));
      meta["settings"]["mapping"].erase(f.key);
      auto old = session::sessionFromMetadata(meta.dump(), "recording test.crec");
      REQUIRE(old);
      CHECK_FALSE(f.get(old.value()));
      meta["settings"]["mapping"][f.key] = f.bad;
      CHECK(errorOf(meta.dump()).find(std::string("settings.mapping.") + f.key) != std::string::npos);
    }
  }
  SECTION("a recording from before marginal_steps and acceptance were recorded") {
    json meta = json::parse(good);
    meta["settings"]["mapping"].erase("marginal_steps");
    meta["settings"]["mapping"].erase("acceptance");
    auto got = session::sessionFromMetadata(meta.dump(), "recording test.crec");
    REQUIRE(got);
    CHECK(got.value().mapping.marginal_steps == MappingOptions{}.marginal_steps);
    CHECK(got.value().mapping.sampler.acceptance == Acceptance::kTempered);
  }
  SECTION("an acceptance that is not paper, literal or rj") {
    CHECK(errorOf(withSetting(good, "mapping.acceptance", "metropolis"))
              .find("settings.mapping.acceptance") != std::string::npos);
    CHECK(errorOf(withSetting(good, "mapping.acceptance", 2))
              .find("settings.mapping.acceptance") != std::string::npos);
  }
  SECTION("a chain_fusion that is neither vote, pool nor marginal") {
    CHECK(errorOf(withSetting(good, "mapping.chain_fusion", "majority"))
              .find("settings.mapping.chain_fusion") != std::string::npos);
    CHECK(errorOf(withSetting(good, "mapping.chain_fusion", 1))
              .find("settings.mapping.chain_fusion") != std::string::npos);
  }
  SECTION("a recording from before the object model was recorded used the paper's") {
    json meta = json::parse(good);
    meta["settings"]["mapping"].erase("model");
    auto got = session::sessionFromMetadata(meta.dump(), "recording test.crec");
    REQUIRE(got);
    CHECK(got.value().mapping.model.objects == ObjectModel::kPaper);
  }
  SECTION("an object model that is neither paper nor rooms") {
    CHECK(errorOf(withSetting(good, "mapping.model", "chairs"))
              .find("settings.mapping.model") != std::string::npos);
    CHECK(errorOf(withSetting(good, "mapping.model", 2))
              .find("settings.mapping.model") != std::string::npos);
  }
  SECTION("an unknown setting (it could change the map)") {
    CHECK(errorOf(withSetting(good, "mapping.negative_evidence", false))
              .find("settings.mapping.negative_evidence: unknown") != std::string::npos);
  }
  SECTION("a wrong type") {
    CHECK(errorOf(withSetting(good, "checksum_includes_header", "yes"))
              .find("settings.checksum_includes_header") != std::string::npos);
  }
  SECTION("a negative seed") {
    CHECK(errorOf(withSetting(good, "seed", -1)).find("settings.seed") != std::string::npos);
  }
  SECTION("another schema, not JSON") {
    json meta = json::parse(good);
    meta["schema"] = "crunch.recording/9";
    CHECK(errorOf(meta.dump()).find("schema") != std::string::npos);
    CHECK(errorOf("{not json").find("metadata: parse error at line 1, column 3") !=
          std::string::npos);
    // Strict: a key twice is refused, not read as its last value (issue 16).
    CHECK(errorOf(R"({"schema": "x", "schema": "y"})").find("metadata: schema: the key appears twice") !=
          std::string::npos);
  }
}
