// libFuzzer target for the signal models file (crunch/signal/models_io.h, docs/TRAINING.md):
// parseModelsJson over arbitrary bytes. Checks, beyond "no crash, no sanitizer report":
//   - a refused file's error names the file;
//   - an accepted file passes validateModels (the physical ranges: sigma in (0, L], f1 a Hall
//     angle, the line within a whisker length of the whisker, window sizes bounded) and makes a
//     SignalPipeline, as a run would;
//   - it writes back (modelsToJson) to text that reads again to the same text.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "crunch/signal/models_io.h"
#include "crunch/signal/pipeline.h"
#include "fuzz_check.h"

using fuzz::check;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const auto models = crunch::signal::parseModelsJson(text, "fuzz.json");
  if (!models.ok()) {
    check(models.error().message.rfind("fuzz.json", 0) == 0);
    return 0;
  }
  const crunch::signal::SignalModels& m = models.value();
  check(crunch::signal::validateModels(m).ok());
  for (const auto& line : m.radial.whiskers) {
    check(line.sigma > 0.0 && line.sigma <= m.radial.options.external_length);
  }
  check(crunch::signal::SignalPipeline::create(m.pipeline).ok());
  const std::string once = crunch::signal::modelsToJson(m);
  const auto again = crunch::signal::parseModelsJson(once, "again.json");
  check(again.ok() && crunch::signal::modelsToJson(again.value()) == once);
  return 0;
}
