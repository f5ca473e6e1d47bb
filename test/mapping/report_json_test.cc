// The mapping parts of report.json (mapping/report_json.h): keys in the documented order.
#include "crunch/mapping/report_json.h"

#include <catch2/catch.hpp>
#include <string>
#include <vector>

using namespace crunch;

namespace {
std::vector<std::string> keys(const nlohmann::ordered_json& j) {
  std::vector<std::string> k;
  for (const auto& [key, value] : j.items()) k.push_back(key);
  return k;
}
}  // namespace

TEST_CASE("report.json: accuracy, counts, model and sampler keep their keys and values",
          "[report_json]") {
  Evaluation ev;
  ev.true_tables = 6;
  ev.matched = 5;
  ev.recall = 5.0 / 6.0;
  ev.phantoms_near_walls = 2;
  const auto acc = evaluationJson(ev);
  CHECK(keys(acc) == std::vector<std::string>{
                         "true_tables", "fused_tables", "matched", "precision", "recall", "f1",
                         "mean_position_error_m", "mean_angle_error_rad", "per_pose_tables",
                         "per_pose_match_fraction", "phantoms_near_walls", "phantoms_elsewhere",
                         "match_tolerance"});
  CHECK(acc["recall"].get<double>() == ev.recall);
  CHECK(acc["match_tolerance"]["position_m"].get<double>() == MatchTolerance{}.position);
  CHECK(keys(accuracyJson(ev)).size() == 8);
  Map map;
  map.stats.poses = 4;
  map.per_pose.resize(3);
  CHECK(mapCountsJson(map)["inferring_poses"] == 3);
  MappingOptions mo;
  mo.working_memory = 9;
  CHECK(samplerJson(mo)["working_memory"] == 9);
  CHECK(modelJson(mo.model)["sigma_r_shapelet"].get<double>() == mo.model.sigma_r_shapelet);
}
