#include "crunch/session/export.h"

#include "crunch/session/recording_csv.h"

namespace crunch::session {

Result<ExportFormat> exportFormatByName(const std::string& name) {
  if (name == "ros-map") return ExportFormat::kRosMap;
  if (name == "csv") return ExportFormat::kCsv;
  std::string why = "--format: unknown format \"";
  why.append(name).append("\" (choose ros-map or csv)");
  return Error{why};
}

Status ExportOptions::validate() const {
  const auto f = exportFormatByName(format);
  if (!f) return f.error();
  if (in.empty()) return Error{"--in: required (the input file)"};
  if (out_dir.empty()) return Error{"--out: required (the output directory)"};
  if (f.value() == ExportFormat::kRosMap) return ros.validate();
  if (resolution_given) return Error{"--resolution: only with --format ros-map"};
  if (tops_given) return Error{"--tops-occupied: only with --format ros-map"};
  return okStatus();
}

ExportReport runExport(const ExportOptions& options) {
  if (auto st = options.validate(); !st) return ExportReport{st.error().message, 2};
  bool output_failed = false;
  if (exportFormatByName(options.format).value() == ExportFormat::kRosMap) {
    auto r = exportRosMap(options.in, options.out_dir, options.ros, &output_failed);
    if (!r) return ExportReport{r.error().message, output_failed ? 1 : 2};
    const RosMapSummary& s = r.value();
    std::string msg = "wrote ";
    msg.append(s.pgm_path).append(" and ").append(s.yaml_path).append(": ");
    msg.append(std::to_string(s.width)).append(" x ").append(std::to_string(s.height));
    msg.append(" cells, ").append(std::to_string(s.occupied)).append(" occupied, ");
    msg.append(std::to_string(s.free)).append(" free, ").append(std::to_string(s.unknown));
    msg.append(" unknown");
    if (!s.had_free_space) {
      msg.append(" (the map file has no free_space, made before issue 17: no cell is free; "
                 "re-run or --replay to get it)");
    }
    return ExportReport{msg, 0};
  }
  auto r = exportRecordingCsv(options.in, options.out_dir, &output_failed);
  if (!r) return ExportReport{r.error().message, output_failed ? 1 : 2};
  const RecordingCsvSummary& s = r.value();
  std::string msg = "wrote ";
  msg.append(options.out_dir).append("/{samples,contacts,odometry}.csv: ");
  msg.append(std::to_string(s.samples)).append(" samples, ");
  msg.append(std::to_string(s.contacts)).append(" contact reports, ");
  msg.append(std::to_string(s.odometry)).append(" odometry rows");
  if (!s.damage.empty()) msg.append("; the recording is damaged, exported up to it: ").append(s.damage);
  return ExportReport{msg, s.damage.empty() ? 0 : 3};
}

}  // namespace crunch::session
