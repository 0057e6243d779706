#pragma once
// How every reader of a user's OpenCV FileStorage file (YAML, XML, JSON) opens it: checks before
// the file reaches cv::FileStorage (issue 18, fuzz/README.md finding 4): Debian's OpenCV 4.6 XML
// reader dereferences null on some malformed files (a tag cut inside an attribute, a NUL byte),
// which ends the program instead of raising an error. So a file OpenCV would parse as XML (it
// starts, after an optional UTF-8 byte-order mark, with "<?xml") must first be well-formed XML
// (tinyxml2), and no FileStorage file may contain a NUL byte (a text format never does; OpenCV's
// line reader stops at one and then misreads the rest). Compressed files (".gz", which OpenCV
// inflates before parsing) are refused: their content cannot be checked here. Then every matrix of
// the file must hold the values its rows x cols x channels declare (fuzz/README.md findings 3 and
// 7): OpenCV allocates the declared size first, and takes a size that is not a number for INT_MAX.

#include "dreamsense/core/status.hpp"

#include <opencv2/core/persistence.hpp>

#include <filesystem>
#include <string_view>

namespace dreamsense {

// `path` read, checked and parsed (from memory: OpenCV's reader of a file loops forever on some
// malformed YAML that it parses from memory in no time, fuzz/README.md finding 8). Errors are one
// line naming the file (and the line of an XML error): kIoError (cannot be read), kCorruptData
// (NUL byte, malformed XML, a YAML/XML/JSON syntax error, a matrix whose size disagrees with its
// data), kUnsupported (compressed).
Result<cv::FileStorage> open_file_storage(const std::filesystem::path& path);

// The same on a file's content (`where` names it in the messages).
Result<cv::FileStorage> parse_file_storage(std::string_view content, std::string_view where);

}  // namespace dreamsense
