// The sweep grid (mapping/sweep.h): grid order, validation naming the option, the fingerprint,
// rows through CSV and JSON and back, shards and jobs, and the merge of shards. No simulator.
#include "crunch/mapping/sweep.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "support/temp_dir.h"

using namespace crunch;

namespace {

// (std::string(...): GCC 12 warns -Wrestrict falsely on `s.seeds = "3"` here once inlined.)
SweepGridSpec smallSpec() {
  SweepGridSpec s;
  s.noise = std::string("ideal,noisy");
  s.schedule_steps = std::string("4,8");
  s.seeds = std::string(1, '3');
  return s;
}

SweepRow rowAt(const SweepGrid& g, size_t index, const SweepShard& shard) {
  MapStats stats;
  stats.poses = 10;
  stats.shapelets = 7;
  stats.proposals = 123456789012LL;
  Evaluation ev;
  ev.true_tables = 2;
  ev.fused_tables = 3;
  ev.matched = 2;
  ev.precision = 2.0 / 3.0;
  ev.recall = 1.0;
  ev.f1 = 0.8;
  ev.mean_position_error = 0.1 * static_cast<double>(index);
  return sweepRow(g, index, shard, stats, ev, 0.25, 4096);
}

void writeText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

}  // namespace

TEST_CASE("Sweep grid: points in grid order, seed fastest and scene slowest", "[sweep]") {
  const auto g = buildSweepGrid(smallSpec());
  REQUIRE(g);
  CHECK(g.value().size() == 2 * 2 * 3);
  CHECK(g.value().scenes.size() == 1);
  CHECK(g.value().scenes[0].arg == "default");
  const SweepPoint p0 = g.value().pointAt(0);
  CHECK((p0.noise == 0 && p0.schedule_steps == 4 && p0.seed == 1));
  const SweepPoint p4 = g.value().pointAt(4);  // seed 2 of (ideal, 8)
  CHECK((p4.noise == 0 && p4.schedule_steps == 8 && p4.seed == 2));
  const SweepPoint last = g.value().pointAt(11);
  CHECK((last.noise == 1 && last.schedule_steps == 8 && last.seed == 3));
  const MappingOptions mo = g.value().mappingOptions(last);
  CHECK(mo.seed == 3);
  CHECK(mo.sampler.schedule_steps == 8);
  CHECK(mo.working_memory == MappingOptions{}.working_memory);
  CHECK(mo.validate().ok());
}

TEST_CASE("Sweep grid: the object model axis sits between scene and noise", "[sweep]") {
  SweepGridSpec s = smallSpec();
  s.models = "paper,rooms";
  const auto g = buildSweepGrid(s);
  REQUIRE(g);
  CHECK(g.value().size() == 2 * 2 * 2 * 3);
  // Model slower than noise: the first 12 points are the paper's, the next 12 the rooms model's.
  CHECK(g.value().pointAt(11).model == ObjectModel::kPaper);
  const SweepPoint p = g.value().pointAt(12);
  CHECK((p.model == ObjectModel::kRooms && p.noise == 0 && p.schedule_steps == 4 && p.seed == 1));
  CHECK(g.value().mappingOptions(p).model.objects == ObjectModel::kRooms);
  CHECK(sweepRow(g.value(), 12, {}, {}, {}, 0.0, 0).model == "rooms");
  // No --model: crunchhost --sim's (walls). `--model paper` alone keeps the fingerprint of a
  // grid from before the axis (the golden sweep's).
  const auto plain = buildSweepGrid(smallSpec());
  REQUIRE(plain);
  CHECK(plain.value().models == std::vector<ObjectModel>{ObjectModel::kWalls});
  SweepGridSpec paper_only = smallSpec();
  paper_only.models = "paper";
  CHECK(buildSweepGrid(paper_only).value().fingerprint != plain.value().fingerprint);
  CHECK(g.value().fingerprint != plain.value().fingerprint);
}

TEST_CASE("Sweep grid: noise scales are multiples of realistic, named xS", "[sweep]") {
  SweepGridSpec s;
  s.noise_scale = "0.5,2";
  const auto g = buildSweepGrid(s);
  REQUIRE(g);
  REQUIRE(g.value().noises.size() == 2);
  CHECK(g.value().noises[0].name == "x0.5");
  CHECK(g.value().noises[1].sigma_r == Approx(2 * NoiseRegime::realistic().sigma_r));
  SweepGridSpec none;
  REQUIRE(buildSweepGrid(none));
  CHECK(buildSweepGrid(none).value().noises.front().name == "realistic");
}

