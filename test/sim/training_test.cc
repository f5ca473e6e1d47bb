// Training protocols (docs/TRAINING.md): the placements' geometry, a reduced protocol through
// the whole physics path (WhiskerRig), determinism by seed, the detector threshold the models
// are trained with, and `crunchhost train` refusing bad options and outputs before it runs.
#include "crunch_sim/training.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "crunch/core/geometry.h"
#include "crunch/robot/shapelet.h"
#include "train_mode.h"

using crunch::kPi;
using crunch::Pose2;
using crunch::Vec2;
using crunch::WhiskerMount;
namespace sim = crunch::sim;
namespace fs = std::filesystem;

namespace {

constexpr double kDeg = kPi / 180.0;

// A small protocol: whisker 3 (index 2) at two distances, twice; two wall angles, twice.
sim::TrainingOptions reducedProtocol(std::uint64_t seed) {
  sim::TrainingOptions o;
  o.seed = seed;
  o.radial_whiskers = {2};
  o.radial_distances = {0.09, 0.115};
  o.radial_repeats = 2;
  o.radial_heldout = false;
  o.angles = {40 * kDeg, 110 * kDeg};
  o.orientation_repeats = 2;
  o.ramp_whiskers = {};  // the ramp protocol has its own tests below
  return o;
}

// One radial contact and one wall contact.
sim::TrainingOptions tinyProtocol(std::uint64_t seed) {
  sim::TrainingOptions o = reducedProtocol(seed);
  o.radial_distances = {0.1};
  o.radial_repeats = 1;
  o.angles = {70 * kDeg};
  o.orientation_repeats = 1;
  return o;
}

const sim::TrainingData& reducedData() {
  static const sim::TrainingData data = [] {
    auto d = sim::collectTrainingData(reducedProtocol(3));
    REQUIRE(d.ok());
    return d.value();
  }();
  return data;
}

fs::path freshDir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("crunch_training_test_" + name);
  fs::remove_all(d);
  return d;
}

}  // namespace

TEST_CASE("Training: the pole placement puts the face at (d, eps) from the whisker's base",
          "[training]") {
  const std::vector<WhiskerMount> mounts = crunch::defaultWhiskerArray();
  const Vec2 face(1.5, 1.49);
  for (int w = 0; w < 4; ++w) {
    const double d = 0.1, eps = 0.05;
    const Pose2 p = sim::placeForPole(mounts, w, d, eps, face, 0.3);
    const Vec2 base = p.toWorld(mounts[w].base);
    const Vec2 to_face = face - base;
    CHECK(to_face.norm() == Approx(d).margin(1e-12));
    // The rest direction of the whisker is along the pole's axis, and the face is eps CCW of it.
    CHECK(crunch::wrapPeriod(p.theta + mounts[w].bearing - 0.3, 2 * kPi) ==
          Approx(0.0).margin(1e-12));
    CHECK(std::atan2(to_face.y(), to_face.x()) - 0.3 == Approx(eps).margin(1e-12));
  }
}

TEST_CASE("Training: the wall placement sets the angle and the deepest whisker's reach",
          "[training]") {
  const std::vector<WhiskerMount> mounts = crunch::defaultWhiskerArray();
  const Vec2 face_point(1.5, 1.49), toward(0.0, -1.0);
  for (const double deg : {20.0, 90.0, 100.0, 160.0}) {
    const double depth = 0.004;
    const Pose2 p = sim::placeWall(mounts, deg * kDeg, depth, 0.05, face_point, 0.0, toward);
    // The wall (along +x) relative to the heading, modulo pi.
    CHECK(crunch::wrapPeriod(0.0 - p.theta - deg * kDeg, kPi) == Approx(0.0).margin(1e-12));
    // The robot is below the wall, and its deepest straight whisker end passes the face by depth.
    double deepest = -1e9;
    for (const WhiskerMount& m : mounts) {
      const Vec2 base = p.toWorld(m.base);
      const double dir = p.theta + m.bearing;
      const Vec2 tip = base + m.length * Vec2(std::cos(dir), std::sin(dir));
      deepest = std::max({deepest, base.y(), tip.y()});
    }
    CHECK(p.y < face_point.y());
    CHECK(deepest - face_point.y() == Approx(depth).margin(1e-12));
    CHECK(p.x == Approx(1.55).margin(1e-12));
  }
}

