#include "crunch/blackboard/params.h"

#include "crunch/core/range_check.h"

namespace crunch {

Result<ObjectModel> objectModelByName(const std::string& name) {
  if (name == "paper") return ObjectModel::kPaper;
  if (name == "rooms") return ObjectModel::kRooms;
  return Error{"model: unknown object model '" + name + "' (paper | rooms)"};
}

const char* objectModelName(ObjectModel m) { return m == ObjectModel::kRooms ? "rooms" : "paper"; }

Status ModelParams::validate() const {
  const Status checks[] = {
      checkAbove("c_T", c_T, 0.0, 1e6),
      checkAbove("c_L", c_L, 0.0, 1e6),
      checkAbove("c_S", c_S, 0.0, 1e6),
      checkAbove("alpha_L", alpha_L, 0.0, 1e6),
      checkAbove("alpha_S", alpha_S, 0.0, 1e6),
      checkAbove("eps_a", eps_a, 0.0, 1.0),
      checkAbove("eps_b", eps_b, 0.0, 1.0),
      checkAbove("eps_c", eps_c, 0.0, 1.0),
      checkAbove("sigma_r_leg", sigma_r_leg, 0.0, 1.0),
      checkAbove("sigma_theta_leg", sigma_theta_leg, 0.0, kPi),
      checkAbove("sigma_r_shapelet", sigma_r_shapelet, 0.0, 1.0),
      checkAbove("sigma_theta_shapelet", sigma_theta_shapelet, 0.0, kPi),
      checkAbove("sigma_w", sigma_w, 0.0, 1.0),
      checkAbove("delta3", delta3, 0.0, 1e6),
      checkRange("table_width", table_width, 0.05, 10.0),
      checkRange("table_depth", table_depth, 0.05, 10.0),
      checkAbove("leg_side", leg_side, 0.0, 0.5 * std::min(table_width, table_depth)),
      checkRange("link_sigmas", link_sigmas, 1.0, 20.0),
      checkAbove("p_miss", p_miss, 0.0, 1.0),
      checkCount("free_pass_cap", free_pass_cap, 0, 1000),
      checkRange("free_margin", free_margin, 0.0, 0.5 * leg_side),
      checkAbove("c_W", c_W, 0.0, 1e6),
      checkAbove("alpha_W", alpha_W, 0.0, 1e6),
      checkRange("wall_cost_per_m", wall_cost_per_m, 0.0, 1e3),
      checkRange("wall_min_length", wall_min_length, 0.001, 1.0),
      checkAbove("wall_solid_depth", wall_solid_depth, 0.0, 1.0)};
  for (const Status& s : checks) {
    if (!s) return s;
  }
  return okStatus();
}

}  // namespace crunch
