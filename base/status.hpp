// Status and Result: the one error type of visvol.
//
// Start-up and offline code return a Status (or a Result<T>) whose message names
// the input and the problem ("dem.tif: post (3, 7) is NaN"); nothing throws across
// module boundaries. Real-time code does not build messages: it returns an Errc
// and counts (see STYLE.md, "two error regimes").
//
// Thread-safety: values, no shared state. Cost: a Status that is ok holds no
// string and never allocates.
#pragma once

#include <cassert>
#include <optional>
#include <string>
#include <utility>

namespace visvol {

// Error classes. Negative in the C style of Cyclone DDS so a raw code can travel
// through C APIs; 0 is success.
enum class Errc : int {
  ok = 0,
  invalid_argument = -1,  // a value from outside is out of range or malformed
  io = -2,                // a file or device could not be read or written
  corrupt = -3,           // stored data fails a checksum or a structural check
  unsupported = -4,       // valid input this build cannot handle
  resource = -5,          // memory or another budget would be exceeded
  timeout = -6,
  state = -7,   // the call is not valid in the current state
  output = -8,  // an output could not be written (disk full, I/O error)
};

class [[nodiscard]] Status {
 public:
  Status() = default;
  Status(Errc code, std::string message) : code_(code), message_(std::move(message)) { assert(code != Errc::ok); }
  static Status ok_status() { return Status(); }

  bool ok() const { return code_ == Errc::ok; }
  explicit operator bool() const { return ok(); }
  Errc code() const { return code_; }
  const std::string& message() const { return message_; }

  // Prefixes the message with context ("reading dem.tif: ...").
  Status with_context(const std::string& context) const {
    if (ok()) return *this;
    return Status(code_, context + ": " + message_);
  }

 private:
  Errc code_ = Errc::ok;
  std::string message_;
};

inline Status invalid_argument(std::string message) { return Status(Errc::invalid_argument, std::move(message)); }
inline Status io_error(std::string message) { return Status(Errc::io, std::move(message)); }
inline Status output_error(std::string message) { return Status(Errc::output, std::move(message)); }
inline Status corrupt(std::string message) { return Status(Errc::corrupt, std::move(message)); }
inline Status resource_error(std::string message) { return Status(Errc::resource, std::move(message)); }

// A value or the Status that explains why there is none.
template <typename T>
class [[nodiscard]] Result {
 public:
  Result(T value) : value_(std::move(value)) {}                                  // NOLINT: implicit by design
  Result(Status status) : status_(std::move(status)) { assert(!status_.ok()); }  // NOLINT

  bool ok() const { return value_.has_value(); }
  explicit operator bool() const { return ok(); }
  const Status& status() const { return status_; }

  T& value() & {
    assert(ok());
    return *value_;
  }
  const T& value() const& {
    assert(ok());
    return *value_;
  }
  T&& value() && {
    assert(ok());
    return std::move(*value_);
  }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }

 private:
  std::optional<T> value_;
  Status status_;
};

}  // namespace visvol

// Returns early from the enclosing function when a Status is not ok.
#define VISVOL_RETURN_IF_ERROR(expr)                 \
  do {                                               \
    ::visvol::Status visvol_status_ = (expr);        \
    if (!visvol_status_.ok()) return visvol_status_; \
  } while (false)
