// Expected-like result for decoding peer data: never throws; carries a reason on failure.
#pragma once
#include <optional>
#include <string>
#include <utility>

namespace tessera {

template <class T>
class Result {
 public:
  Result(T v) : value_(std::move(v)) {}  // NOLINT: implicit on purpose
  static Result fail(std::string why) { Result r; r.error_ = std::move(why); return r; }
  explicit operator bool() const { return value_.has_value(); }
  T& operator*() { return *value_; }
  const T& operator*() const { return *value_; }
  T* operator->() { return &*value_; }
  const T* operator->() const { return &*value_; }
  const std::string& error() const { return error_; }

 private:
  Result() = default;
  std::optional<T> value_;
  std::string error_;
};

}  // namespace tessera
