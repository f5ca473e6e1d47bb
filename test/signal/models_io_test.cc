// The signal models file: round trip, and a clear error for every kind of corruption.
#include "crunch/signal/models_io.h"

#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>

#include "crunch/core/rng.h"
#include "support/temp_dir.h"

using namespace crunch;
using namespace crunch::signal;
using Json = nlohmann::json;

namespace {

// Templates of `columns` columns at decimation 20, with the pipeline window they come from.
SignalModels sampleModels(int columns = 7) {
  SignalModels m;
  Rng rng(9);
  m.radial.options = {.external_length = 0.14, .tip_zone = 0.05};
  for (int w = 0; w < kWhiskers; ++w) {
    RadialLine& l = m.radial.whiskers[w];
    l.a1 = -3.0 - 0.1 * w + 1e-17 * rng.normal();
    l.a0 = 0.2 + 0.01 * rng.normal();  // arbitrary bits: the round trip must keep them all
    l.sigma = 0.003 + 0.001 * w;
    l.samples = 30;
    l.f1_min = 0.01;
    l.f1_max = 0.03 + 1e-3 * rng.uniform();
    l.r_min = 0.09;
    l.r_max = 0.14;
  }
  m.orientation.decimation = 20;
  m.orientation.columns = columns;
  for (double a : defaultOrientationAngles()) {
    OrientationTemplate t;
    t.angle = a;
    t.windows = 3;
    t.mean.resize(kChannels, columns);
    for (Eigen::Index i = 0; i < t.mean.size(); ++i) t.mean.data()[i] = 0.01 * rng.normal();
    m.orientation.templates.push_back(t);
  }
  m.pipeline.window = {20 * columns, 20};  // the windows the templates were trained on
  return m;
}


// The error message for a document made by editing the valid one.
std::string errorFor(const std::function<void(Json&)>& edit) {
  Json doc = Json::parse(modelsToJson(sampleModels()));
  edit(doc);
  const Result<SignalModels> r = parseModelsJson(doc.dump(), "models.json");
  return r.ok() ? std::string("(ok)") : r.error().message;
}

}  // namespace

TEST_CASE("Models file: round trip is bit-exact", "[signal]") {
  TempDir dir;
  const SignalModels m = sampleModels();
  const std::string path = dir.file("signal_models.json");
  REQUIRE(saveModels(m, path).ok());
  CHECK(dir.entries().size() == 1);  // no temporary left behind
  const Result<SignalModels> back = loadModels(path);
  REQUIRE(back.ok());
  const SignalModels& b = back.value();
  CHECK(b.radial.options.external_length == m.radial.options.external_length);
  CHECK(b.radial.options.tip_zone == m.radial.options.tip_zone);
  for (int w = 0; w < kWhiskers; ++w) {
    const RadialLine &x = m.radial.whiskers[w], &y = b.radial.whiskers[w];
    CHECK(x.a1 == y.a1);
    CHECK(x.a0 == y.a0);
    CHECK(x.sigma == y.sigma);
    CHECK(x.samples == y.samples);
    CHECK(x.f1_min == y.f1_min);
    CHECK(x.f1_max == y.f1_max);
    CHECK(x.r_min == y.r_min);
    CHECK(x.r_max == y.r_max);
  }
  CHECK(b.orientation.decimation == 20);
  CHECK(b.orientation.columns == 7);
  REQUIRE(b.orientation.templates.size() == 15);
  for (size_t k = 0; k < 15; ++k) {
    CHECK(b.orientation.templates[k].angle == m.orientation.templates[k].angle);
    CHECK(b.orientation.templates[k].windows == 3);
    CHECK(b.orientation.templates[k].mean == m.orientation.templates[k].mean);
  }
  const Json doc = Json::parse(modelsToJson(m));
  CHECK(doc["format"] == "crunchbot-signal-models");
  CHECK(doc["version"] == 3);
  CHECK(b.pipeline.detector.min_onset_threshold == m.pipeline.detector.min_onset_threshold);
}