TEST_CASE("Sweep grid: every bad list is an Error naming its option", "[sweep]") {
  struct Case {
    std::string SweepGridSpec::*field;
    std::string value, option;
  };
  const Case cases[] = {{&SweepGridSpec::models, "paper,chairs", "--model"},
                        {&SweepGridSpec::models, "rooms,rooms", "--model"},
                        {&SweepGridSpec::noise, "realistic,loud", "--noise"},
                        {&SweepGridSpec::noise, "ideal,ideal", "--noise"},
                        {&SweepGridSpec::noise_scale, "1,x", "--noise-scale"},
                        {&SweepGridSpec::noise_scale, "-1", "--noise-scale"},
                        {&SweepGridSpec::schedule_steps, "4,,8", "--schedule-steps"},
                        {&SweepGridSpec::schedule_steps, "0", "--schedule-steps"},
                        {&SweepGridSpec::sweeps, "1,1", "--sweeps"},
                        {&SweepGridSpec::working_memory, "7,", "--working-memory"},
                        {&SweepGridSpec::working_memory, "5000", "--working-memory"},
                        {&SweepGridSpec::seeds, "two", "--seeds"},
                        {&SweepGridSpec::seeds, "1,2", "--seeds"},
                        {&SweepGridSpec::seed_list, "3,3", "--seed-list"}};
  for (const Case& c : cases) {
    SweepGridSpec s;
    s.*c.field = c.value;
    const auto g = buildSweepGrid(s);
    INFO(c.option << " " << c.value);
    REQUIRE_FALSE(g);
    CHECK_THAT(g.error().message, Catch::Contains(c.option));
  }
  SweepGridSpec both;
  both.seeds = "2";
  both.seed_list = "1";
  CHECK_THAT(buildSweepGrid(both).error().message, Catch::Contains("--seeds and --seed-list"));
  SweepGridSpec missing;
  missing.scenes = {"/nonexistent/scene.json"};
  CHECK_THAT(buildSweepGrid(missing).error().message,
             Catch::Contains("--scene") && Catch::Contains("/nonexistent/scene.json"));
}

TEST_CASE("Sweep grid: the fingerprint follows the grid, not the spelling", "[sweep]") {
  const std::string a = buildSweepGrid(smallSpec()).value().fingerprint;
  CHECK(a.size() == 16);
  SweepGridSpec spaced = smallSpec();
  spaced.schedule_steps = " 4, 8 ";
  CHECK(buildSweepGrid(spaced).value().fingerprint == a);
  SweepGridSpec other = smallSpec();
  other.seeds = "4";
  CHECK(buildSweepGrid(other).value().fingerprint != a);
}

TEST_CASE("Sweep shards and jobs parse or name their option", "[sweep]") {
  CHECK(parseSweepShard("").value().name() == "0/1");
  const auto s = parseSweepShard("1/3");
  REQUIRE(s);
  CHECK(s.value().holds(4));
  CHECK_FALSE(s.value().holds(3));
  for (const char* bad : {"3/3", "1", "a/b", "-1/2", "1/0"})
    CHECK_THAT(parseSweepShard(bad).error().message, Catch::Contains("--shard"));
  CHECK(parseSweepJobs("").value() == 0);
  CHECK(parseSweepJobs("3").value() == 3);
  for (const char* bad : {"-1", "1,2", "x"})
    CHECK_THAT(parseSweepJobs(bad).error().message, Catch::Contains("--jobs"));
}

