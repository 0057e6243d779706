#include "dreamsense/core/status.hpp"

namespace dreamsense {

const char* to_string(ErrorCode code) {
  switch (code) {
    case ErrorCode::kInvalidArgument:
      return "INVALID_ARGUMENT";
    case ErrorCode::kNotFound:
      return "NOT_FOUND";
    case ErrorCode::kCorruptData:
      return "CORRUPT_DATA";
    case ErrorCode::kUnsupported:
      return "UNSUPPORTED";
    case ErrorCode::kIoError:
      return "IO_ERROR";
    case ErrorCode::kEndOfStream:
      return "END_OF_STREAM";
    case ErrorCode::kFailedPrecondition:
      return "FAILED_PRECONDITION";
    case ErrorCode::kInternal:
      return "INTERNAL";
  }
  return "UNKNOWN";
}

std::string Error::to_string() const {
  return fmt::format("{} ({})", message, dreamsense::to_string(code));
}

}  // namespace dreamsense
