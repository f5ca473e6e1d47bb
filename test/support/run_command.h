// Runs a shell command line as a user would, for the tests that drive the binaries
// (crunchhost, crunch-virtual-robot): its exit status, its stdout and stderr interleaved, and its
// wall time. Header-only; test support.
#pragma once

#include <sys/wait.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <cstdio>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>

struct CommandRun {
  int exit_code = -1;  // -1 when the command did not exit normally (a signal)
  std::string output;  // stdout and stderr, interleaved
  double wall_s = 0.0;
};

inline CommandRun runCommand(const std::string& command) {
  CommandRun r;
  const auto t0 = std::chrono::steady_clock::now();
  FILE* p = popen((command + " 2>&1").c_str(), "r");
  REQUIRE(p != nullptr);
  char buf[4096];
  while (std::fgets(buf, sizeof buf, p) != nullptr) r.output += buf;
  const int status = pclose(p);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

// The same, run in `dir` (a test that runs the binaries on the project's own files).
inline CommandRun runCommandIn(const std::string& dir, const std::string& command) {
  return runCommand("cd '" + dir + "' && " + command);
}

// runCommandIn's exit status, its output in `*out` when given.
inline int exitStatusIn(const std::string& dir, const std::string& command,
                        std::string* out = nullptr) {
  CommandRun r = runCommandIn(dir, command);
  if (out != nullptr) *out = std::move(r.output);
  return r.exit_code;
}

// The last line of `output` that starts with `prefix` (without its newline), or "".
inline std::string lastLineStartingWith(const std::string& output, std::string_view prefix) {
  std::istringstream lines(output);
  std::string found;
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind(prefix, 0) == 0) found = line;
  }
  return found;
}
