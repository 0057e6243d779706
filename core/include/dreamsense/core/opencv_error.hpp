#pragma once
// OpenCV's exception text ("OpenCV(4.6.0) ./modules/core/src/persistence.cpp:692: error: (-49:
// Unknown error code -49) ... in function 'open'") names OpenCV's own source file, which tells a
// user nothing. Errors quote only its reason (for a file it parses: the file, line and problem).

#include <opencv2/core.hpp>

#include <algorithm>
#include <exception>
#include <string>

namespace dreamsense {

inline std::string opencv_reason(const cv::Exception& e) {
  std::string s = e.err.empty() ? std::string("invalid data") : e.err;
  std::replace(s.begin(), s.end(), '\n', ' ');
  return s;
}

// Any exception reading a file can raise: OpenCV's (its reason) or the standard library's, which
// OpenCV's parser lets through on some malformed files (std::length_error: found by fuzzing,
// issue 18), so file readers catch std::exception.
inline std::string opencv_reason(const std::exception& e) {
  if (const auto* cv_error = dynamic_cast<const cv::Exception*>(&e))
    return opencv_reason(*cv_error);
  return e.what();
}

}  // namespace dreamsense
