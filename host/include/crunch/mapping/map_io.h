// The map file (OUT/map.json, ARCHITECTURE.md §4). Writers use core/atomic_file.h, so an output
// file is either the old one or the complete new one.
#pragma once

#include <string>

#include "crunch/core/atomic_file.h"  // writeFileAtomic
#include "crunch/core/result.h"
#include "crunch/mapping/map.h"

namespace crunch {

inline constexpr const char* kMapSchema = "crunch.map/1";

// The map.json text of `map`: schema, fused tables (with the extra key "support"), walls,
// per-pose MAPs and stats, pretty-printed with a 2-space indent. Table thetas (fused and
// per-pose) are normalised into [0, pi); robot pose headings are written as they are.
// map.shapelets is not written: it is for pictures only and can be large. A non-finite number
// (a bug upstream) is written as null, which parseMapJson rejects.
std::string mapToJson(const Map& map);

// Reads map.json text back. `source` names the file in errors, which read
// "<source>: <field path>: <what is wrong>". "schema" must be kMapSchema; the sections tables,
// walls, per_pose and stats may be absent (empty); a table needs x, y, theta, a wall its four
// coordinates, a per-pose entry its pose. Other fields default as in map.h. Unknown keys are
// ignored (the contract allows extra keys). The result has no shapelets.
Result<Map> parseMapJson(const std::string& text, const std::string& source);

}  // namespace crunch
