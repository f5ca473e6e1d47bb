// The consumer project's program: a map through the installed library's map file reader and ROS
// map rasteriser (mapping, render: Cairo, yaml-cpp and nlohmann linked through the package),
// and where an installed program finds the shipped models. Prints what it found; exit 0 when
// everything is as expected.
#include <cstdio>
#include <string>

#include "crunch/mapping/map_io.h"
#include "crunch/render/ros_map.h"
#include "crunch/signal/models_io.h"

int main(int argc, char** argv) {
  crunch::Map map;
  crunch::MapTable table;
  table.pose = {1.0, 1.0, 0.0};
  map.tables.push_back(table);
  const auto read = crunch::parseMapJson(crunch::mapToJson(map), "consumer map");
  if (!read || read.value().tables.size() != 1) {
    std::fprintf(stderr, "consumer: map round trip failed\n");
    return 1;
  }
  const auto grid = crunch::rasteriseRosMap(read.value(), crunch::RosMapOptions{});
  if (!grid) {
    std::fprintf(stderr, "consumer: %s\n", grid.error().message.c_str());
    return 1;
  }
  long occupied = 0;
  for (auto c : grid.value().cells) occupied += c == crunch::kRosOccupied ? 1 : 0;
  const std::string yaml = crunch::rosMapYaml(grid.value(), "map.pgm");
  std::printf("consumer: %d x %d cells, %ld occupied\n", grid.value().width,
              grid.value().height, occupied);
  std::printf("consumer: models %s\n", crunch::signal::shippedModelsPath("(source tree)").c_str());
  // argv[1]: the models path an installed program must find (the test passes it).
  if (argc > 1 && crunch::signal::shippedModelsPath("(source tree)") != argv[1]) return 1;
  return occupied >= 4 && yaml.find("resolution: 0.02") != std::string::npos ? 0 : 1;
}
