// The one-table scene of the session tests: a 3 x 3 m arena with the standard table at its
// centre, so a robot at (0.85, 1.275) facing +x whisks at the table's near-left leg (as
// test/scenes/physics_one_table.json).
#pragma once

#include "crunch/scene/scene.h"

inline crunch::Scene oneTableScene() {
  crunch::Scene s;
  s.width = 3.0;
  s.depth = 3.0;
  crunch::TableSpec t;
  t.pose = {1.5, 1.5, 0.0};
  s.tables.push_back(t);
  return s;
}
