// What a live view shows of a run (`--serve`, docs/LIVE_VIEW.md): the map as the mapper
// currently estimates it (fused tables with their legs, walls), the robot's pose and the path it
// drove, the newest contacts (shapelets) and the run's counters. The run's thread fills a
// LiveState and hands it to LiveView::publish (live_view.h); liveStateJson is the document the
// server sends (GET /state.json, and each event of GET /events).
//
// The document, schema "crunch.live/1" (SI units, map frame, angles CCW from +x; extra keys may
// be added, never change meaning):
//   {"schema": "crunch.live/1", "seq": 12, "mode": "robot" | "sim", "stage": "roaming",
//    "t": 31.5, "done": false,
//    "area": {"x0": 0, "y0": 0, "x1": 6, "y1": 6},          the arena / mapped area's walls
//    "pose": [x, y, theta] | null,  "path": [[x, y], ...],
//    "tables": [{"x","y","theta","width","depth","leg","score"}],
//    "legs":   [[[x, y] x 4 corners], ...],                   four per table (TableSpec::legs())
//    "walls":  [{"x0","y0","x1","y1","score"}],
//    "contacts": [{"x","y","phi","oriented","whisker","whisk","from":[x, y]}],  newest last
//    "shapelets": 123,                                        every contact of the run
//    "counters": {"name": number, ...}}                       in the order given
// `seq` counts the snapshots the view has published (1 the first); `done` is true on the last
// one (the run ended: the page stops listening).
//
// Thread-safety: plain values; a LiveState belongs to the thread that fills it. Cost: moveTo()
// is O(1) (amortised); setMap() copies at most max_contacts shapelets and the map's objects.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "crunch/core/geometry.h"
#include "crunch/mapping/map.h"

namespace crunch::serve {

struct LiveContact {
  double x = 0.0, y = 0.0;
  double phi = 0.0;  // surface orientation, modulo pi
  bool oriented = true;
  int whisker = -1;
  int whisk = -1;  // the pose (whisk) it was sensed at: Shapelet::pose_index
  Vec2 from{0.0, 0.0};  // the whisker's base when it touched
};

struct LiveCounter {
  std::string name;
  double value = 0.0;  // written as an integer when it is one
};

struct LiveState {
  // The path keeps a point every kPathStep metres; beyond kPathMaxPoints every other point is
  // dropped (the newest kept), so a long run's document stays small.
  static constexpr double kPathStep = 0.01;
  static constexpr std::size_t kPathMaxPoints = 4000;
  static constexpr std::size_t kMaxContacts = 64;

  std::string mode;  // "robot" | "sim"; empty before the run says
  std::string stage;
  double t = 0.0;  // seconds since the run started
  bool done = false;
  Vec2 area_lo{0.0, 0.0}, area_hi{0.0, 0.0};
  std::optional<Pose2> pose;
  std::vector<Vec2> path;
  std::vector<MapTable> tables;
  std::vector<MapWall> walls;
  std::vector<LiveContact> contacts;
  int shapelets = 0;
  std::vector<LiveCounter> counters;

  // The robot is at `pose` now: sets pose, extends the path (see kPathStep).
  void moveTo(const Pose2& pose);
  // The map's fused tables and walls, its newest `max_contacts` shapelets and their count.
  void setMap(const Map& map, std::size_t max_contacts = kMaxContacts);
  // Sets counter `name` (appended the first time; its place kept after).
  void setCounter(const std::string& name, double value);
};

// The document above, `seq` its sequence number.
std::string liveStateJson(const LiveState& state, std::uint64_t seq);

}  // namespace crunch::serve