TEST_CASE("Sweep rows: CSV has the JSON's values, and JSON reads back exactly", "[sweep]") {
  const SweepGrid g = buildSweepGrid(smallSpec()).value();
  std::vector<SweepRow> rows = {rowAt(g, 0, {}), rowAt(g, 7, {})};
  rows[1].accuracy.mean_angle_error = std::numeric_limits<double>::quiet_NaN();  // written null
  const std::string json = sweepRowsJson(rows);
  const auto back = parseSweepRows(json, "sweep.json");
  REQUIRE(back);
  CHECK(sweepRowsJson(back.value()) == json);
  CHECK(sweepRowsCsv(back.value()) == sweepRowsCsv(rows));
  const std::string csv = sweepRowsCsv(rows);
  CHECK(csv.substr(0, csv.find('\n')) ==
        "grid,grid_index,grid_size,shard,scene,model,explore,noise,sigma_r,sigma_phi,"
        "schedule_steps,sweeps,working_memory,seed,poses,shapelets,travel_m,whisks,"
        "fused_tables,true_tables,matched,precision,recall,"
        "f1,mean_position_error_m,mean_angle_error_rad,per_pose_match_fraction,"
        "phantoms_near_walls,phantoms_elsewhere,proposals,peak_live_tables,peak_live_legs,"
        "wall_s,process_peak_rss_kib");
  CHECK(back.value()[1].proposals == 123456789012LL);
  CHECK(back.value()[1].noise == "noisy");  // 7 = (noisy, 4 temperatures, seed 2)
  // Without --explore: the pose list teleported, no travel measured, one whisk per pose.
  CHECK(back.value()[1].explore == "none");
  CHECK(std::isnan(back.value()[1].travel_m));
  CHECK(back.value()[1].whisks == 10);
  CHECK_FALSE(parseSweepRows("{}", "x.json"));
  CHECK_THAT(parseSweepRows("[{\"grid\": 1}]", "x.json").error().message,
             Catch::Contains("x.json") && Catch::Contains("not a sweep row"));
}

TEST_CASE("Sweep merge: shards join in grid order, other grids, twins and gaps refused",
          "[sweep]") {
  const SweepGrid g = buildSweepGrid(smallSpec()).value();
  const SweepShard s0 = parseSweepShard("0/2").value(), s1 = parseSweepShard("1/2").value();
  std::vector<SweepRow> even, odd;
  for (size_t i = 0; i < g.size(); ++i) (i % 2 ? odd : even).push_back(rowAt(g, i, i % 2 ? s1 : s0));
  TempDir a, b, c;
  writeText(a.file("sweep.json"), sweepRowsJson(odd));
  writeText(b.file("sweep.json"), sweepRowsJson(even));
  const auto merged = mergeSweepShards({a.path().string(), b.path().string()});
  REQUIRE(merged);
  REQUIRE(merged.value().size() == g.size());
  for (size_t i = 0; i < g.size(); ++i) CHECK(merged.value()[i].grid_index == i);
  CHECK_THAT(mergeSweepShards({a.path().string()}).error().message,
             Catch::Contains("missing") && Catch::Contains("0, 2, 4"));
  CHECK_THAT(mergeSweepShards({a.path().string(), a.path().string()}).error().message,
             Catch::Contains("appears twice"));
  std::vector<SweepRow> other = even;
  for (SweepRow& r : other) r.grid = "0000000000000000";
  writeText(c.file("sweep.json"), sweepRowsJson(other));
  CHECK_THAT(mergeSweepShards({a.path().string(), c.path().string()}).error().message,
             Catch::Contains("another grid"));
  CHECK_THAT(mergeSweepShards({c.file("nothing")}).error().message,
             Catch::Contains("not a sweep output directory"));
  CHECK_FALSE(mergeSweepShards({}));
}

TEST_CASE("Sweep explore axis: grid order after the model, budgets checked, fingerprint kept "
          "without it", "[sweep]") {
  SweepGridSpec spec = smallSpec();
  const std::string plain = buildSweepGrid(spec).value().fingerprint;
  spec.explore = "random,infogain";
  spec.travel_budget = "30";
  spec.whisk_budget = "200";
  const auto g = buildSweepGrid(spec);
  REQUIRE(g);
  CHECK(g.value().size() == 2 * 2 * 2 * 3);
  CHECK(g.value().travel_budget_m == 30.0);
  CHECK(g.value().whisk_budget == 200);
  // explore is slower than noise: the first 12 points are random's, the next 12 infogain's.
  CHECK(g.value().pointAt(0).explore == "random");
  CHECK(g.value().pointAt(11).explore == "random");
  CHECK(g.value().pointAt(11).noise == 1);
  CHECK(g.value().pointAt(12).explore == "infogain");
  CHECK(g.value().pointAt(12).noise == 0);
  CHECK(g.value().fingerprint != plain);
  SweepGridSpec budget = spec;
  budget.travel_budget = "40";
  CHECK(buildSweepGrid(budget).value().fingerprint != g.value().fingerprint);
  SweepGridSpec none = smallSpec();
  none.explore = "none";  // the default said out loud: the same grid
  CHECK(buildSweepGrid(none).value().fingerprint == plain);
  CHECK(buildSweepGrid(smallSpec()).value().pointAt(0).explore == "none");

  SweepGridSpec twice = smallSpec();
  twice.explore = "random,random";
  CHECK_THAT(buildSweepGrid(twice).error().message,
             Catch::Contains("--explore") && Catch::Contains("twice"));
  SweepGridSpec lonely = smallSpec();
  lonely.travel_budget = "10";  // a budget without a policy to spend it
  CHECK_THAT(buildSweepGrid(lonely).error().message, Catch::Contains("--travel-budget"));
  lonely.travel_budget.clear();
  lonely.whisk_budget = "5";
  CHECK_THAT(buildSweepGrid(lonely).error().message, Catch::Contains("--whisk-budget"));
  SweepGridSpec bad = spec;
  bad.travel_budget = "ten";
  CHECK_THAT(buildSweepGrid(bad).error().message, Catch::Contains("--travel-budget"));
  bad = spec;
  bad.whisk_budget = "1,2";
  CHECK_THAT(buildSweepGrid(bad).error().message, Catch::Contains("--whisk-budget"));
}

