// The map file (OUT/map.json, ARCHITECTURE.md §4). Writers use core/atomic_file.h, so an output
// file is either the old one or the complete new one.
#pragma once

#include <string>

#include "crunch/core/atomic_file.h"  // writeFileAtomic
#include "crunch/core/result.h"
#include "crunch/mapping/map.h"

namespace crunch {

// /2 (issue 13): a fused table's `score` is its posterior probability (the fraction of the
// global chains, or of the samples, holding it: ChainFusion in mapping_options.h), where /1 wrote
// the fraction of per-pose MAPs that held it. Nothing else changed; /1 files are still read.
inline constexpr const char* kMapSchema = "crunch.map/2";
inline constexpr const char* kMapSchemaV1 = "crunch.map/1";

// The map.json text of `map`: schema, fused tables (with the extra key "support"), walls,
// per-pose MAPs and stats, pretty-printed with a 2-space indent. Table thetas (fused and
// per-pose) are normalised into [0, pi); robot pose headings are written as they are.
// map.shapelets is not written: it is for pictures only and can be large. map.free_space, when
// not empty, is the extra key "free_space" (the contract allows extra keys; issue 17):
//   {"cell": 0.01, "origin": [x, y], "size": [nx, ny], "rows": ["3+10 40+2", ...]}
// rows[iy] lists the swept cells of row iy (from origin.y upward) as runs "start+length" of
// cells from origin.x, in increasing order; "" is a row with none. A non-finite number
// (a bug upstream) is written as null, which parseMapJson rejects.
std::string mapToJson(const Map& map);

// Reads map.json text back. `source` names the file in errors, which read
// "<source>: <field path>: <what is wrong>". "schema" must be kMapSchema or kMapSchemaV1; the
// sections tables, walls, per_pose and stats may be absent (empty); a table needs x, y, theta, a
// wall its four coordinates, a per-pose entry its pose. Other fields default as in map.h. Unknown
// keys are ignored (the contract allows extra keys). "free_space" is optional (files before
// issue 17 have none: the result's free_space is empty); when present it is checked whole (a run
// outside its row, overlapping runs, rows not matching size: an error naming
// free_space.rows[i]). The result has no shapelets.
Result<Map> parseMapJson(const std::string& text, const std::string& source);

}  // namespace crunch
