// Expected failures (bad file, missing device) as values with a message a user can act on.
// Broken invariants are assertions instead (STYLE.md item 3).
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <variant>

namespace crunch {

struct Error {
  std::string message;  // names the file, field or device and what to do about it
};

template <typename T>
class Result {
 public:
  Result(T value) : v_(std::move(value)) {}      // NOLINT(google-explicit-constructor)
  Result(Error error) : v_(std::move(error)) {}  // NOLINT(google-explicit-constructor)

  bool ok() const { return std::holds_alternative<T>(v_); }
  explicit operator bool() const { return ok(); }
  const T& value() const& { return std::get<T>(v_); }
  T& value() & { return std::get<T>(v_); }
  T&& value() && { return std::get<T>(std::move(v_)); }
  const Error& error() const { return std::get<Error>(v_); }

 private:
  std::variant<T, Error> v_;
};

}  // namespace crunch

namespace crunch {
// Success or an Error, for operations with no value (writing a file, opening a device).
using Status = Result<std::monostate>;
inline Status okStatus() { return std::monostate{}; }
}  // namespace crunch
