#include "crunch/core/atomic_file.h"

#include <sys/stat.h>
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
