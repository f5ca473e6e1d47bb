// The settings of a robot session and their round trip through a recording's metadata (the JSON
// header of io/recording.h; docs/RECORDING.md): `crunchhost --robot` writes them, `crunchhost
// --replay` reads them back, so a replay needs nothing but the file to give the same map.
//
// Metadata (schema kRecordingSchema; the format of every recording so far, read and written
// byte for byte as before the session moved into the library):
//
//   {"schema": "crunch.recording/1", "crunchhost": "0.1.0", "usb": "1209:0001",
//    "create": "/dev/ttyUSB0", "models_path": "...", "models": {signal models file, models_io.h},
//    "settings": {"seed": n, "start": [x, y, theta], "area": [lo.x, lo.y, hi.x, hi.y],
//                 "checksum_includes_header": bool, "onset_threshold": rad,
//                 "mapping": {"working_memory": n, "schedule_steps": n, "sweeps": n,
//                             "smart_proposals": bool, "smart_gain": x, "min_support": n,
//                             "global_sweeps": n, "global_chains": n,
//                             "sigma_r_shapelet": m, "sigma_theta_shapelet": rad}}}
//
// "crunchhost", "usb", "create" and "models_path" say where the run came from and are not read
// back. Everything else is what the session's result depends on; the rest of RobotSessionOptions
// follows from the models (sessionOptions()). MappingOptions::threads is not written: it never
// changes the map, and a replay runs on its own machine's cores (replay.h takes it).
//
// Reading is strict (ARCHITECTURE.md §3 "One road in"): every settings field required, unknown
// settings refused (a setting this reader does not know could change the map), numbers finite
// and of their type (integers in range), and then RobotSessionOptions::validate() — the same
// check a live run's options pass. Every failure is an Error "<source>: metadata: <field>: <what
// is wrong>" naming the field, never a crash.
//
// Pure functions: thread-safe, allocate their results.
#pragma once

#include <cstdint>
#include <string>

#include "crunch/core/result.h"
#include "crunch/mapping/mapping_options.h"
#include "crunch/session/robot_session.h"
#include "crunch/signal/models_io.h"

namespace crunch::session {

inline constexpr char kRecordingSchema[] = "crunch.recording/1";

// The session's options for `models`: the pipeline they were trained with (carried in the models
// file; docs/TRAINING.md), the default whisker array, `mapping` with `seed`, no progress
// callback, and eq. 12's shapelet sigmas set to the classifiers' measured errors (paper Table 1
// all whiskers, Fig. 10), as `--sim --sensor-model physics` does. Start and area keep
// RobotSessionOptions' defaults.
RobotSessionOptions sessionOptions(const signal::SignalModels& models,
                                   const MappingOptions& mapping, std::uint64_t seed);

// Where a recorded run came from: written into the metadata, not read back.
struct RecordingProvenance {
  std::string usb;          // the bridge's VID:PID
  std::string create;       // the Create's serial port
  std::string models_path;  // the models file the run loaded
  std::string program_version = "0.1.0";
};

// The metadata JSON text of a recording of a session run with `options` (its seed is
// options.mapping.seed).
std::string recordingMetadata(const RobotSessionOptions& options,
                              const RecordingProvenance& provenance);

// The session options a recording's metadata describes; `source` names it in errors (e.g.
// "recording out/recording.crec"). Errors: not JSON, another schema, a models error
// (models_io.h), a settings field missing, of the wrong type, unknown or out of range (see top).
Result<RobotSessionOptions> sessionFromMetadata(const std::string& metadata_json,
                                                const std::string& source);

}  // namespace crunch::session