TEST_CASE("Training: options are validated with the field named", "[training]") {
  sim::TrainingOptions o;
  CHECK(o.validate().ok());
  // radial: 4 whiskers x 6 distances x 5 repeats x 2 sets; ramp: 4 whiskers x 9 distances x
  // 2 objects x 2 directions x 2 sets; orientation: 15 angles x 4 repeats.
  CHECK(o.plannedWhisks() == 4 * 6 * 5 * 2 + 4 * 9 * 2 * 2 * 2 + 15 * 4);
  auto fails = [](sim::TrainingOptions bad, const std::string& field) {
    const crunch::Status s = bad.validate();
    REQUIRE_FALSE(s.ok());
    CHECK_THAT(s.error().message, Catch::Contains(field));
  };
  sim::TrainingOptions b = o;
  b.radial_whiskers = {4};
  fails(b, "radial_whiskers[0]");
  b = o;
  b.radial_distances = {0.1, 0.15};
  fails(b, "radial_distances[1]");
  b = o;
  b.eps_min = 0.0;
  fails(b, "eps_min");
  b = o;
  b.depth_max = 0.011;  // past half the 2 cm wall: the tip could be pushed out the back
  fails(b, "depth");
  b = o;
  b.angles = {0.0};
  fails(b, "angles[0]");
  b = o;
  b.radial_repeats = 0;
  b.orientation_repeats = 0;
  b.ramp_repeats = 0;
  fails(b, "no contacts");
  b = o;
  b.rig.pipeline.detector.min_onset_threshold = -1.0;
  fails(b, "rig");
  b = o;
  b.ramp_whiskers = {0, -1};
  fails(b, "ramp_whiskers[1]");
  b = o;
  b.ramp_distances = {0.005};  // nearer the follicle than 1 cm: no ramp band at the whisk's rate
  fails(b, "ramp_distances[0]");
  b = o;
  b.edge_max = 1.5;  // the second face would come round into the sweep
  fails(b, "edge_min/edge_max");
  b = o;
  b.ramp_repeats = -1;
  fails(b, "ramp_repeats");
}

TEST_CASE("Training: a reduced radial protocol gives f1 falling with distance and true labels",
          "[training]") {
  const sim::TrainingData& data = reducedData();
  REQUIRE(data.radial.size() == 4);
  CHECK(data.missing_frames == 0);
  std::vector<double> near_f1, far_f1;
  for (const sim::RadialContact& c : data.radial) {
    INFO("nominal " << c.nominal_d << " repeat " << c.repeat << " f1 " << c.f1 << " r " << c.r);
    CHECK(c.set == 0);
    CHECK(c.whisker == 2);
    CHECK(std::abs(c.d - c.nominal_d) <= 0.001);
    CHECK(c.eps >= 0.03);
    CHECK(c.eps <= 0.08);
    REQUIRE(c.detected);
    CHECK(c.truth_touched);
    // One pass, one episode at these distances (the pole's end is not reached).
    CHECK(c.episodes.size() == 1);
    CHECK(c.peak_episode == 0);
    CHECK(c.first_f1 == c.f1);
    // The contact slides outward as the whisker bends: the true r at the peak lies a few mm
    // beyond the face's centre, never nearer the base than its near end.
    CHECK(c.r >= c.d - 0.005);
    CHECK(c.r <= c.d + 0.015);
    // Only the whisker under test touched, and the free ones stayed under the threshold.
    CHECK(c.other_touched == 0);
    CHECK(c.episodes[0].touched_mask == (1u << 2));
    CHECK(c.max_free_theta < sim::kPhysicsOnsetThreshold);
    // A real contact is far above the threshold and inside the Hall model's 30 degree range.
    CHECK(c.f1 > 5 * sim::kPhysicsOnsetThreshold);
    CHECK(c.f1 < 30 * kDeg);
    (c.nominal_d < 0.1 ? near_f1 : far_f1).push_back(c.f1);
  }
  REQUIRE(near_f1.size() == 2);
  REQUIRE(far_f1.size() == 2);
  // Eq. 2's premise: the peak deflection falls with the distance to the contact.
  CHECK(std::min(near_f1[0], near_f1[1]) > std::max(far_f1[0], far_f1[1]) + 0.05);
}