TEST_CASE("Models file: the pipeline settings travel with the models", "[signal]") {
  SignalModels m = sampleModels();
  m.pipeline.detector.min_onset_threshold = 0.0123;
  m.pipeline.detector.smoothing.moving_average = 7;
  m.pipeline.detector.accept_dropped = true;
  m.pipeline.window = {140, 20};
  m.pipeline.max_episode_samples = 9000;
  m.pipeline.max_held_fraction = 0.25;
  auto back = parseModelsJson(modelsToJson(m), "m.json");
  REQUIRE(back.ok());
  const PipelineOptions& p = back.value().pipeline;
  CHECK(p.detector.min_onset_threshold == 0.0123);
  CHECK(p.detector.smoothing.moving_average == 7);
  CHECK(p.detector.accept_dropped);
  CHECK(p.window.samples == 140);
  CHECK(p.window.decimation == 20);
  CHECK(p.max_episode_samples == 9000);
  CHECK(p.max_held_fraction == 0.25);
  // A bad setting is named by its path in the file.
  CHECK_THAT(errorFor([](Json& d) { d["pipeline"]["detector"]["onset_sigmas"] = -1.0; }),
             Catch::Contains("models.json: pipeline.detector.onset_sigmas"));
  CHECK_THAT(errorFor([](Json& d) { d["pipeline"]["window"]["samples"] = 100000000; }),
             Catch::Contains("pipeline.window.samples"));
  CHECK_THAT(errorFor([](Json& d) { d["pipeline"].erase("max_held_fraction"); }),
             Catch::Contains("pipeline.max_held_fraction: missing"));
  CHECK_THAT(errorFor([](Json& d) { d.erase("pipeline"); }), Catch::Contains("pipeline: missing"));
}

TEST_CASE("Models file: a version-1 file reads with the pipeline it was trained with",
          "[signal]") {
  // Version 1 had no "pipeline": every such file was trained with the defaults and an onset
  // threshold of kVersion1OnsetThreshold: templates of the default window's 200 columns.
  Json doc = Json::parse(modelsToJson(sampleModels(200)));
  doc["version"] = 1;
  doc.erase("pipeline");
  doc.erase("ramp");
  auto v1 = parseModelsJson(doc.dump(), "v1.json");
  REQUIRE(v1.ok());
  PipelineOptions expected;
  expected.detector.min_onset_threshold = kVersion1OnsetThreshold;
  CHECK(v1.value().pipeline.detector.min_onset_threshold == kVersion1OnsetThreshold);
  CHECK(v1.value().pipeline.window.samples == expected.window.samples);
  CHECK(v1.value().pipeline.max_episode_samples == expected.max_episode_samples);
  // ... and a version-1 file with a "pipeline" is not one.
  doc["pipeline"] = Json::parse(modelsToJson(sampleModels()))["pipeline"];
  CHECK_THAT(parseModelsJson(doc.dump(), "v1.json").error().message,
             Catch::Contains("pipeline: unknown key"));
}

