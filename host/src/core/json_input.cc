#include "crunch/core/json_input.h"

#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>
#include <vector>

namespace crunch {

namespace {

// "line L, column C" of byte `offset` (both from 1).
std::string placeOf(std::string_view text, std::size_t offset) {
  std::size_t line = 1, column = 1;
  for (std::size_t i = 0; i < offset && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  std::string out = "line ";  // appended, not '"..." + std::to_string()': GCC 12's -Wrestrict
  out.append(std::to_string(line)).append(", column ").append(std::to_string(column));
  return out;
}

template <typename J>
Result<J> parseAs(std::string_view text, const std::string& source) {
  if (auto st = checkStrictJson(text, source); !st) return st.error();
  try {
    return J::parse(text);
  } catch (const nlohmann::json::exception& e) {
    // "[json.exception.parse_error.101] parse error at line 1, column 2: ..." without the tag.
    std::string what = e.what();
    if (const auto close = what.find("] "); what.rfind("[json.exception.", 0) == 0 &&
                                            close != std::string::npos) {
      what = what.substr(close + 2);
    }
    return Error{source + ": " + what};
  }
}

}  // namespace

bool JsonPathTracker::key(string_t& k) {
  Level& l = levels_.back();
  l.key = k;
  if (!l.keys.insert(k).second) {
    duplicate_ = path();
    return false;  // stop: one is enough
  }
  return true;
}

bool JsonPathTracker::parse_error(std::size_t, const std::string&,
                                  const nlohmann::detail::exception&) {
  error_path_ = path();
  return false;
}

bool JsonPathTracker::value() {
  if (!levels_.empty() && levels_.back().is_array) ++levels_.back().index;
  return true;
}

bool JsonPathTracker::open(bool is_array) {
  levels_.push_back({is_array, 0, {}, {}});
  return true;
}

bool JsonPathTracker::close() {
  levels_.pop_back();
  return value();
}

std::string JsonPathTracker::path() const {
  std::string out;
  for (const Level& l : levels_) {
    if (l.is_array) {
      out.append("[").append(std::to_string(l.index)).append("]");
    } else {
      if (!out.empty()) out += ".";
      out += l.key;
    }
  }
  return out;
}

Result<std::string> readInputFile(const std::string& path, const std::string& what,
                                  std::size_t max_bytes) {
  const std::string prefix = path + ": cannot read " + what + ": ";
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return Error{prefix + std::strerror(errno)};
  if (S_ISDIR(st.st_mode)) return Error{prefix + "is a directory"};
  if (!S_ISREG(st.st_mode)) {
    return Error{prefix + "not a regular file (a FIFO, device or socket)"};
  }
  if (static_cast<std::size_t>(st.st_size) > max_bytes) {
    std::ostringstream s;
    s << prefix << "is " << st.st_size << " bytes, more than the " << max_bytes
      << " an input file may have";
    return Error{s.str()};
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{prefix + std::strerror(errno)};
  std::string text(static_cast<std::size_t>(st.st_size), '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  if (in.bad() || static_cast<std::size_t>(in.gcount()) != text.size()) {
    return Error{prefix + "short read (the file changed while it was read?)"};
  }
  return text;
}

Status checkStrictJson(std::string_view text, const std::string& source) {
  if (text.size() >= 3 && text.substr(0, 3) == "\xEF\xBB\xBF") {
    return Error{source + ": byte 0: a UTF-8 byte-order mark; JSON text must not begin with one "
                          "(RFC 8259 §8.1): save the file without it"};
  }
  if (const auto nul = text.find('\0'); nul != std::string_view::npos) {
    return Error{source + ": " + placeOf(text, nul) +
                 ": a NUL byte; the document must be text only"};
  }
  JsonPathTracker dup;
  nlohmann::json::sax_parse(text, &dup, nlohmann::json::input_format_t::json, false);
  if (!dup.duplicate().empty()) {
    return Error{source + ": " + dup.duplicate() +
                 ": the key appears twice in its object; keep one"};
  }
  return okStatus();
}

Result<nlohmann::json> parseStrictJson(std::string_view text, const std::string& source) {
  return parseAs<nlohmann::json>(text, source);
}

Result<nlohmann::ordered_json> parseStrictOrderedJson(std::string_view text,
                                                      const std::string& source) {
  return parseAs<nlohmann::ordered_json>(text, source);
}

}  // namespace crunch