TEST_CASE("Training: a reduced orientation protocol gives labelled 2 s windows from the start",
          "[training]") {
  const sim::TrainingData& data = reducedData();
  REQUIRE(data.orientation.size() == 4);
  std::set<std::pair<int, int>> labels;
  for (const sim::OrientationContact& c : data.orientation) {
    INFO("angle " << c.angle / kDeg << " repeat " << c.repeat);
    labels.insert({static_cast<int>(std::lround(c.angle / kDeg)), c.repeat});
    REQUIRE(c.episodes >= 1);
    REQUIRE(c.has_window);
    CHECK(c.window.decimation == 20);
    CHECK(c.window.data.rows() == 8);
    CHECK(c.window.data.cols() == 200);
    CHECK(c.window.data.allFinite());
    // Pressed against the wall: the window opens at the start of the whisk, so the heading at
    // the first onset (the mapper's reference) is the label's within a degree.
    CHECK(c.onset_s < 0.2);
    CHECK(std::abs(c.onset_offset) < 1.0 * kDeg);
    CHECK(c.touched_mask != 0);
    CHECK(c.window.data.cwiseAbs().maxCoeff() > sim::kPhysicsOnsetThreshold);
    CHECK(c.depth >= 0.002);
    CHECK(c.depth <= 0.008);
  }
  CHECK(labels == std::set<std::pair<int, int>>{{40, 0}, {40, 1}, {110, 0}, {110, 1}});
  const auto windows = sim::labelledWindows(data.orientation);
  REQUIRE(windows.size() == 4);
  for (std::size_t i = 0; i < windows.size(); ++i) {
    CHECK(windows[i].angle == data.orientation[i].angle);
    CHECK(windows[i].repeat == data.orientation[i].repeat);
  }
}

TEST_CASE("Training: the same seed gives the same data, another seed other data", "[training]") {
  auto a = sim::collectTrainingData(tinyProtocol(7));
  auto b = sim::collectTrainingData(tinyProtocol(7));
  auto c = sim::collectTrainingData(tinyProtocol(8));
  REQUIRE(a.ok());
  REQUIRE(b.ok());
  REQUIRE(c.ok());
  const sim::TrainingData& A = a.value();
  const sim::TrainingData& B = b.value();
  const sim::TrainingData& C = c.value();
  REQUIRE(A.radial.size() == 1);
  REQUIRE(B.radial.size() == 1);
  REQUIRE(C.radial.size() == 1);
  CHECK(A.radial[0].eps == B.radial[0].eps);
  CHECK(A.radial[0].f1 == B.radial[0].f1);
  CHECK(A.radial[0].r == B.radial[0].r);
  CHECK(A.simulated_s == B.simulated_s);
  REQUIRE(A.orientation.size() == 1);
  REQUIRE(B.orientation.size() == 1);
  CHECK(A.orientation[0].depth == B.orientation[0].depth);
  CHECK(A.orientation[0].window.data == B.orientation[0].window.data);
  CHECK(A.radial[0].eps != C.radial[0].eps);
  CHECK(A.radial[0].f1 != C.radial[0].f1);
  CHECK(A.orientation[0].depth != C.orientation[0].depth);
}

TEST_CASE("Training: at the detector's default threshold the free whiskers' lag reads as contact",
          "[training]") {
  // Why kPhysicsOnsetThreshold: with the default onset threshold (~3e-4 rad) the whiskers that
  // touch nothing are "touching" too, from their inertial lag when the whisk starts.
  sim::TrainingOptions o = tinyProtocol(5);
  o.angles.clear();
  o.rig.pipeline.detector.min_onset_threshold = 3e-4;
  auto d = sim::collectTrainingData(o);
  REQUIRE(d.ok());
  REQUIRE(d.value().radial.size() == 1);
  const sim::RadialContact& c = d.value().radial[0];
  CHECK(c.other_touched == 0);  // the simulator: only whisker 2 touched the pole
  CHECK(c.max_free_theta > 10 * 3e-4);
  CHECK(c.max_free_theta < sim::kPhysicsOnsetThreshold);
  std::uint32_t seen = 0;
  for (const sim::EpisodeRecord& e : c.episodes) seen |= e.touched_mask;
  CHECK((seen & ~(1u << 2)) != 0);  // the pipeline: others too
}

