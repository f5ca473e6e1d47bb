// One road in (ARCHITECTURE.md §3): a setting out of range is refused by the library's own
// validation whichever road it came by, with exit status 2, a message naming the setting, and
// nothing written. This file covers the command line (`--sim`) and the sweep grid (`sweep`);
// the recording-metadata road (`--replay`) is covered in test/session. Each case runs the
// crunchhost binary as a user would.
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <string>

#include "support/run_command.h"
#include "support/temp_dir.h"

namespace {

using Run = CommandRun;

// `crunchhost ARGS`, as a user would run it.
Run run(const std::string& args) { return runCommand(std::string(CRUNCHHOST) + " " + args); }

struct Case {
  const char* args;   // the bad setting
  const char* named;  // what the message must name
};

// `crunchhost MODE --out DIR ARGS` is refused: exit 2, the setting named, DIR not created.
void expectRefused(const std::string& mode, const Case& c) {
  TempDir dir;
  const std::string out = dir.file("out");
  const Run r = run(mode + " --out " + out + " " + c.args);
  INFO(mode << " " << c.args << "\n" << r.output);
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.output, Catch::Contains(c.named));
  CHECK_FALSE(std::filesystem::exists(out));
}

}  // namespace

TEST_CASE("Settings: a bad value on the --sim command line is exit 2, named, nothing written",
          "[settings]") {
  const Case c = GENERATE(Case{"--working-memory 0", "working_memory"},
                          Case{"--working-memory 2147483647", "working_memory"},
                          Case{"--schedule-steps 0", "schedule_steps"},
                          Case{"--schedule-steps 100000000", "schedule_steps"},
                          Case{"--sweeps 0", "sweeps_per_temperature"},
                          Case{"--global-chains 0", "global_chains"},
                          Case{"--global-chains -2", "global_chains"},
                          Case{"--global-sweeps -1", "global_sweeps"},
                          Case{"--threads -1", "threads"},
                          Case{"--threads 257", "threads"},
                          Case{"--min-support 0", "min_support"},
                          Case{"--smart-gain nan", "smart_parent_gain"},
                          Case{"--smart-gain -100", "smart_parent_gain"},
                          Case{"--noise bogus", "noise"},
                          Case{"--acceptance bogus", "acceptance"});
  expectRefused("--sim", c);
}

TEST_CASE("Settings: a bad seed or scene file is exit 2, named, nothing written (issue 16)",
          "[settings]") {
  TempDir files;
  auto writeFile = [&](const std::string& name, const std::string& bytes) {
    const std::string path = files.file(name);
    FILE* f = std::fopen(path.c_str(), "wb");
    REQUIRE(f != nullptr);
    std::fwrite(bytes.data(), 1, bytes.size(), f);
    std::fclose(f);
    return path;
  };
  const std::string arena = R"("arena": {"width": 3.0, "depth": 2.5}, "tables": [])";
  const std::string dup = writeFile("dup.json", "{" + arena + ", " + arena + "}");
  const std::string bom = writeFile("bom.json", "\xEF\xBB\xBF{" + arena + "}");
  const std::string nul = writeFile("nul.json", "{" + arena + "}" + std::string(1, '\0') + "junk");
  const std::string fifo = files.file("fifo.json");
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);  // nobody writes it: reading would block forever
  const std::string dup_args = "--scene " + dup, bom_args = "--scene " + bom,
                    nul_args = "--scene " + nul, fifo_args = "--scene " + fifo;
  const Case cases[] = {Case{"--seed -1", "--seed"}, Case{"--seed 1e23", "--seed"},
                        Case{"--seed abc", "--seed"},
                        Case{dup_args.c_str(), "dup.json: arena: the key appears twice"},
                        Case{bom_args.c_str(), "bom.json: byte 0: a UTF-8 byte-order mark"},
                        Case{nul_args.c_str(), "nul.json: line 1, column"},
                        Case{fifo_args.c_str(), "fifo.json: cannot read scene file: not a "
                                                "regular file"},
                        Case{"--scene /dev/zero", "/dev/zero: cannot read scene file"},
                        Case{"--scene /tmp", "--scene: File is actually a directory"},
                        Case{"--scene no/such/scene.json", "--scene: File does not exist"}};
  for (const Case& c : cases) expectRefused("--sim", c);
}

