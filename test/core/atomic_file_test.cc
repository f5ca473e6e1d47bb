#include "crunch/core/atomic_file.h"

#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>
#include <vector>

using namespace crunch;
namespace fs = std::filesystem;

namespace {

// A fresh directory made by mkdtemp, removed with its contents at scope exit.
struct ScratchDir {
  fs::path dir = makeDir();
  ~ScratchDir() {
    std::error_code ec;
    fs::permissions(dir, fs::perms::owner_all, fs::perm_options::add, ec);
    fs::remove_all(dir, ec);
  }
  static fs::path makeDir() {
    std::string name = (fs::temp_directory_path() / "crunch_atomic_file_test.XXXXXX").string();
    REQUIRE(::mkdtemp(name.data()) != nullptr);
    return name;
  }
  std::string at(const std::string& name) const { return (dir / name).string(); }
  // File names in the directory, sorted.
  std::vector<std::string> names() const {
    std::vector<std::string> out;
    for (const auto& e : fs::directory_iterator(dir)) out.push_back(e.path().filename());
    std::sort(out.begin(), out.end());
    return out;
  }
};

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void spit(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

Error customMessage(const std::string& target, const std::string& why) {
  return Error{"cannot save '" + target + "': " + why};
}

}  // namespace

TEST_CASE("AtomicFile: commit replaces the target whole, mode 0644, nothing else left", "[core]") {
  ScratchDir d;
  const std::string target = d.at("out.json");
  spit(target, "old content, longer than the new\n");

  Result<AtomicFile> file = AtomicFile::create(target);
  REQUIRE(file.ok());
  const std::string temp = file.value().tempPath();
  CHECK(fs::path(temp).parent_path() == d.dir);  // beside the target: rename stays in one fs
  CHECK(temp != target);
  REQUIRE(file.value().write("new ").ok());
  REQUIRE(file.value().write("content\n").ok());
  CHECK(slurp(target) == "old content, longer than the new\n");  // untouched until commit

  REQUIRE(file.value().commit().ok());
  CHECK(slurp(target) == "new content\n");
  CHECK(d.names() == std::vector<std::string>{"out.json"});
  struct stat st {};
  REQUIRE(::stat(target.c_str(), &st) == 0);
  CHECK((st.st_mode & 0777) == 0644);
}

TEST_CASE("AtomicFile: a library may write the temporary path itself", "[core]") {
  ScratchDir d;
  const std::string target = d.at("picture.svg");
  Result<AtomicFile> file = AtomicFile::create(target);
  REQUIRE(file.ok());
  spit(file.value().tempPath(), "<svg/>");  // as Cairo does: open by name, truncate, write
  REQUIRE(file.value().commit().ok());
  CHECK(slurp(target) == "<svg/>");
  CHECK(d.names() == std::vector<std::string>{"picture.svg"});
}

TEST_CASE("AtomicFile: without commit the target is untouched and no temporary is left", "[core]") {
  ScratchDir d;
  const std::string target = d.at("keep.txt");
  spit(target, "keep me");
  {
    Result<AtomicFile> file = AtomicFile::create(target);
    REQUIRE(file.ok());
    REQUIRE(file.value().write("half a fi").ok());
    // Moving the file on keeps one owner of the temporary.
    AtomicFile moved = std::move(file).value();
    CHECK(fs::exists(moved.tempPath()));
  }
  CHECK(slurp(target) == "keep me");
  CHECK(d.names() == std::vector<std::string>{"keep.txt"});

  { REQUIRE(AtomicFile::create(d.at("never.txt")).ok()); }
  CHECK(d.names() == std::vector<std::string>{"keep.txt"});
}

TEST_CASE("AtomicFile: a directory it cannot write in gives an Error naming the path", "[core]") {
  ScratchDir d;

  const std::string missing = d.at("no_such_dir/out.json");
  Result<AtomicFile> r = AtomicFile::create(missing);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().message.rfind(missing + ": cannot write file: ", 0) == 0);
  CHECK(contains(r.error().message, "No such file or directory"));

  spit(d.at("plain"), "a file, not a directory");
  const std::string under_file = d.at("plain/out.json");
  const Status s = writeFileAtomic(under_file, "{}");
  REQUIRE_FALSE(s.ok());
  CHECK(s.error().message.rfind(under_file + ": ", 0) == 0);
  CHECK(contains(s.error().message, "Not a directory"));

  if (::geteuid() != 0) {  // root writes through permissions
    const fs::path locked = d.dir / "locked";
    fs::create_directory(locked);
    fs::permissions(locked, fs::perms::owner_read | fs::perms::owner_exec);
    const std::string target = (locked / "out.json").string();
    const Status denied = writeFileAtomic(target, "{}");
    REQUIRE_FALSE(denied.ok());
    CHECK(contains(denied.error().message, target));
    CHECK(contains(denied.error().message, "Permission denied"));
  }

  // A caller's own wording still gets the target and the reason.
  Result<AtomicFile> custom = AtomicFile::create(missing, customMessage);
  REQUIRE_FALSE(custom.ok());
  CHECK(custom.error().message ==
        "cannot save '" + missing +
            "': creating a temporary file beside it: No such file or directory");
  const std::vector<std::string> left = d.names();
  CHECK((left == std::vector<std::string>{"plain"} ||
         left == std::vector<std::string>{"locked", "plain"}));
}

TEST_CASE("AtomicFile: a failed rename keeps the target and removes the temporary", "[core]") {
  ScratchDir d;
  const fs::path target = d.dir / "out.json";
  fs::create_directories(target / "inside");  // everything works up to the rename
  Result<AtomicFile> file = AtomicFile::create(target.string());
  REQUIRE(file.ok());
  REQUIRE(file.value().write("{}").ok());
  const Status s = file.value().commit();
  REQUIRE_FALSE(s.ok());
  CHECK(s.error().message.rfind(target.string() + ": cannot write file: renaming '", 0) == 0);
  CHECK(fs::is_directory(target / "inside"));
  CHECK(d.names() == std::vector<std::string>{"out.json"});
}

