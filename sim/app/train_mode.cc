#include "train_mode.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <ostream>

#include "crunch/core/atomic_file.h"
#include "crunch_sim/training_report.h"
#include "progress.h"

namespace crunch::app {

namespace {

namespace fs = std::filesystem;
constexpr double kDeg = 180.0 / kPi;

// A directory we can create files in: created if missing, then probed with a file that is
// removed again. The Error names the directory.
Status checkWritableDir(const std::string& dir) {
  if (auto s = ensureDirectory(dir); !s) return s;
  const fs::path probe = fs::path(dir) / (".crunch-train-probe-" + std::to_string(::getpid()));
  std::error_code ec;
  {
    std::ofstream f(probe);
    if (!f || !(f << "probe") || !f.flush()) {
      fs::remove(probe, ec);
      return Error{dir + ": cannot write files there"};
    }
  }
  fs::remove(probe, ec);
  return okStatus();
}

Status checkModelsOut(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) return Error{path + ": --models-out names a directory"};
  const fs::path parent = fs::path(path).parent_path();
  const std::string pdir = parent.empty() ? "." : parent.string();
  if (!fs::is_directory(pdir, ec)) {
    return Error{"--models-out " + path + ": the directory " + pdir + " does not exist"};
  }
  if (auto s = checkWritableDir(pdir); !s) {
    return Error{"--models-out " + path + ": " + s.error().message};
  }
  return okStatus();
}

// Options and outputs, before anything is collected.
Status checkOptions(const TrainOptions& opt, const sim::TrainingOptions& proto) {
  if (auto s = sim::f1SourceByName(opt.radial_f1); !s) return s.error();
  if (auto s = proto.validate(); !s) return s;
  if (opt.out_dir.empty()) return Error{"--out: the directory name is empty"};
  if (auto s = checkWritableDir(opt.out_dir); !s) return Error{"--out: " + s.error().message};
  if (!opt.models_out.empty()) return checkModelsOut(opt.models_out);
  return okStatus();
}

// Each file complete or not at all, stopping at the first failure.
Status writeOutputs(const TrainOptions& opt, const sim::TrainingOptions& proto,
                    const sim::TrainingData& data, const sim::TrainingFit& fit, double wall_s) {
  if (Status s = sim::writeTrainingFigures(opt.out_dir, data, fit); !s) return s;
  const std::string dir = opt.out_dir + "/";
  if (Status s = writeFileAtomic(dir + "training_report.json",
                                 sim::trainingReportJson(proto, data, fit, wall_s));
      !s)
    return s;
  if (Status s = signal::saveModels(fit.models, dir + "models.json"); !s) return s;
  if (!opt.models_out.empty()) return signal::saveModels(fit.models, opt.models_out);
  return okStatus();
}

void printDone(const TrainOptions& opt, const sim::TrainingOptions& proto,
               const sim::TrainingData& data, const sim::TrainingFit& fit, double wall_s,
               std::ostream& out) {
  const sim::RadialEvaluation& sv = fit.variants[fit.saved];
  const signal::CrossValidation& cv = fit.cv;
  if (opt.json_progress) {
    out << "{\"event\":\"done\",\"radial_sigma_all_mm\":" << sv.heldout_rms_all * 1e3
        << ",\"orientation_mean_deg\":" << cv.mean_error * kDeg
        << ",\"orientation_sd_deg\":" << cv.sd_error * kDeg << ",\"wall_s\":" << wall_s
        << ",\"out\":\"" << opt.out_dir << "\"}\n";
    return;
  }
  char line[400];
  out << "radial distance, held-out sigma (mm), f1 = " << opt.radial_f1
      << " (paper 2.78 1.82 4.37 5.68, combo 4.98):";
  for (int w = 0; w < 4; ++w) {
    std::snprintf(line, sizeof line, " %.2f", sv.heldout_rms[static_cast<size_t>(w)] * 1e3);
    out << line;
  }
  std::snprintf(line, sizeof line, ", all %.2f\n", sv.heldout_rms_all * 1e3);
  out << line;
  std::snprintf(line, sizeof line,
                "orientation, leave one repeat out: mean %.1f deg, sd %.1f deg, %.0f%% right "
                "(paper -2.2, 21.2)\n",
                cv.mean_error * kDeg, cv.sd_error * kDeg, cv.accuracy * 100.0);
  out << line;
  if (fit.has_ramp) {
    const sim::RampEvaluation& r = fit.ramp;
    std::snprintf(line, sizeof line,
                  "ramp calibration: gain %.4f, compliance_scale %.4f (%d contacts, %d outliers); "
                  "held-out r error rms %.2f mm (mean %+.2f), nominal %.2f mm (mean %+.2f); "
                  "eq. 2 on the same contacts %.1f mm\n",
                  r.calibration.gain, r.calibration.compliance_scale, r.fit.used, r.fit.outliers,
                  r.fitted.rms_all * 1e3, r.fitted.mean_all * 1e3, r.nominal.rms_all * 1e3,
                  r.nominal.mean_all * 1e3, r.eq2.rms_all * 1e3);
    out << line;
  }
  if (fit.faces.located > 0) {
    std::snprintf(line, sizeof line,
                  "orientation from two whiskers' ramps: %d of %zu wall whisks, mean %.2f deg, "
                  "sd %.2f deg\n",
                  fit.faces.located, fit.faces.trials.size(), fit.faces.mean_error * kDeg,
                  fit.faces.sd_error * kDeg);
    out << line;
  }
  out << "collected " << proto.plannedWhisks() << " whisks (" << std::lround(data.simulated_s)
      << " s simulated) in " << formatDuration(wall_s) << "; wrote " << opt.out_dir << "/"
      << "{models.json,training_report.json,fig9_peak_deflection,table1_radial_sigma,"
         "fig10_orientation_error" << (fit.has_ramp ? ",ramp_distance,table1_ramp_sigma" : "") << "}"
      << (opt.models_out.empty() ? "" : " and " + opt.models_out) << "\n";
}

}  // namespace

int runTrain(const TrainOptions& opt, std::ostream& out, std::ostream& err) {
  sim::TrainingOptions proto = opt.protocol;
  proto.seed = opt.seed;
  if (Status s = checkOptions(opt, proto); !s) {
    err << "crunchhost train: " << s.error().message << "\n";
    return 2;
  }
  WhiskProgress progress(opt.json_progress ? out : err, opt.json_progress);
  proto.progress = [&progress](const sim::TrainingProgress& p) { progress(p); };
  auto collected = sim::collectTrainingData(proto);
  if (!collected) {
    err << "crunchhost train: " << collected.error().message << "\n";
    return 1;
  }
  const sim::TrainingData& data = collected.value();
  auto fit = sim::fitTrainingModels(data, proto, sim::f1SourceByName(opt.radial_f1).value());
  if (!fit) {
    err << "crunchhost train: " << fit.error().message << "\n";
    return 1;
  }
  const double wall_s = progress.elapsed();
  if (Status s = writeOutputs(opt, proto, data, fit.value(), wall_s); !s) {
    err << "crunchhost train: " << s.error().message << "\n";
    return 1;
  }
  printDone(opt, proto, data, fit.value(), wall_s, out);
  return 0;
}

}  // namespace crunch::app
