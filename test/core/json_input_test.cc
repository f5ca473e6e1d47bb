// Strict input files (crunch/core/json_input.h): what nlohmann alone accepts and a strict reader
// refuses, each with the file and the place named; files that are not regular are refused
// without being opened (a FIFO without a writer would block).
#include "crunch/core/json_input.h"

#include <sys/stat.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>

#include "support/temp_dir.h"

using namespace crunch;
namespace fs = std::filesystem;

namespace {
void write(const fs::path& p, const std::string& bytes) {
  std::ofstream out(p, std::ios::binary);
  out << bytes;
}
bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }
}  // namespace

TEST_CASE("Strict JSON: a document nlohmann takes as it is passes, its value intact", "[core]") {
  const auto j = parseStrictJson(R"({"arena": {"width": 3, "depth": 2.5}, "tables": [{"x": 1}]})",
                                 "s.json");
  REQUIRE(j);
  CHECK(j.value()["arena"]["depth"] == 2.5);
  CHECK(j.value()["tables"][0]["x"] == 1);
  // Same keys in different objects are not duplicates.
  CHECK(checkStrictJson(R"({"a": {"x": 1}, "b": {"x": 2}, "c": [{"x": 1}, {"x": 2}]})", "s"));
}

TEST_CASE("Strict JSON: a key twice in one object is an error naming the member", "[core]") {
  const auto top = checkStrictJson(R"({"arena": {"width": 3}, "arena": {"width": 4}})", "s.json");
  REQUIRE_FALSE(top);
  CHECK(top.error().message == "s.json: arena: the key appears twice in its object; keep one");
  const auto nested =
      parseStrictJson(R"({"tables": [{"x": 1}, {"x": 1, "y": 2, "x": 3}]})", "s.json");
  REQUIRE_FALSE(nested);
  CHECK(contains(nested.error().message, "s.json: tables[1].x: the key appears twice"));
}

TEST_CASE("Strict JSON: a NUL byte, and whatever follows it, is an error with line and column",
          "[core]") {
  // nlohmann stops at the NUL and would return the document before it.
  const std::string text = std::string("{\"a\": 1}\n") + '\0' + "garbage";
  REQUIRE(nlohmann::json::parse(text)["a"] == 1);
  const auto st = parseStrictJson(text, "s.json");
  REQUIRE_FALSE(st);
  CHECK(st.error().message == "s.json: line 2, column 1: a NUL byte; the document must be text only");
}

TEST_CASE("Strict JSON: a byte-order mark is an error at byte 0", "[core]") {
  const auto st = parseStrictJson("\xEF\xBB\xBF{\"a\": 1}", "s.json");
  REQUIRE_FALSE(st);
  CHECK(contains(st.error().message, "s.json: byte 0: a UTF-8 byte-order mark"));
}

TEST_CASE("Strict JSON: syntax errors and trailing bytes name the file, line and column", "[core]") {
  const auto bad = parseStrictJson("{\"a\": 1,\n \"b\": }", "s.json");
  REQUIRE_FALSE(bad);
  CHECK(contains(bad.error().message, "s.json: parse error at line 2, column"));
  const auto trailing = parseStrictOrderedJson("{\"a\": 1} {\"b\": 2}", "t.json");
  REQUIRE_FALSE(trailing);
  CHECK(contains(trailing.error().message, "t.json: parse error at line 1, column"));
  // Invalid UTF-8 inside a string.
  const auto utf = parseStrictJson("{\"a\": \"\xC3\x28\"}", "u.json");
  REQUIRE_FALSE(utf);
  CHECK(contains(utf.error().message, "u.json: "));
}

TEST_CASE("readInputFile: a regular file whole, a directory, a FIFO, a device, a missing or an "
          "oversized file is an Error naming it", "[core]") {
  TempDir scratch;
  const fs::path d = scratch.path();
  const fs::path ok = d / "ok.json";
  write(ok, "{\"a\": 1}");
  const auto text = readInputFile(ok.string(), "scene file");
  REQUIRE(text);
  CHECK(text.value() == "{\"a\": 1}");

  const auto dir = readInputFile(d.string(), "scene file");
  REQUIRE_FALSE(dir);
  CHECK(dir.error().message == d.string() + ": cannot read scene file: is a directory");

  const fs::path fifo = d / "fifo.json";
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  const auto f = readInputFile(fifo.string(), "scene file");  // returns: it does not open it
  REQUIRE_FALSE(f);
  CHECK(f.error().message ==
        fifo.string() + ": cannot read scene file: not a regular file (a FIFO, device or socket)");

  const auto zero = readInputFile("/dev/zero", "models file");
  REQUIRE_FALSE(zero);
  CHECK(contains(zero.error().message, "/dev/zero: cannot read models file: not a regular file"));

  const auto missing = readInputFile((d / "none.json").string(), "scene file");
  REQUIRE_FALSE(missing);
  CHECK(contains(missing.error().message, "none.json: cannot read scene file: No such file"));

  const auto big = readInputFile(ok.string(), "scene file", 4);
  REQUIRE_FALSE(big);
  CHECK(contains(big.error().message, "ok.json: cannot read scene file: is 8 bytes, more than the 4"));
}
