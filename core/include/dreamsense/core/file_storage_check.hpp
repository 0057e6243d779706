#pragma once
// A check every reader of a user's OpenCV FileStorage file (YAML, XML, JSON) runs before it hands
// the file to cv::FileStorage (issue 18, fuzz/README.md finding 4): Debian's OpenCV 4.6 XML reader
// dereferences null on some malformed files (a tag cut inside an attribute, a NUL byte), which
// ends the program instead of raising an error. So a file OpenCV would parse as XML (it starts,
// after an optional UTF-8 byte-order mark, with "<?xml") must first be well-formed XML (tinyxml2),
// and no FileStorage file may contain a NUL byte (a text format never does; OpenCV's line reader
// stops at one and then misreads the rest). Compressed files (".gz", which OpenCV inflates before
// parsing) are refused: their content cannot be checked here.

#include "dreamsense/core/status.hpp"

#include <filesystem>
#include <string_view>

namespace dreamsense {

// Ok when `path` is safe to open with cv::FileStorage; otherwise one line naming the file (and
// the line of an XML error): kIoError (cannot be read), kCorruptData (NUL byte, malformed XML),
// kUnsupported (compressed).
Status check_file_storage_input(const std::filesystem::path& path);

// The same check on a file's content (`where` names it in the message).
Status check_file_storage_text(std::string_view content, std::string_view where);

}  // namespace dreamsense