TEST_CASE("crunchhost train: bad options and unwritable outputs fail before collecting",
          "[training][app]") {
  const fs::path dir = freshDir("bad");
  fs::create_directories(dir);
  const fs::path file = dir / "a_file";
  std::ofstream(file) << "x";
  auto run = [](crunch::app::TrainOptions opt, std::string& err_text) {
    std::ostringstream out, err;
    const int code = crunch::app::runTrain(opt, out, err);
    err_text = err.str();
    return code;
  };
  std::string err;
  crunch::app::TrainOptions opt;
  opt.out_dir = (file / "out").string();  // under a regular file: cannot be created
  CHECK(run(opt, err) == 2);
  CHECK_THAT(err, Catch::Contains("--out") && Catch::Contains((file / "out").string()));
  CHECK_FALSE(fs::exists(file / "out"));

  opt.out_dir = (dir / "out").string();
  opt.models_out = (dir / "missing" / "models.json").string();
  CHECK(run(opt, err) == 2);
  CHECK_THAT(err, Catch::Contains("--models-out") && Catch::Contains("does not exist"));
  CHECK_FALSE(fs::exists(dir / "missing"));

  opt.models_out.clear();
  opt.radial_f1 = "median";
  CHECK(run(opt, err) == 2);
  CHECK_THAT(err, Catch::Contains("--radial-f1"));

  opt.radial_f1 = "max";
  opt.protocol.radial_repeats = -1;
  CHECK(run(opt, err) == 2);
  CHECK_THAT(err, Catch::Contains("radial_repeats"));
  // Nothing was written anywhere.
  CHECK_FALSE(fs::exists(dir / "out" / "models.json"));
  CHECK_FALSE(fs::exists(dir / "out" / "training_report.json"));
  fs::remove_all(dir);
}

TEST_CASE("crunchhost train: the executable exits non-zero on an unwritable --out",
          "[training][app]") {
  const fs::path dir = freshDir("exe");
  fs::create_directories(dir);
  const fs::path file = dir / "a_file";
  std::ofstream(file) << "x";
  const fs::path log = dir / "stderr.txt";
  const std::string cmd = std::string("\"") + CRUNCHHOST_PATH + "\" train --out \"" +
                          (file / "out").string() + "\" 2> \"" + log.string() + "\"";
  const int status = std::system(cmd.c_str());
  REQUIRE(status != -1);
  CHECK(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 2);
  std::ifstream in(log);
  std::stringstream text;
  text << in.rdbuf();
  CHECK_THAT(text.str(), Catch::Contains("cannot create directory"));
  CHECK_FALSE(fs::exists(file / "out"));
  fs::remove_all(dir);
}

TEST_CASE("Training: the edge placement puts the corner at (d, +-eps) with both faces beyond it",
          "[training]") {
  const std::vector<WhiskerMount> mounts = crunch::defaultWhiskerArray();
  const Vec2 corner(4.0, 4.0);
  const double face_dir = kPi;  // faces leave the corner along -x and -y
  for (int w = 0; w < 4; ++w) {
    for (const int dir : {+1, -1}) {
      const double d = 0.05, eps = 0.05, edge = 0.5;
      const Pose2 p = sim::placeForEdge(mounts, w, d, eps, dir, corner, face_dir, edge);
      const Vec2 base = p.toWorld(mounts[w].base);
      const Vec2 to_corner = corner - base;
      CHECK(to_corner.norm() == Approx(d).margin(1e-12));
      const double rest = p.theta + mounts[w].bearing;
      const double radial = std::atan2(to_corner.y(), to_corner.x());
      // The corner is eps off the rest line, on the side the whisk turns to first meet it.
      CHECK(std::remainder(radial - rest, 2 * kPi) == Approx(dir * eps).margin(1e-12));
      // Both faces (face_dir, face_dir + pi/2) turn further in the sweep's sense than the line
      // to the corner: the sweeping whisker meets the corner before either face.
      for (const double f : {face_dir, face_dir + kPi / 2}) {
        const double beyond = dir * std::remainder(f - radial, 2 * kPi);
        CHECK(beyond >= edge - 1e-12);
        CHECK(beyond <= edge + kPi / 2 + 1e-12);
      }
    }
  }
}