TEST_CASE("Sweep curves.csv: one line per whisk of every explore row, written beside the sweep",
          "[sweep]") {
  SweepGridSpec spec = smallSpec();
  spec.explore = "grid,random";
  const SweepGrid g = buildSweepGrid(spec).value();
  std::vector<SweepRow> rows = {rowAt(g, 0, {}), rowAt(g, 13, {})};
  rows[0].travel_m = 1.5;
  rows[0].whisks = 2;
  rows[0].curve = {{0.5, 1, 0.0, std::numeric_limits<double>::quiet_NaN(), 0.0},
                   {1.5, 2, 0.5, 1.0, 2.0 / 3.0}};
  rows[1].travel_m = 0.75;
  rows[1].whisks = 1;
  rows[1].curve = {{0.75, 1, 0.25, 0.5, 1.0 / 3.0}};
  const std::string csv = sweepCurvesCsv(rows);
  std::vector<std::string> lines;
  for (size_t b = 0, e; (e = csv.find('\n', b)) != std::string::npos; b = e + 1)
    lines.push_back(csv.substr(b, e - b));
  REQUIRE(lines.size() == 4);
  CHECK(lines[0] == "grid_index,scene,model,explore,noise,seed,whisk,travel_m,whisks,recall,"
                    "precision,f1,run_travel_m,run_recall,run_f1");
  // Each line carries its run's travel and final map (rowAt: recall 1, F1 0.8).
  CHECK(lines[1] == "0,default,walls,grid,ideal,1,0,0.5,1,0.0,null,0.0,1.5,1.0,0.8");
  CHECK(lines[3].find(",0.75,1.0,0.8") != std::string::npos);
  CHECK(lines[2].rfind("0,default,walls,grid,ideal,1,1,1.5,2,0.5,1.0,0.6666", 0) == 0);
  // 13 = (random, ideal, 4 temperatures, seed 2)
  CHECK(lines[3].rfind("13,default,walls,random,ideal,2,0,0.75,1,0.25,0.5,0.333", 0) == 0);
  const std::string json = sweepRowsJson(rows);
  const auto back = parseSweepRows(json, "sweep.json");
  REQUIRE(back);
  CHECK(back.value()[0].explore == "grid");
  CHECK(back.value()[0].travel_m == 1.5);
  CHECK(back.value()[1].whisks == 1);

  TempDir dir;
  REQUIRE(writeSweepFiles(rows, dir.path().string()));
  std::ifstream in(dir.file("curves.csv"));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  CHECK(text == csv);
  // Without explore rows no curves.csv is written.
  TempDir plain;
  const SweepGrid pg = buildSweepGrid(smallSpec()).value();
  REQUIRE(writeSweepFiles({rowAt(pg, 0, {})}, plain.path().string()));
  CHECK_FALSE(std::ifstream(plain.file("curves.csv")).good());
}

