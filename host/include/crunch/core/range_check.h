// Range checks for the options structs' validate() (Ceres' Options::IsValid pattern): every
// setting of a run is checked by the library, in the one validate() of the struct that owns it,
// whichever road it came by (command line, recording metadata, sweep grid, API). Each check
// returns an Error naming the setting as "<field>: <what is wrong> (got <value>)"; a NaN or an
// infinity is never in range.
#pragma once

#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>

#include "crunch/core/result.h"

namespace crunch {

namespace range_check_detail {
template <typename T>
std::string text(T v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}
}  // namespace range_check_detail

// lo <= value <= hi, and finite.
inline Status checkRange(const std::string& field, double value, double lo, double hi) {
  if (std::isfinite(value) && lo <= value && value <= hi) return okStatus();
  return Error{field + ": must be a number from " + range_check_detail::text(lo) + " to " +
               range_check_detail::text(hi) + " (got " + range_check_detail::text(value) + ")"};
}

// lo < value <= hi, and finite.
inline Status checkAbove(const std::string& field, double value, double lo, double hi) {
  if (std::isfinite(value) && lo < value && value <= hi) return okStatus();
  return Error{field + ": must be a number above " + range_check_detail::text(lo) +
               " and at most " + range_check_detail::text(hi) + " (got " +
               range_check_detail::text(value) + ")"};
}

// lo <= value <= hi for a count.
inline Status checkCount(const std::string& field, std::int64_t value, std::int64_t lo,
                         std::int64_t hi) {
  if (lo <= value && value <= hi) return okStatus();
  return Error{field + ": must be a whole number from " + std::to_string(lo) + " to " +
               std::to_string(hi) + " (got " + std::to_string(value) + ")"};
}

// Prefixes an Error's message with `where` ("sampler options: ..."); passes okStatus() through.
inline Status within(const std::string& where, Status status) {
  if (status) return status;
  return Error{where + ": " + status.error().message};
}

}  // namespace crunch