TEST_CASE("Settings: an --out that cannot take the outputs is exit 2 before the run, nothing "
          "written (issue 16)", "[settings]") {
  TempDir dir;
  // --out on a file.
  const std::string file = dir.file("a_file");
  FILE* f = std::fopen(file.c_str(), "w");
  REQUIRE(f != nullptr);
  std::fclose(f);
  Run r = run("--sim --out " + file);
  INFO(r.output);
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.output, Catch::Contains(file + ": cannot write output: exists and is not a directory"));
  CHECK_THAT(r.output, !Catch::Contains("poses"));  // refused before the run (no progress)
  // map.png is a directory: nothing else is written either.
  const std::string out = dir.file("out");
  std::filesystem::create_directories(out + "/map.png");
  r = run("--sim --out " + out);
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.output, Catch::Contains(out + "/map.png: cannot write output: is a directory"));
  CHECK_FALSE(std::filesystem::exists(out + "/map.json"));
  CHECK_FALSE(std::filesystem::exists(out + "/report.json"));
  // A 1e308 m arena: refused as a scene error, not after the run by the picture.
  const std::string huge = dir.file("huge.json");
  f = std::fopen(huge.c_str(), "w");
  REQUIRE(f != nullptr);
  std::fputs(R"({"arena": {"width": 1e308, "depth": 2.5}})", f);
  std::fclose(f);
  expectRefused("--sim", Case{("--scene " + huge).c_str(), "arena.width: 1e+308 m is more than"});
}

TEST_CASE("Settings: a bad --explore setting is exit 2, named, nothing written", "[settings]") {
  const Case c = GENERATE(Case{"--explore spiral", "--explore: unknown policy 'spiral'"},
                          Case{"--explore random --travel-budget -1", "--travel-budget -1"},
                          Case{"--explore random --travel-budget nan", "--travel-budget nan"},
                          Case{"--explore grid --whisk-budget -2", "--whisk-budget -2"},
                          Case{"--travel-budget 5", "--travel-budget: needs --explore"},
                          Case{"--explore random --start 1,2", "--start 1,2: expected x,y,theta"},
                          Case{"--explore random --start 9,9,0", "outside the arena"},
                          // The body (radius 0.165) centred 5 cm from two boundary walls.
                          Case{"--explore frontier --start 0.05,0.05,0", "inside an obstacle"});
  expectRefused("--sim", c);
}

TEST_CASE("Settings: a bad value in a sweep grid is exit 2, named, nothing written",
          "[settings]") {
  const Case c = GENERATE(Case{"--working-memory 7,0", "working_memory"},
                          Case{"--working-memory -5", "working_memory"},
                          Case{"--schedule-steps 4,5000", "schedule_steps"},
                          Case{"--sweeps 0", "sweeps_per_temperature"},
                          Case{"--noise realistic,bogus", "bogus"},
                          Case{"--noise-scale 1,1e9", "sigma_r"},
                          Case{"--model paper,bogus", "model"});
  expectRefused("sweep", c);
}

namespace {

// Runs crunchhost with `args` (no shell), its output to /dev/null; the exit status and the
// child's peak resident memory (ru_maxrss, KiB).
struct Child {
  int status = -1;
  long max_rss_kib = 0;
};
Child runMeasured(const std::vector<std::string>& args) {
  std::vector<char*> argv{const_cast<char*>(CRUNCHHOST)};
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const pid_t pid = ::fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    std::freopen("/dev/null", "w", stdout);
    std::freopen("/dev/null", "w", stderr);
    ::execv(CRUNCHHOST, argv.data());
    ::_exit(127);
  }
  Child c;
  rusage use{};
  REQUIRE(::wait4(pid, &c.status, 0, &use) == pid);
  c.max_rss_kib = use.ru_maxrss;
  return c;
}

