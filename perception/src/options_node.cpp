#include "dreamsense/perception/options_node.hpp"

#include <fmt/format.h>

#include <cmath>
#include <sstream>

namespace dreamsense {
namespace {

std::string show(const YAML::Node& n) {
  YAML::Emitter e;
  e.SetMapFormat(YAML::Flow);
  e.SetSeqFormat(YAML::Flow);
  e << n;
  return e.c_str();
}

template <typename T>
bool scalar_as(const YAML::Node& n, T& out) {
  if (!n.IsScalar()) return false;
  try {
    out = n.as<T>();
    return true;
  } catch (const YAML::Exception&) {
    return false;
  }
}

// yaml-cpp nodes are handles and assigning to an existing handle re-binds the node it refers to:
// descend with fresh handles (passed by value), creating maps on the way.
void set_path(YAML::Node node, const std::vector<std::string>& parts, size_t i,
              const YAML::Node& value) {
  if (i + 1 == parts.size()) {
    node[parts[i]] = value;
    return;
  }
  if (!node[parts[i]].IsMap()) node[parts[i]] = YAML::Node(YAML::NodeType::Map);
  set_path(node[parts[i]], parts, i + 1, value);
}

}  // namespace

OptionsNode::OptionsNode(std::string where, YAML::Node node)
    : where_(std::move(where)), node_(node) {  // YAML::Node has no move constructor
  if (!node_ || node_.IsNull()) node_ = YAML::Node(YAML::NodeType::Map);
}

bool OptionsNode::has(std::string_view key) const {
  return node_.IsMap() && node_[std::string(key)].IsDefined() && !node_[std::string(key)].IsNull();
}

Error OptionsNode::type_error(std::string_view key, std::string_view expected) const {
  return Error{ErrorCode::kInvalidArgument, fmt::format("{}.{}: expected {}, got '{}'", where_, key,
                                                        expected, show(node_[std::string(key)]))};
}

void OptionsNode::record(std::string_view key, std::string value) {
  read_.insert(std::string(key));
  effective_.emplace_back(std::string(key), std::move(value));
}

template <>
Status OptionsNode::get<bool>(std::string_view key, bool& value) {
  if (has(key) && !scalar_as(node_[std::string(key)], value))
    return tl::unexpected(type_error(key, "true or false"));
  record(key, value ? "true" : "false");
  return ok_status();
}

template <>
Status OptionsNode::get<int>(std::string_view key, int& value) {
  if (has(key) && !scalar_as(node_[std::string(key)], value))
    return tl::unexpected(type_error(key, "an integer"));
  record(key, std::to_string(value));
  return ok_status();
}

template <>
Status OptionsNode::get<double>(std::string_view key, double& value) {
  if (has(key) && (!scalar_as(node_[std::string(key)], value) || !std::isfinite(value)))
    return tl::unexpected(type_error(key, "a finite number"));
  record(key, fmt::format("{}", value));
  return ok_status();
}

template <>
Status OptionsNode::get<std::string>(std::string_view key, std::string& value) {
  if (has(key) && !scalar_as(node_[std::string(key)], value))
    return tl::unexpected(type_error(key, "a string"));
  record(key, value);
  return ok_status();
}

template <>
Status OptionsNode::get<std::filesystem::path>(std::string_view key, std::filesystem::path& value) {
  if (has(key)) {
    std::string s;
    if (!scalar_as(node_[std::string(key)], s) || s.empty())
      return tl::unexpected(type_error(key, "a file path"));
    value = s;
    if (value.is_relative() && !base_dir_.empty()) value = base_dir_ / value;
  }
  record(key, value.string());
  return ok_status();
}

template <>
Status OptionsNode::get<cv::Vec3d>(std::string_view key, cv::Vec3d& value) {
  if (has(key)) {
    const YAML::Node n = node_[std::string(key)];
    if (!n.IsSequence() || n.size() != 3) return tl::unexpected(type_error(key, "[x, y, z]"));
    cv::Vec3d v;
    for (int i = 0; i < 3; ++i)
      if (!scalar_as(n[i], v[i]) || !std::isfinite(v[i]))
        return tl::unexpected(type_error(key, "[x, y, z] (finite numbers)"));
    value = v;
  }
  record(key, fmt::format("[{}, {}, {}]", value[0], value[1], value[2]));
  return ok_status();
}

template <>
Status OptionsNode::get<std::vector<std::string>>(std::string_view key,
                                                  std::vector<std::string>& value) {
  if (has(key)) {
    const YAML::Node n = node_[std::string(key)];
    std::vector<std::string> v;
    if (n.IsScalar()) {
      v.push_back(n.as<std::string>());
    } else if (n.IsSequence()) {
      for (const auto& e : n) {
        std::string s;
        if (!scalar_as(e, s)) return tl::unexpected(type_error(key, "a list of strings"));
        v.push_back(s);
      }
    } else {
      return tl::unexpected(type_error(key, "a list of strings"));
    }
    value = v;
  }
  std::string shown;
  for (const auto& s : value) shown += (shown.empty() ? "" : ", ") + s;
  record(key, "[" + shown + "]");
  return ok_status();
}

OptionsNode& OptionsNode::child(std::string_view key) {
  auto it = children_.find(key);
  if (it != children_.end()) return *it->second;
  read_.insert(std::string(key));
  YAML::Node n = has(key) ? node_[std::string(key)] : YAML::Node(YAML::NodeType::Map);
  auto c = std::make_unique<OptionsNode>(fmt::format("{}.{}", where_, key), n);
  c->set_base_dir(base_dir_);
  return *children_.emplace(std::string(key), std::move(c)).first->second;
}

Status OptionsNode::set(std::string_view dotted_key, const std::string& yaml_value) {
  YAML::Node value;
  try {
    value = YAML::Load(yaml_value);
  } catch (const YAML::Exception& e) {
    return make_error(ErrorCode::kInvalidArgument, "{}.{}: cannot parse '{}'", where_, dotted_key,
                      yaml_value);
  }
  std::vector<std::string> parts;
  std::string part;
  std::istringstream in{std::string(dotted_key)};
  while (std::getline(in, part, '.'))
    if (!part.empty()) parts.push_back(part);
  if (parts.empty())
    return make_error(ErrorCode::kInvalidArgument, "{}: empty option name", where_);
  if (!node_.IsMap()) node_ = YAML::Node(YAML::NodeType::Map);
  set_path(node_, parts, 0, value);
  return ok_status();
}

std::vector<std::string> OptionsNode::unread_keys() const {
  std::vector<std::string> out;
  if (!node_.IsMap()) return out;
  for (const auto& kv : node_) {
    // A list or map as a key (`? [a, b]: 1`) names no option: reported as unread, in YAML's
    // flow form, instead of the BadConversion that as<std::string>() throws (fuzz finding 6).
    if (!kv.first.IsScalar()) {
      YAML::Emitter flow;
      flow << YAML::Flow << kv.first;
      out.emplace_back(flow.c_str());
      continue;
    }
    const std::string k = kv.first.Scalar();
    if (read_.count(k) == 0) {
      out.push_back(k);
      continue;
    }
    if (auto it = children_.find(k); it != children_.end())
      for (const auto& sub : it->second->unread_keys()) out.push_back(k + "." + sub);
  }
  return out;
}

std::vector<std::pair<std::string, std::string>> OptionsNode::effective() const {
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& [k, v] : effective_) out.emplace_back(k, v);
  for (const auto& [k, c] : children_)
    for (const auto& [sk, sv] : c->effective()) out.emplace_back(k + "." + sk, sv);
  return out;
}

}  // namespace dreamsense
