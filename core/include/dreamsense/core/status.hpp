#pragma once
// Errors as values: Result<T> = tl::expected<T, Error>; Status = Result<void>.
// "Nothing detected" is never an Error; an Error means the input or configuration is bad.

#include <fmt/format.h>
#include <tl/expected.hpp>

#include <string>
#include <utility>

namespace dreamsense {

enum class ErrorCode {
  kInvalidArgument,     // bad option or flag
  kNotFound,            // missing file, stream or key
  kCorruptData,         // unreadable, truncated or inconsistent data
  kUnsupported,         // unknown format version, unsupported codec or layout
  kIoError,             // cannot read or write (permissions, disk full)
  kEndOfStream,         // a source has no more frames (not a failure)
  kFailedPrecondition,  // wiring or call-order error (pipeline contract)
  kInternal,            // a bug; carries the values that broke the check
};

const char* to_string(ErrorCode code);

struct Error {
  ErrorCode code = ErrorCode::kInternal;
  std::string message;  // one line, names the file/option and the problem
  std::string to_string() const;
};

template <typename T>
using Result = tl::expected<T, Error>;
using Status = tl::expected<void, Error>;

inline tl::unexpected<Error> make_error(ErrorCode code, std::string message) {
  return tl::unexpected<Error>(Error{code, std::move(message)});
}

template <typename... Args>
tl::unexpected<Error> make_error(ErrorCode code, fmt::format_string<Args...> f, Args&&... args) {
  return tl::unexpected<Error>(Error{code, fmt::format(f, std::forward<Args>(args)...)});
}

inline Status ok_status() { return {}; }

// Thrown only for broken preconditions (programmer errors); the pipeline catches it per analyser.
class CheckFailure : public std::exception {
 public:
  explicit CheckFailure(std::string what) : what_(std::move(what)) {}
  const char* what() const noexcept override { return what_.c_str(); }

 private:
  std::string what_;
};

}  // namespace dreamsense

// Always-on precondition checks that print the values involved.
#define DS_CHECK(cond)                                                        \
  do {                                                                        \
    if (!(cond))                                                              \
      throw ::dreamsense::CheckFailure(                                       \
          fmt::format("{}:{}: check failed: {}", __FILE__, __LINE__, #cond)); \
  } while (0)
#define DS_CHECK_OP(a, op, b)                                                                  \
  do {                                                                                         \
    const auto& ds_a_ = (a);                                                                   \
    const auto& ds_b_ = (b);                                                                   \
    if (!(ds_a_ op ds_b_))                                                                     \
      throw ::dreamsense::CheckFailure(fmt::format("{}:{}: check failed: {} {} {} ({} vs {})", \
                                                   __FILE__, __LINE__, #a, #op, #b, ds_a_,     \
                                                   ds_b_));                                    \
  } while (0)
#define DS_CHECK_EQ(a, b) DS_CHECK_OP(a, ==, b)
#define DS_CHECK_GT(a, b) DS_CHECK_OP(a, >, b)
#define DS_CHECK_GE(a, b) DS_CHECK_OP(a, >=, b)
#define DS_CHECK_LT(a, b) DS_CHECK_OP(a, <, b)
#define DS_CHECK_LE(a, b) DS_CHECK_OP(a, <=, b)

// Error propagation (as MediaPipe's MP_RETURN_IF_ERROR / MP_ASSIGN_OR_RETURN):
//   DS_RETURN_IF_ERROR(write_header(out));           // returns the error of a Status/Result
//   DS_ASSIGN_OR_RETURN(auto model, read_model(p));  // declares/assigns the value or returns
#define DS_STATUS_CONCAT_INNER_(a, b) a##b
#define DS_STATUS_CONCAT_(a, b) DS_STATUS_CONCAT_INNER_(a, b)
#define DS_RETURN_IF_ERROR(expr)                                             \
  do {                                                                       \
    auto&& ds_status_ = (expr);                                              \
    if (!ds_status_) return ::tl::unexpected(std::move(ds_status_.error())); \
  } while (0)
#define DS_ASSIGN_OR_RETURN_IMPL_(tmp, lhs, expr)            \
  auto tmp = (expr);                                         \
  if (!tmp) return ::tl::unexpected(std::move(tmp.error())); \
  lhs = std::move(*tmp)
#define DS_ASSIGN_OR_RETURN(lhs, expr) \
  DS_ASSIGN_OR_RETURN_IMPL_(DS_STATUS_CONCAT_(ds_result_, __LINE__), lhs, expr)
