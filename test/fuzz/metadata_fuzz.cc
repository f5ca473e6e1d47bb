// libFuzzer target for a recording's metadata (crunch/session/session_settings.h,
// docs/RECORDING.md): sessionFromMetadata over arbitrary bytes, the road by which a replay's
// settings arrive (issue 16: a working_memory of 0 there once crashed the sampler). Checks,
// beyond "no crash, no sanitizer report":
//   - a refused metadata's error names its source;
//   - accepted options pass RobotSessionOptions::validate() and make a RobotSession (what
//     --replay does next), with working memory, schedule and chains inside their ranges;
//   - they write back (recordingMetadata) to metadata that reads again to the same options'
//     metadata text.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "crunch/session/robot_session.h"
#include "crunch/session/session_settings.h"
#include "fuzz_check.h"

using fuzz::check;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const std::string source = "recording fuzz.crec";
  const auto options = crunch::session::sessionFromMetadata(text, source);
  if (!options.ok()) {
    check(options.error().message.rfind(source, 0) == 0);
    return 0;
  }
  const crunch::session::RobotSessionOptions& o = options.value();
  check(o.validate().ok());
  check(o.mapping.working_memory >= 1 && o.mapping.sampler.schedule_steps >= 1 &&
        o.mapping.global_chains >= 1);
  check(crunch::session::RobotSession::create(o).ok());
  const crunch::session::RecordingProvenance from{"1209:0001", "/dev/ttyUSB0", "m.json"};
  const std::string once = crunch::session::recordingMetadata(o, from);
  const auto again = crunch::session::sessionFromMetadata(once, "again");
  check(again.ok() && crunch::session::recordingMetadata(again.value(), from) == once);
  return 0;
}