TEST_CASE("Models file: the ramp settings and calibration round-trip, version 2 reads nominal",
          "[signal]") {
  SignalModels m = sampleModels();
  m.pipeline.ramp.theta_low = 0.015;
  m.pipeline.ramp.min_points = 55;
  m.ramp.gain = 0.97;
  m.ramp.compliance_scale = 1.12;
  auto back = parseModelsJson(modelsToJson(m), "m.json");
  REQUIRE(back.ok());
  CHECK(back.value().pipeline.ramp.theta_low == 0.015);
  CHECK(back.value().pipeline.ramp.min_points == 55);
  CHECK(back.value().ramp.gain == 0.97);
  CHECK(back.value().ramp.compliance_scale == 1.12);
  // Version 2: no ramp settings, no calibration: the defaults and the nominal beam.
  Json doc = Json::parse(modelsToJson(m));
  doc["version"] = 2;
  doc.erase("ramp");
  doc["pipeline"].erase("ramp");
  auto v2 = parseModelsJson(doc.dump(), "v2.json");
  REQUIRE(v2.ok());
  CHECK(v2.value().pipeline.ramp.theta_low == RampOptions{}.theta_low);
  CHECK(v2.value().ramp.gain == 1.0);
  CHECK(v2.value().ramp.compliance_scale == 1.0);
  // A version-3 file must carry both; a bad value is named by its path.
  CHECK_THAT(errorFor([](Json& d) { d.erase("ramp"); }), Catch::Contains("ramp: missing"));
  CHECK_THAT(errorFor([](Json& d) { d["pipeline"]["ramp"].erase("min_span"); }),
             Catch::Contains("pipeline.ramp.min_span: missing"));
  CHECK_THAT(errorFor([](Json& d) { d["ramp"]["gain"] = -1.0; }), Catch::Contains("ramp.gain"));
  CHECK_THAT(errorFor([](Json& d) { d["pipeline"]["ramp"]["theta_high"] = 0.001; }),
             Catch::Contains("pipeline.ramp.theta_high"));
}

TEST_CASE("Models file: a missing, unreadable or malformed file names the file", "[signal]") {
  TempDir dir;
  const std::string missing = dir.file("nope.json");
  Result<SignalModels> r = loadModels(missing);
  REQUIRE_FALSE(r.ok());
  CHECK_THAT(r.error().message, Catch::StartsWith(missing) && Catch::Contains("No such file"));
  r = loadModels(dir.path().string());
  REQUIRE_FALSE(r.ok());
  CHECK_THAT(r.error().message, Catch::Contains("is a directory"));

  const std::string bad = dir.file("bad.json");
  {
    std::ofstream(bad) << "{\"format\": \"crunchbot-signal-models\", ";  // cut short
  }
  r = loadModels(bad);
  REQUIRE_FALSE(r.ok());
  CHECK_THAT(r.error().message, Catch::StartsWith(bad + ": ") && Catch::Contains("parse error"));
  { std::ofstream(bad) << ""; }
  CHECK_FALSE(loadModels(bad).ok());
  // JSON has no NaN; a writer that tried would produce invalid JSON.
  const std::string text = modelsToJson(sampleModels());
  std::string nan_text = text;
  nan_text.replace(nan_text.find("\"sigma\":") + 8, 0, "NaN,\"x\":");
  CHECK_FALSE(parseModelsJson(nan_text, "m.json").ok());
  CHECK_THAT(parseModelsJson("[1, 2]", "m.json").error().message,
             Catch::Contains("m.json: (document): expected an object"));
}

TEST_CASE("Models file: wrong format or version is refused first", "[signal]") {
  CHECK(errorFor([](Json&) {}) == "(ok)");
  CHECK_THAT(errorFor([](Json& d) { d["version"] = 4; }),
             Catch::Contains("models.json: version: unsupported version 4"));
  CHECK_THAT(errorFor([](Json& d) { d["version"] = 0; }),
             Catch::Contains("models.json: version: unsupported version 0"));
  CHECK_THAT(errorFor([](Json& d) { d["version"] = "1"; }), Catch::Contains("version"));
  CHECK_THAT(errorFor([](Json& d) { d.erase("version"); }), Catch::Contains("version: missing"));
  // Version is checked before the rest: a v4 file with other fields is reported as v4.
  CHECK_THAT(errorFor([](Json& d) {
               d["version"] = 4;
               d.erase("radial");
             }),
             Catch::Contains("unsupported version"));
  CHECK_THAT(errorFor([](Json& d) { d["format"] = "crunch.map/1"; }),
             Catch::Contains("models.json: format: expected \"crunchbot-signal-models\""));
  CHECK_THAT(errorFor([](Json& d) { d["extra"] = 1; }), Catch::Contains("extra: unknown key"));
}