TEST_CASE("AtomicFile: two writers of the same target never collide", "[core]") {
  ScratchDir d;
  const std::string target = d.at("shared.txt");

  Result<AtomicFile> a = AtomicFile::create(target);
  Result<AtomicFile> b = AtomicFile::create(target);
  REQUIRE(a.ok());
  REQUIRE(b.ok());
  CHECK(a.value().tempPath() != b.value().tempPath());
  REQUIRE(a.value().write("from a").ok());
  REQUIRE(b.value().write("from b, the longer one").ok());
  REQUIRE(a.value().commit().ok());
  CHECK(slurp(target) == "from a");
  REQUIRE(b.value().commit().ok());
  CHECK(slurp(target) == "from b, the longer one");
  CHECK(d.names() == std::vector<std::string>{"shared.txt"});

  // Threads racing on one target: every write succeeds and the file is always one of them whole.
  constexpr int kThreads = 8, kRounds = 20;
  std::vector<std::string> contents;
  for (int t = 0; t < kThreads; ++t) {
    contents.push_back(std::string(1000 + 100 * t, static_cast<char>('a' + t)));
  }
  std::vector<int> failures(kThreads, 0);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      for (int i = 0; i < kRounds; ++i) failures[t] += writeFileAtomic(target, contents[t]) ? 0 : 1;
    });
  }
  for (auto& th : threads) th.join();
  CHECK(std::count(failures.begin(), failures.end(), 0) == kThreads);
  CHECK(std::find(contents.begin(), contents.end(), slurp(target)) != contents.end());
  CHECK(d.names() == std::vector<std::string>{"shared.txt"});
}

TEST_CASE("OutputSet: the files appear together at publish, not before", "[core]") {
  ScratchDir d;
  spit(d.at("b.txt"), "old b");
  OutputSet set;
  auto a = set.add(d.at("a.txt"));
  REQUIRE(a);
  REQUIRE(a.value()->write("new a"));
  auto b = set.add(d.at("b.txt"));
  REQUIRE(b);
  REQUIRE(b.value()->write("new b"));
  // Staged: the targets are as they were, the temporaries carry the pid.
  CHECK_FALSE(fs::exists(d.at("a.txt")));
  CHECK(slurp(d.at("b.txt")) == "old b");
  const std::string pid_part = ".tmp." + std::to_string(::getpid()) + ".";
  CHECK(contains(a.value()->tempPath(), pid_part));
  REQUIRE(set.publish());
  CHECK(slurp(d.at("a.txt")) == "new a");
  CHECK(slurp(d.at("b.txt")) == "new b");
  CHECK(d.names() == std::vector<std::string>{"a.txt", "b.txt"});
}

TEST_CASE("OutputSet: an error before publish leaves no output and no temporary", "[core]") {
  ScratchDir d;
  spit(d.at("a.txt"), "old a");
  {
    OutputSet set;
    auto a = set.add(d.at("a.txt"));
    REQUIRE(a);
    REQUIRE(a.value()->write("new a"));
    // The second output cannot be made (its directory is missing): the caller gives up.
    auto b = set.add(d.at("missing/b.txt"));
    CHECK_FALSE(b);
  }
  CHECK(slurp(d.at("a.txt")) == "old a");
  CHECK(d.names() == std::vector<std::string>{"a.txt"});
}

TEST_CASE("removeTempsOnSignals: SIGTERM mid-write removes the temporaries, then kills", "[core]") {
  ScratchDir d;
  int ready[2];
  REQUIRE(::pipe(ready) == 0);
  const pid_t child = ::fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    removeTempsOnSignals();
    OutputSet set;
    auto a = set.add(d.at("map.json"));
    auto b = set.add(d.at("map.png"));
    if (!a || !b || !a.value()->write("half")) ::_exit(10);
    (void)!::write(ready[1], "x", 1);  // the temporaries exist: kill me now
    for (;;) ::pause();
  }
  ::close(ready[1]);
  char c;
  REQUIRE(::read(ready[0], &c, 1) == 1);
  ::close(ready[0]);
  CHECK(d.names().size() == 2);  // the two temporaries
  REQUIRE(::kill(child, SIGTERM) == 0);
  int status = 0;
  REQUIRE(::waitpid(child, &status, 0) == child);
  CHECK(WIFSIGNALED(status));
  CHECK(WTERMSIG(status) == SIGTERM);  // it still dies of the signal
  CHECK(d.names().empty());
}

TEST_CASE("removeStaleTemps: a dead process's temporaries go, a live one's stay", "[core]") {
  ScratchDir d;
  // A pid that no longer runs: a child that has exited and been reaped.
  const pid_t gone = ::fork();
  REQUIRE(gone >= 0);
  if (gone == 0) ::_exit(0);
  REQUIRE(::waitpid(gone, nullptr, 0) == gone);
  const std::string dead = "map.png.tmp." + std::to_string(gone) + ".AbC123";
  const std::string live = "map.png.tmp." + std::to_string(::getppid()) + ".XyZ789";
  const std::string other = "notes.txt.tmp." + std::to_string(gone) + ".AbC123";
  for (const auto& n : {dead, live, other, std::string("map.png")}) spit(d.at(n), "x");
  CHECK(removeStaleTemps(d.dir.string(), {"map.json", "map.png"}) == 1);
  std::vector<std::string> want{live, "map.png", other};
  std::sort(want.begin(), want.end());
  CHECK(d.names() == want);
}
