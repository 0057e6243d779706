#pragma once
// Expression labels: the seven CK+ classes plus neutral (FER2013 has it, CK+ has not; FER2013
// has no contempt). Dataset spellings (angry, sad, surprise, disgusted, fearful, surprised) map
// onto these names.

#include <optional>
#include <string>
#include <string_view>

namespace dreamsense::expression {

inline constexpr const char* kExpressionLabels[] = {"anger", "contempt", "disgust",  "fear",
                                                    "happy", "sadness",  "surprise", "neutral"};

// The project's label for a dataset's class name (case-insensitive): anger/angry, contempt,
// disgust/disgusted, fear/fearful, happy/happiness, sadness/sad, surprise/surprised, neutral.
std::optional<std::string> canonical_label(std::string_view dataset_name);

// DREAM's legacy identifyFaceExpression id (spec/original-dream.md §2.2 #18, code order):
// 0 happy, 1 sad, 2 angry, 3 fear, 4 neutral, -1 anything else (and no face).
int dream_expression_id(std::string_view label);

}  // namespace dreamsense::expression
