// `crunchhost --replay` in the library: a recording of a robot run (io/recording.h) re-run
// offline through the same RobotSession, in the order the control loop handled the chunks, which
// gives the same map (robot_session.h). The recording's metadata holds the run's settings and
// models (session_settings.h), so the file is all a replay needs.
//
// A damaged recording (cut short, a bad CRC) replays up to the damage: not an Error, but said in
// Replay::damage, with the map of what was replayed.
//
// Thread-safety: none needed (everything is the caller's). Allocation: the session and the map.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "crunch/core/result.h"
#include "crunch/session/robot_session.h"

namespace crunch::session {

struct Replay {
  RobotSessionOptions options;            // as the metadata gave them
  std::unique_ptr<RobotSession> session;  // after the last record and finish()
  Map map;                                // RobotSession::finish()
  std::uint64_t records = 0;              // records replayed
  std::string damage;                     // empty: the file ended cleanly
  // False for a version-1 recording: its metadata (the settings) has no CRC of its own.
  bool metadata_protected = true;
};

// `threads`: MappingOptions::threads of the replay (the metadata does not hold it: it is the
// replaying machine's and never changes the map); validated with the session's options.
// Errors (nothing replayed): the file cannot be opened or is not a recording (its header),
// its metadata (sessionFromMetadata: the field named), a session that cannot be made from it
// (e.g. "mapping: threads: ...").
Result<Replay> replayRecording(const std::string& path, int threads = 0);

}  // namespace crunch::session
