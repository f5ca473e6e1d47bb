// libFuzzer target for the two JSON readers (scene files, map files). Properties checked beyond
// "no crash, no sanitizer report": an accepted map re-serialises and re-reads to the same JSON;
// an accepted scene has only finite numbers and tables inside its arena.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "crunch/mapping/map_io.h"
#include "crunch/scene/scene.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);

  const auto scene = crunch::parseScene(text, "fuzz.json");
  if (scene.ok()) {
    const crunch::Scene& s = scene.value();
    if (!(s.width > 0 && s.depth > 0 && std::isfinite(s.width) && std::isfinite(s.depth)))
      std::abort();
    for (const auto& t : s.tables)
      for (const auto& c : t.top().corners())
        if (c.x() < -1e-6 || c.y() < -1e-6 || c.x() > s.width + 1e-6 || c.y() > s.depth + 1e-6)
          std::abort();
  } else if (scene.error().message.rfind("fuzz.json: ", 0) != 0) {
    std::abort();  // every error names the file
  }

  const auto map = crunch::parseMapJson(text, "fuzz.json");
  if (map.ok()) {
    const std::string once = crunch::mapToJson(map.value());
    const auto again = crunch::parseMapJson(once, "again.json");
    if (!again.ok() || crunch::mapToJson(again.value()) != once) std::abort();
  }
  return 0;
}