void writeText(const std::string& path, const std::string& text) {
  FILE* f = std::fopen(path.c_str(), "w");
  REQUIRE(f != nullptr);
  std::fputs(text.c_str(), f);
  std::fclose(f);
}

}  // namespace

TEST_CASE("Outputs: an empty 160 m arena maps in bounded memory (issue 16)", "[settings]") {
  // Was 1.5 GB (a dense free-space grid of the whole arena) and 4 GB before the picture's size
  // limit. Now: the free-space tiles the whiskers reached, plus the picture at its 8192-pixel
  // limit (256 MiB of RGBA): under 400 MB.
  TempDir dir;
  const std::string scene = dir.file("hall.json");
  writeText(scene, R"({"arena": {"width": 160, "depth": 160}, "tables": []})");
  const Child c = runMeasured({"--sim", "--scene", scene, "--out", dir.file("out")});
  CHECK(WIFEXITED(c.status));
  CHECK(WEXITSTATUS(c.status) == 0);
  CHECK(c.max_rss_kib < 400 * 1024);
  CHECK(std::filesystem::exists(dir.file("out/map.png")));
}

TEST_CASE("Outputs: a run removes the temporaries a killed run left, not a live run's (issue 16)",
          "[settings]") {
  TempDir dir;
  const std::string out = dir.file("out");
  std::filesystem::create_directories(out);
  const pid_t gone = ::fork();
  REQUIRE(gone >= 0);
  if (gone == 0) ::_exit(0);
  REQUIRE(::waitpid(gone, nullptr, 0) == gone);
  const std::string stale = out + "/map.png.tmp." + std::to_string(gone) + ".Ab12Cd";
  const std::string live = out + "/map.png.tmp." + std::to_string(::getpid()) + ".Ab12Cd";
  writeText(stale, "half a picture");
  writeText(live, "another run's picture in progress");
  const Run r = run("--sim --out " + out);
  INFO(r.output);
  CHECK(r.exit_code == 0);
  CHECK_FALSE(std::filesystem::exists(stale));
  CHECK(std::filesystem::exists(live));
  CHECK(std::filesystem::exists(out + "/map.json"));
}

TEST_CASE("Outputs: SIGTERM during a --sim run leaves nothing (issue 16)", "[settings]") {
  TempDir dir;
  const std::string out = dir.file("out");
  // --json progress on stdout: the first pose line says the run is under way.
  int to_child[2];
  REQUIRE(::pipe(to_child) == 0);
  const pid_t pid = ::fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    ::dup2(to_child[1], 1);
    ::close(to_child[0]);
    ::close(to_child[1]);
    std::freopen("/dev/null", "w", stderr);
    ::execl(CRUNCHHOST, CRUNCHHOST, "--sim", "--json", "--out", out.c_str(), nullptr);
    ::_exit(127);
  }
  ::close(to_child[1]);
  FILE* progress = ::fdopen(to_child[0], "r");
  REQUIRE(progress != nullptr);
  char line[512];
  REQUIRE(std::fgets(line, sizeof line, progress) != nullptr);  // a progress event: mid-run
  REQUIRE(::kill(pid, SIGTERM) == 0);
  int status = 0;
  REQUIRE(::waitpid(pid, &status, 0) == pid);
  std::fclose(progress);
  CHECK(WIFSIGNALED(status));
  CHECK(WTERMSIG(status) == SIGTERM);
  // Nothing: no outputs, no temporaries (the directory is made only when the outputs are).
  const bool empty = !std::filesystem::exists(out) || std::filesystem::is_empty(out);
  CHECK(empty);
}
