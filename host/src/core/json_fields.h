// Private to the crunch library: checked reading of JSON documents (scene files, map files, models
// files, recording metadata).
// Every failure names the field by its path ("tables[2].theta") so the caller's error names the
// file and the field (ARCHITECTURE.md §4). A failure throws FieldError, which never leaves the
// reader that uses these helpers: it catches it and returns an Error.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

namespace crunch::json_fields {

using Json = nlohmann::json;

struct FieldError {
  std::string path;  // empty: the document itself
  std::string what;
};

[[noreturn]] inline void fail(const std::string& path, const std::string& what) {
  throw FieldError{path, what};
}

// "source: path: what", the message of an Error for a FieldError.
inline std::string describe(const std::string& source, const FieldError& e) {
  return source + ": " + (e.path.empty() ? "(document)" : e.path) + ": " + e.what;
}

// nlohmann's messages start with "[json.exception.parse_error.101] "; the tag means nothing to
// a user.
inline std::string withoutExceptionTag(const std::string& what) {
  if (what.rfind("[json.exception.", 0) == 0) {
    const size_t end = what.find("] ");
    if (end != std::string::npos) return what.substr(end + 2);
  }
  return what;
}

inline std::string member(const std::string& path, std::string_view key) {
  return path.empty() ? std::string(key) : path + "." + std::string(key);
}

inline std::string element(const std::string& path, size_t i) {
  return path + "[" + std::to_string(i) + "]";
}

inline void expectObject(const Json& j, const std::string& path) {
  if (!j.is_object()) fail(path, std::string("expected an object, got ") + j.type_name());
}

// Requires `j` to be an object whose keys are all in `allowed`.
inline void expectObject(const Json& j, const std::string& path,
                         std::initializer_list<std::string_view> allowed) {
  expectObject(j, path);
  for (auto it = j.begin(); it != j.end(); ++it) {
    if (std::find(allowed.begin(), allowed.end(), it.key()) != allowed.end()) continue;
    std::string list;
    for (std::string_view k : allowed) list += (list.empty() ? "" : ", ") + std::string(k);
    fail(member(path, it.key()), "unknown key (allowed: " + list + ")");
  }
}

inline void expectArray(const Json& j, const std::string& path) {
  if (!j.is_array()) fail(path, std::string("expected an array, got ") + j.type_name());
}

inline double number(const Json& j, const std::string& path) {
  if (!j.is_number()) fail(path, std::string("expected a number, got ") + j.type_name());
  const double v = j.get<double>();
  if (!std::isfinite(v)) fail(path, "expected a finite number");
  return v;
}

inline const Json& required(const Json& obj, const std::string& path, std::string_view key) {
  const auto it = obj.find(key);
  if (it == obj.end()) fail(member(path, key), "missing (required)");
  return *it;
}

inline bool requiredBool(const Json& obj, const std::string& path, std::string_view key) {
  const Json& j = required(obj, path, key);
  if (!j.is_boolean()) fail(member(path, key), "expected true or false, got " + j.dump());
  return j.get<bool>();
}

// A non-negative integer no larger than `max`.
inline int count(const Json& j, const std::string& path,
                 int max = std::numeric_limits<int>::max()) {
  if (!j.is_number_unsigned() || j.get<std::uint64_t>() > static_cast<std::uint64_t>(max)) {
    fail(path, "expected an integer from 0 to " + std::to_string(max) + ", got " + j.dump());
  }
  return static_cast<int>(j.get<std::uint64_t>());
}

// Any whole number an int holds (its range is the setting's own validate()'s to check).
inline int integer(const Json& j, const std::string& path) {
  if (j.is_number_integer()) {
    const bool fits = j.is_number_unsigned()
                          ? j.get<std::uint64_t>() <= std::numeric_limits<int>::max()
                          : j.get<std::int64_t>() >= std::numeric_limits<int>::min();
    if (fits) return static_cast<int>(j.get<std::int64_t>());
  }
  fail(path, "expected a whole number within int range, got " + j.dump());
}

inline std::uint64_t unsignedInteger(const Json& j, const std::string& path) {
  if (!j.is_number_unsigned()) fail(path, "expected a non-negative whole number, got " + j.dump());
  return j.get<std::uint64_t>();
}

// `j` as an array of exactly `expected_size` elements.
inline const Json& array(const Json& j, const std::string& path, size_t expected_size) {
  expectArray(j, path);
  if (j.size() != expected_size) {
    fail(path, "expected " + std::to_string(expected_size) + " elements, got " +
                   std::to_string(j.size()));
  }
  return j;
}

inline double requiredNumber(const Json& obj, const std::string& path, std::string_view key) {
  const auto it = obj.find(key);
  if (it == obj.end()) fail(member(path, key), "missing (required)");
  return number(*it, member(path, key));
}

inline double optionalNumber(const Json& obj, const std::string& path, std::string_view key,
                             double fallback) {
  const auto it = obj.find(key);
  return it == obj.end() ? fallback : number(*it, member(path, key));
}

}  // namespace crunch::json_fields
