// `crunchhost export` in the library (issue 17; docs/EXPORT.md): CrunchBot's outputs in the
// formats other robotics tools read.
//   --format ros-map  map.json -> map.pgm + map.yaml for map_server / nav2_map_server
//                     (render/ros_map.h);
//   --format csv      a recording (.crec) -> one CSV per stream: decoded samples, contact reports,
//                     odometry (session/recording_csv.h).
// One road in: every setting is checked here (ExportOptions::validate), whichever front end set
// it; crunchhost only parses and hands them over.
//
// Thread-safety: none needed (values in, files out).
#pragma once

#include <string>

#include "crunch/core/result.h"
#include "crunch/render/ros_map.h"

namespace crunch::session {

enum class ExportFormat { kRosMap, kCsv };

// "ros-map" | "csv"; an Error names --format and the choices.
Result<ExportFormat> exportFormatByName(const std::string& name);

struct ExportOptions {
  std::string format;   // --format
  std::string in;       // --in: map.json (ros-map) or a recording (csv)
  std::string out_dir;  // --out: created if missing
  RosMapOptions ros;    // --resolution, --tops-occupied (ros-map only)
  // Whether --resolution / --tops-occupied were given: with --format csv they mean nothing and
  // are refused rather than ignored.
  bool resolution_given = false;
  bool tops_given = false;

  // okStatus(), or an Error naming the first bad flag: --format, --in (empty), --out (empty),
  // --resolution (RosMapOptions::validate), a ros-map flag with --format csv.
  Status validate() const;
};

struct ExportReport {
  // One line for the user: what was written, cell or row counts, and what the input lacked
  // (a map without free space, a damaged recording).
  std::string summary;
  // crunchhost's exit status (ARCHITECTURE.md §4): 0 written; 1 an output could not be written
  // after every check passed (a full disk; nothing left half-written); 2 bad input or setting;
  // 3 a damaged recording (csv), exported up to the damage.
  int exit_status = 0;
};

// Validates `options`, then writes the chosen format's files into options.out_dir. On an error
// (exit_status 1 or 2) `summary` is the message naming the flag or the file, and nothing is
// written.
ExportReport runExport(const ExportOptions& options);

}  // namespace crunch::session
