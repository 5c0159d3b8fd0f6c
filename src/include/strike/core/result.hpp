// SPDX-License-Identifier: MIT
// Result<T> and Status: the core never throws; it returns a value or an Error that names
// the file, line, field and value ("path:line: error: what, got value, expected range").
// Modelled on JPH Core/Result.h.
#pragma once

#include <optional>
#include <string>
#include <utility>

namespace strike {

/// What kind of failure, and so which exit code the CLI uses: 1 for bad input, 2 for a bug.
enum class ErrorKind { BadInput = 1, Internal = 2 };

struct Error {
  ErrorKind kind = ErrorKind::Internal;
  std::string message;  ///< "bar.msh:1432: error: tet 877 references node 90211, mesh has 9021 nodes"
};

inline Error badInput(std::string message) { return Error{ErrorKind::BadInput, std::move(message)}; }
inline Error internalError(std::string message) { return Error{ErrorKind::Internal, std::move(message)}; }

template <class T>
class [[nodiscard]] Result {
 public:
  Result(T value) : value_(std::move(value)) {}      // NOLINT(google-explicit-constructor)
  Result(Error error) : error_(std::move(error)) {}  // NOLINT(google-explicit-constructor)

  bool ok() const { return value_.has_value(); }
  explicit operator bool() const { return ok(); }
  T& value() & { return *value_; }
  const T& value() const& { return *value_; }
  T&& value() && { return std::move(*value_); }
  T* operator->() { return &*value_; }
  const T* operator->() const { return &*value_; }
  T& operator*() { return *value_; }
  const T& operator*() const { return *value_; }
  const Error& error() const { return error_; }

 private:
  std::optional<T> value_;
  Error error_;
};

/// A Result with no value: success or an Error.
class [[nodiscard]] Status {
 public:
  Status() = default;
  Status(Error error) : failed_(true), error_(std::move(error)) {}  // NOLINT(google-explicit-constructor)
  bool ok() const { return !failed_; }
  explicit operator bool() const { return ok(); }
  const Error& error() const { return error_; }

 private:
  bool failed_ = false;
  Error error_;
};

}  // namespace strike