namespace {

// A few ramp contacts of whisker 1 from near the follicle to the tip, on the leg and the post,
// with a whisker whose Young's modulus is `modulus_factor` times the host's nominal one.
sim::TrainingOptions rampProtocol(std::uint64_t seed, double modulus_factor) {
  sim::TrainingOptions o;
  o.seed = seed;
  o.radial_whiskers = {};
  o.angles = {};
  o.ramp_whiskers = {1};
  o.ramp_distances = {0.03, 0.07, 0.11, 0.135};
  o.ramp_both_directions = false;
  o.ramp_heldout = false;
  o.rig.robot.beam.youngs_modulus *= modulus_factor;
  return o;
}

}  // namespace

TEST_CASE("Ramp calibration: the fit recovers a softer whisker and brings the r error back",
          "[training]") {
  // The simulated whisker's shaft is 1/0.6 as compliant as the host's nominal beam (a printed
  // batch with a lower modulus): its base turns less per radian of body turn, so read with the
  // nominal calibration the contacts away from the follicle read too far (measured: +5 mm mean,
  // 7.6 mm rms; the unperturbed whisker reads 2.5 mm rms, -2.4 mm mean, on the same placements).
  // Eight contacts, 30-135 mm, leg and post, ~6 s in Release.
  auto data = sim::collectTrainingData(rampProtocol(3, 0.6));
  REQUIRE(data.ok());
  const std::vector<crunch::RampSample> xs = sim::rampSamples(data.value().ramp, 0);
  REQUIRE(xs.size() == 8);  // every contact touched, was seen by both sides, and has a ramp
  crunch::RampFitOptions fo;
  fo.min_samples = 6;
  auto fit = crunch::fitRampCalibration(crunch::WhiskerBeam{}, xs, fo);
  REQUIRE(fit.ok());
  const crunch::RampFitSummary& f = fit.value();
  INFO("gain " << f.gain << ", compliance_scale " << f.compliance_scale << ", rms " << f.rms
               << " m (nominal " << f.rms_nominal << ", mean " << f.mean_nominal << ")");
  // The perturbation matters: the nominal calibration is millimetres off, and too far.
  CHECK(f.rms_nominal > 4e-3);
  CHECK(f.mean_nominal > 3e-3);
  // The fit finds a softer shaft (not a sensor gain: the near-follicle contacts pin the gain).
  // The unperturbed ODE whisker fits compliance_scale ~1.07 (its 4 rigid elements, within 4.4 %
  // of beam theory, docs/WHISKERS.md §3); 1/0.6 of that is ~1.8, and four distances let gain
  // and compliance trade ~15 % against each other, hence the band.
  CHECK(f.compliance_scale > 1.4);
  CHECK(f.compliance_scale < 2.6);
  CHECK(f.gain > 0.9);
  CHECK(f.gain < 1.3);
  // And the distances are back: millimetre-level, unbiased.
  CHECK(f.rms < 1.2e-3);
  CHECK(f.rms < 0.2 * f.rms_nominal);
  CHECK(std::abs(f.mean) < 0.5e-3);
  // The host reads the same with the fitted calibration (rampDistance = WhiskEvidence's reading).
  const crunch::signal::RampCalibration cal{f.gain, f.compliance_scale};
  for (const sim::RampContact& c : data.value().ramp) {
    CHECK(sim::rampDistance(c.contact, c.lever, cal) == Approx(c.contact.r_touch).margin(2.5e-3));
  }
}
