#pragma once
// Result<T>: the value of an operation of ours, or an Error saying what was wrong.
// Shaped like std::expected (which g++ 12 lacks) so that it can be swapped for it later.
#include <cassert>
#include <string>
#include <utility>
#include <variant>

namespace epa::core {

enum class ErrorCode {
  kInvalidArgument,  // a parameter or option is out of its domain
  kParse,            // a file or string could not be read as the expected format
  kIo,               // a file could not be opened, read or written
  kNumerical,        // a computation failed (singular matrix, no convergence)
};

struct Error {
  ErrorCode code = ErrorCode::kInvalidArgument;
  std::string message;
};

inline Error invalid_argument(std::string message) { return {ErrorCode::kInvalidArgument, std::move(message)}; }
inline Error parse_error(std::string message) { return {ErrorCode::kParse, std::move(message)}; }
inline Error io_error(std::string message) { return {ErrorCode::kIo, std::move(message)}; }
inline Error numerical_error(std::string message) { return {ErrorCode::kNumerical, std::move(message)}; }

template <typename T>
class [[nodiscard]] Result {
 public:
  Result(T value) : data_(std::move(value)) {}       // NOLINT: implicit by design, like std::expected
  Result(Error error) : data_(std::move(error)) {}   // NOLINT

  bool has_value() const { return std::holds_alternative<T>(data_); }
  explicit operator bool() const { return has_value(); }

  const T& value() const& { assert(has_value()); return std::get<T>(data_); }
  T& value() & { assert(has_value()); return std::get<T>(data_); }
  T&& value() && { assert(has_value()); return std::get<T>(std::move(data_)); }
  const T& operator*() const& { return value(); }
  T& operator*() & { return value(); }
  const T* operator->() const { return &value(); }
  T* operator->() { return &value(); }

  const Error& error() const { assert(!has_value()); return std::get<Error>(data_); }

 private:
  std::variant<T, Error> data_;
};

// Result<void> equivalent: success or an Error.
struct Ok {};
using Status = Result<Ok>;
inline Status ok() { return Ok{}; }

}  // namespace epa::core