TEST_CASE("Sweep merge: explore shards' curves come back from their curves.csv", "[sweep]") {
  SweepGridSpec spec = smallSpec();
  spec.explore = "grid";
  const SweepGrid g = buildSweepGrid(spec).value();
  const SweepShard s0 = parseSweepShard("0/2").value(), s1 = parseSweepShard("1/2").value();
  std::vector<SweepRow> even, odd;
  for (size_t i = 0; i < g.size(); ++i) {
    SweepRow r = rowAt(g, i, i % 2 ? s1 : s0);
    r.travel_m = static_cast<double>(i);
    for (int k = 0; k <= static_cast<int>(i % 3); ++k)  // 1 to 3 points per run
      r.curve.push_back({0.5 * k, k + 1, 0.1 * k, 1.0, 0.05 * k});
    (i % 2 ? odd : even).push_back(r);
  }
  std::vector<SweepRow> all;
  for (size_t i = 0; i < g.size(); ++i) all.push_back(i % 2 ? odd[i / 2] : even[i / 2]);
  TempDir a, b;
  REQUIRE(writeSweepFiles(odd, a.path().string()));
  REQUIRE(writeSweepFiles(even, b.path().string()));
  const auto merged = mergeSweepShards({a.path().string(), b.path().string()});
  REQUIRE(merged);
  CHECK(sweepCurvesCsv(merged.value()) == sweepCurvesCsv(all));
  CHECK(merged.value()[4].curve.size() == 2);
  std::filesystem::remove(a.file("curves.csv"));
  CHECK_THAT(mergeSweepShards({a.path().string(), b.path().string()}).error().message,
             Catch::Contains("curves.csv"));
}

TEST_CASE("Sweep rows: a wrong type or a value out of range is refused, naming row and column "
          "(issue 16)", "[sweep]") {
  const SweepGrid g = buildSweepGrid(smallSpec()).value();
  const SweepShard all = parseSweepShard("").value();
  auto edited = [&](const std::function<void(nlohmann::json&)>& edit) {
    nlohmann::json rows = nlohmann::json::parse(sweepRowsJson({rowAt(g, 0, all), rowAt(g, 1, all)}));
    edit(rows[1]);
    const auto parsed = parseSweepRows(rows.dump(), "s/sweep.json");
    return parsed ? std::string("(ok)") : parsed.error().message;
  };
  CHECK(edited([](nlohmann::json&) {}) == "(ok)");
  CHECK_THAT(edited([](nlohmann::json& r) { r["precision"] = "high"; }),
             Catch::Contains("s/sweep.json: row 2: precision: not the type"));
  CHECK_THAT(edited([](nlohmann::json& r) { r["recall"] = 1.5; }),
             Catch::Contains("row 2: recall: 1.5"));
  CHECK_THAT(edited([](nlohmann::json& r) { r["wall_s"] = -3; }),
             Catch::Contains("row 2: wall_s"));
  CHECK_THAT(edited([](nlohmann::json& r) { r["shard"] = "0/2"; }),  // point 1 is not in 0/2
             Catch::Contains("row 2: shard: grid point 1 is not in shard 0/2"));
  CHECK_THAT(edited([](nlohmann::json& r) { r["shard"] = "2/1"; }),
             Catch::Contains("row 2: shard: '2/1' is not i/n"));
  CHECK_THAT(edited([](nlohmann::json& r) { r["matched"] = 99; }),
             Catch::Contains("row 2: matched"));
}

TEST_CASE("Sweep merge: shards of different splits are refused even when they cover the grid "
          "(issue 16)", "[sweep]") {
  // 0/2 and 1/3 of a grid: points 0, 2, ... and 1, 4, ...; together they may cover a small grid
  // exactly, but they are not parts of one sweep.
  const SweepGrid g = buildSweepGrid(smallSpec()).value();
  const SweepShard half = parseSweepShard("0/2").value();
  std::vector<SweepRow> a_rows, b_rows;
  for (size_t i = 0; i < g.size(); ++i) {
    if (half.holds(i)) a_rows.push_back(rowAt(g, i, half));
    else b_rows.push_back(rowAt(g, i, SweepShard{static_cast<int>(i % 3), 3}));
  }
  TempDir a, b;
  writeText(a.file("sweep.json"), sweepRowsJson(a_rows));
  writeText(b.file("sweep.json"), sweepRowsJson(b_rows));
  const auto merged = mergeSweepShards({a.path().string(), b.path().string()});
  REQUIRE_FALSE(merged);
  CHECK_THAT(merged.error().message, Catch::Contains("is one of 3 shards") &&
                                         Catch::Contains("not parts of the same sweep"));
}
