#include "crunch/session/replay.h"

#include <utility>

#include "crunch/io/recording.h"
#include "crunch/session/session_settings.h"

namespace crunch::session {

Result<Replay> replayRecording(const std::string& path, int threads) {
  auto reader = io::RecordingReader::open(path);
  if (!reader) return reader.error();
  io::RecordingReader& rec = *reader.value();
  auto options = sessionFromMetadata(rec.metadata(), "recording " + path);
  if (!options) return options.error();
  options.value().mapping.threads = threads;
  auto created = RobotSession::create(options.value());
  if (!created) return created.error();
  Replay r;
  r.options = std::move(options).value();
  r.session = std::move(created).value();
  r.metadata_protected = rec.metadataProtected();
  io::Chunk chunk;
  io::RecordingReader::Next next;
  while ((next = rec.next(chunk)) == io::RecordingReader::Next::kRecord) {
    (void)r.session->handle(chunk);  // no recorder: cannot fail
  }
  if (next == io::RecordingReader::Next::kDamaged) r.damage = rec.damage();
  r.records = rec.records();
  r.map = r.session->finish();
  return r;
}

}  // namespace crunch::session
