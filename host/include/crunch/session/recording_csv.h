// A recording (io/recording.h, docs/RECORDING.md) as CSV files any plotting tool reads
// (`crunchhost export --format csv`, issue 17): the recording is replayed through the same
// RobotSession as `--replay` (replay.h), and three of its streams are written, one file each.
// The columns (docs/RECORDING.md, "CSV export", is their definition):
//
//   samples.csv   one decoded bridge frame per row (io/bridge_stream.h), in arrival order:
//                 t_s, t_ns, board, seq, tick, alpha, beta, status, frames_lost, samples_dropped
//   contacts.csv  one contact report per row, as the mapper received it at the end of its whisk:
//                 t_s, t_ns, whisk, whisker, r_m, phi_rad, oriented, face_span_m, robot_x_m,
//                 robot_y_m, robot_theta_rad, contact_x_m, contact_y_m
//   odometry.csv  the robot's pose in the map frame after each chunk of Create bytes:
//                 t_s, t_ns, x_m, y_m, theta_rad, bumped, packets
//
// t_ns is the recording's CLOCK_MONOTONIC arrival time of the chunk (or mark) the row came from;
// t_s is the same in seconds from the earliest record's t_ns, for plotting (the file's order is
// the processing order, so the earliest is not always the first). Contacts of the last whisk,
// which a recording cut short never closed, come from the session's finish() with the time of the
// last record. Numbers are written with enough digits to read back the same double.
//
// Thread-safety: none needed. Writing: the three files are one OutputSet (core/atomic_file.h),
// written in pieces of 1 MiB and renamed into place together only when the whole recording is
// read: an error or a signal before that leaves no output.
#pragma once

#include <cstdint>
#include <string>

#include "crunch/core/result.h"

namespace crunch::session {

struct RecordingCsvSummary {
  std::uint64_t records = 0;   // records read
  std::uint64_t samples = 0;   // rows of samples.csv
  std::uint64_t contacts = 0;  // rows of contacts.csv
  std::uint64_t odometry = 0;  // rows of odometry.csv
  std::string damage;          // empty: the recording ended cleanly (else RecordingReader::damage)
};

// Replays `recording` and writes DIR/samples.csv, DIR/contacts.csv, DIR/odometry.csv (DIR
// created if missing). A damaged recording is exported up to the damage (summary.damage says
// where); a file that is no recording, bad metadata or a DIR that cannot take the files
// ("--out ...") is an Error naming it, and nothing is written. `output_failed`, if given, is set
// true when the Error is a failure to write the outputs after every check passed (a full disk:
// the contract's exit 1), false otherwise (exit 2).
Result<RecordingCsvSummary> exportRecordingCsv(const std::string& recording,
                                               const std::string& out_dir,
                                               bool* output_failed = nullptr);

}  // namespace crunch::session
