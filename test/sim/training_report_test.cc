// crunchhost train's fitting and report (crunch_sim/training_report.h): the --radial-f1 names and
// a fit refused on data it cannot fit. (The full protocol runs in test/sim/training_test.cc.)
#include "crunch_sim/training_report.h"

#include <catch2/catch.hpp>

using namespace crunch;
using namespace crunch::sim;

TEST_CASE("Training report: --radial-f1 names the f1 source", "[training]") {
  CHECK(f1SourceByName("max").value() == F1Source::kMaxOverWhisk);
  CHECK(f1SourceByName("first").value() == F1Source::kFirstEpisode);
  CHECK_THAT(f1SourceByName("median").error().message,
             Catch::Contains("--radial-f1") && Catch::Contains("median"));
}

TEST_CASE("Training report: no contacts, no fit (an Error, not a crash)", "[training]") {
  const TrainingData empty;
  CHECK_FALSE(fitTrainingModels(empty, TrainingOptions{}, F1Source::kFirstEpisode));
}