TEST_CASE("Models file: a missing or ill-typed field is named by its path", "[signal]") {
  CHECK_THAT(errorFor([](Json& d) { d.erase("orientation"); }),
             Catch::Contains("models.json: orientation: missing (required)"));
  CHECK_THAT(errorFor([](Json& d) { d["radial"]["whiskers"][2].erase("a0"); }),
             Catch::Contains("models.json: radial.whiskers[2].a0: missing (required)"));
  CHECK_THAT(errorFor([](Json& d) { d["radial"]["whiskers"][1]["a1"] = "big"; }),
             Catch::Contains("radial.whiskers[1].a1: expected a number, got string"));
  CHECK_THAT(errorFor([](Json& d) { d["radial"]["whiskers"][0]["samples"] = -3; }),
             Catch::Contains("radial.whiskers[0].samples: expected an integer"));
  CHECK_THAT(errorFor([](Json& d) { d["radial"]["whiskers"][0]["samples"] = 2.5; }),
             Catch::Contains("radial.whiskers[0].samples"));
  CHECK_THAT(errorFor([](Json& d) { d["radial"]["whiskers"][3]["sigma"] = -0.1; }),
             Catch::Contains("radial.whiskers[3].sigma"));
  CHECK_THAT(errorFor([](Json& d) { d["radial"]["tip_zone"] = 0.5; }),
             Catch::Contains("radial.tip_zone"));
  CHECK_THAT(errorFor([](Json& d) { d["orientation"]["templates"][4]["data"][2][6] = nullptr; }),
             Catch::Contains("orientation.templates[4].data[2][6]: expected a number, got null"));
  CHECK_THAT(errorFor([](Json& d) { d["orientation"]["templates"][0]["angle"] = true; }),
             Catch::Contains("orientation.templates[0].angle: expected a number"));
  CHECK_THAT(errorFor([](Json& d) { d["orientation"]["templates"] = Json::object(); }),
             Catch::Contains("orientation.templates: expected an array"));
  // A number too large for a double is a parse error, not an infinity.
  Json doc = Json::parse(modelsToJson(sampleModels()));
  std::string text = doc.dump();
  text.replace(text.find("\"tip_zone\":") + 11, 4, "1e999");
  const Result<SignalModels> r = parseModelsJson(text, "models.json");
  REQUIRE_FALSE(r.ok());
  CHECK_THAT(r.error().message, Catch::StartsWith("models.json: "));
}

TEST_CASE("Models file: wrong sizes are refused", "[signal]") {
  CHECK_THAT(errorFor([](Json& d) { d["radial"]["whiskers"].erase(3); }),
             Catch::Contains("radial.whiskers: expected 4 elements, got 3"));
  CHECK_THAT(errorFor([](Json& d) { d["orientation"]["channels"] = 6; }),
             Catch::Contains("orientation.channels: expected 8"));
  CHECK_THAT(errorFor([](Json& d) { d["orientation"]["templates"][2]["data"].erase(7); }),
             Catch::Contains("orientation.templates[2].data: expected 8 elements, got 7"));
  CHECK_THAT(errorFor([](Json& d) { d["orientation"]["templates"][1]["data"][5].erase(0); }),
             Catch::Contains("orientation.templates[1].data[5]: expected 7 elements, got 6"));
  CHECK_THAT(errorFor([](Json& d) { d["orientation"]["columns"] = 8; }),
             Catch::Contains("orientation.templates[0].data[0]: expected 8 elements"));
  CHECK_THAT(errorFor([](Json& d) { d["orientation"]["columns"] = 0; }),
             Catch::Contains("orientation.columns: expected at least 1"));
  CHECK_THAT(errorFor([](Json& d) { d["orientation"]["decimation"] = 1u << 30; }),
             Catch::Contains("orientation.decimation: expected an integer"));
  CHECK_THAT(errorFor([](Json& d) { d["orientation"]["templates"] = Json::array(); }),
             Catch::Contains("orientation.templates: expected at least one template"));
}

