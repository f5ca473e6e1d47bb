// Reading the project's input files strictly: scenes, models, recordings' metadata, maps and
// sweep rows (issue 16, "strict JSON everywhere"). nlohmann's parser accepts a document that a
// strict reader must refuse, each seen with a scene file: an object with the same key twice (the
// last silently wins), a NUL byte and anything after it (the parser stops at the NUL), a
// byte-order mark. And an input "file" that is not a regular file (/dev/zero, a FIFO nobody
// writes) would be read without end or block forever.
#pragma once

#include <cstddef>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "crunch/core/result.h"

namespace crunch {

// The largest input file read whole (bytes): far above any scene, models file, map or sweep the
// project writes (a 10^5-shapelet map is ~20 MB), low enough that reading one cannot exhaust
// the machine's memory.
inline constexpr std::size_t kMaxInputFileBytes = std::size_t{256} << 20;

// The whole content of the regular file at `path`, or an Error
// "<path>: cannot read <what>: <why>": missing, a directory, not a regular file (FIFO, device,
// socket: checked before opening, so a FIFO without a writer does not block), larger than
// `max_bytes`, or a read error.
Result<std::string> readInputFile(const std::string& path, const std::string& what,
                                  std::size_t max_bytes = kMaxInputFileBytes);

// A SAX pass that follows the member path of the value being parsed (`tables[1].x`; "" at the
// top): the first key an object holds twice stops it (duplicate()), and so does a parse error
// (errorPath(): where it stopped, e.g. to name the field of a number too large for a double,
// which nlohmann reports without one). Used by checkStrictJson and the scene reader.
class JsonPathTracker final : public nlohmann::json_sax<nlohmann::json> {
 public:
  const std::string& duplicate() const { return duplicate_; }
  const std::string& errorPath() const { return error_path_; }

  bool null() override { return value(); }
  bool boolean(bool) override { return value(); }
  bool number_integer(number_integer_t) override { return value(); }
  bool number_unsigned(number_unsigned_t) override { return value(); }
  bool number_float(number_float_t, const string_t&) override { return value(); }
  bool string(string_t&) override { return value(); }
  bool binary(binary_t&) override { return value(); }
  bool start_object(std::size_t) override { return open(false); }
  bool end_object() override { return close(); }
  bool start_array(std::size_t) override { return open(true); }
  bool end_array() override { return close(); }
  bool key(string_t& k) override;
  bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception&) override;

 private:
  struct Level {
    bool is_array = false;
    std::size_t index = 0;  // arrays: the element being parsed
    std::string key;        // objects: the member being parsed
    std::set<std::string> keys;
  };
  bool value();  // a complete value moves an enclosing array on to its next element
  bool open(bool is_array);
  bool close();
  std::string path() const;

  std::vector<Level> levels_;
  std::string duplicate_;
  std::string error_path_;
};

// okStatus() when `text` is one JSON document a strict reader accepts; else an Error
// "<source>: <place>: <why>" for what nlohmann alone lets through: a byte-order mark (byte 0),
// a NUL byte (line and column), an object with a key twice (the member's path, e.g.
// `arena.width`). Syntax errors are left to the parser (it reports them with line and column).
Status checkStrictJson(std::string_view text, const std::string& source);

// checkStrictJson, then the document; syntax errors as "<source>: <nlohmann's message>" (which
// gives the line and column), never an exception.
Result<nlohmann::json> parseStrictJson(std::string_view text, const std::string& source);
Result<nlohmann::ordered_json> parseStrictOrderedJson(std::string_view text,
                                                      const std::string& source);

}  // namespace crunch
