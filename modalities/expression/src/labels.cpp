#include "dreamsense/expression/labels.hpp"

#include <algorithm>
#include <cctype>
#include <map>

namespace dreamsense::expression {

std::optional<std::string> canonical_label(std::string_view name) {
  std::string s(name);
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  static const std::map<std::string, std::string> kNames = {
      {"anger", "anger"},        {"angry", "anger"},       {"contempt", "contempt"},
      {"disgust", "disgust"},    {"disgusted", "disgust"}, {"fear", "fear"},
      {"fearful", "fear"},       {"happy", "happy"},       {"happiness", "happy"},
      {"sadness", "sadness"},    {"sad", "sadness"},       {"surprise", "surprise"},
      {"surprised", "surprise"}, {"neutral", "neutral"}};
  auto it = kNames.find(s);
  if (it == kNames.end()) return std::nullopt;
  return it->second;
}

int dream_expression_id(std::string_view label) {
  if (label == "happy") return 0;
  if (label == "sadness") return 1;
  if (label == "anger") return 2;
  if (label == "fear") return 3;
  if (label == "neutral") return 4;
  return -1;
}

}  // namespace dreamsense::expression
