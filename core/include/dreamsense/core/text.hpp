#pragma once
// Text checks for user-supplied files: JSON outputs require UTF-8, so text fields are validated
// where they are read (naming the file and line), not where an output writer would throw.

#include <cstddef>
#include <optional>
#include <string_view>

namespace dreamsense {

// The byte offset of the first byte that is not part of a well-formed UTF-8 sequence (overlong
// forms, surrogates and code points above U+10FFFF count as malformed); nullopt when all is valid.
std::optional<size_t> find_invalid_utf8(std::string_view text);

// 1-based line number of byte `offset` in `text`.
size_t line_of_offset(std::string_view text, size_t offset);

}  // namespace dreamsense