TEST_CASE("Models file: saving invalid models fails and keeps the old file", "[signal]") {
  TempDir dir;
  const std::string path = dir.file("m.json");
  REQUIRE(saveModels(sampleModels(), path).ok());
  std::ifstream in(path);
  std::stringstream before;
  before << in.rdbuf();

  SignalModels bad = sampleModels();
  bad.radial.whiskers[2].a1 = std::nan("");
  Status s = saveModels(bad, path);
  REQUIRE_FALSE(s.ok());
  CHECK_THAT(s.error().message,
             Catch::StartsWith(path) && Catch::Contains("radial.whiskers[2].a1"));
  bad = sampleModels();
  bad.orientation.templates[3].mean(0, 0) = INFINITY;
  s = saveModels(bad, path);
  REQUIRE_FALSE(s.ok());
  CHECK_THAT(s.error().message, Catch::Contains("orientation.templates[3].data"));
  bad = sampleModels();
  bad.orientation.templates[1].mean.resize(kChannels, 3);
  CHECK_FALSE(saveModels(bad, path).ok());

  std::ifstream again(path);
  std::stringstream after;
  after << again.rdbuf();
  CHECK(after.str() == before.str());
  CHECK(dir.entries().size() == 1);
  // A directory that does not exist: an error naming the path, nothing written.
  const std::string nowhere = dir.file("no/such/dir/m.json");
  s = saveModels(sampleModels(), nowhere);
  REQUIRE_FALSE(s.ok());
  CHECK_THAT(s.error().message, Catch::StartsWith(nowhere));
  CHECK(dir.entries().size() == 1);
}

TEST_CASE("Models file: values outside their physical ranges are refused, named (issue 16)",
          "[signal]") {
  const std::string radial = "models.json: radial.whiskers[2]";
  // sigma 0 would make every reading but the line's own impossible.
  CHECK_THAT(errorFor([](Json& d) { d["radial"]["whiskers"][2]["sigma"] = 0.0; }),
             Catch::Contains(radial + ".sigma: expected a residual in (0, "));
  CHECK_THAT(errorFor([](Json& d) { d["radial"]["whiskers"][2]["sigma"] = 5.0; }),
             Catch::Contains(radial + ".sigma"));
  // A slope of 1e308 m/rad predicts distances nowhere near the 14 cm whisker.
  CHECK_THAT(errorFor([](Json& d) { d["radial"]["whiskers"][2]["a1"] = 1e308; }),
             Catch::Contains(radial + ": a1, a0: the line predicts r = "));
  CHECK_THAT(errorFor([](Json& d) { d["radial"]["whiskers"][2]["r_max"] = 3.0; }),
             Catch::Contains(radial + ": r_min, r_max"));
  CHECK_THAT(errorFor([](Json& d) { d["radial"]["whiskers"][2]["f1_min"] = -4.0; }),  // not a Hall angle
             Catch::Contains(radial + ": f1_min, f1_max"));
  // The window: 0 samples, or 10^8 (14 hours at 2 kHz).
  CHECK_THAT(errorFor([](Json& d) { d["pipeline"]["window"]["samples"] = 0; }),
             Catch::Contains("pipeline.window.samples"));
  CHECK_THAT(errorFor([](Json& d) { d["pipeline"]["window"]["samples"] = 100000000; }),
             Catch::Contains("pipeline.window.samples"));
}

TEST_CASE("Models file: templates of another window than the pipeline's are refused (issue 16)",
          "[signal]") {
  // Found by metadata_fuzz: such a file loaded, and only making the session failed.
  CHECK_THAT(errorFor([](Json& d) { d["pipeline"]["window"]["samples"] = 280; }),
             Catch::Contains("models.json: orientation: templates of decimation 20 and 7 columns, "
                             "but pipeline.window records decimation 20 and 14 columns"));
}
