#include "dreamsense/runner/pipeline_config.hpp"

#include <fmt/format.h>

namespace dreamsense::runner {
namespace {

Error config_error(const std::filesystem::path& file, const std::string& what) {
  return Error{ErrorCode::kInvalidArgument, fmt::format("{}: {}", file.string(), what)};
}

Result<std::vector<std::string>> role_list(const std::filesystem::path& file, const std::string& id,
                                           const YAML::Node& n) {
  std::vector<std::string> out;
  if (n.IsScalar()) {
    out.push_back(n.Scalar());
  } else if (n.IsSequence()) {
    for (const auto& e : n) {
      if (!e.IsScalar())
        return tl::unexpected(
            config_error(file, fmt::format("roles.{}: expected a role name or a list", id)));
      out.push_back(e.Scalar());
    }
  } else {
    return tl::unexpected(
        config_error(file, fmt::format("roles.{}: expected a role name or a list", id)));
  }
  return out;
}

// A key that is not a plain name (`? [a, b]: 1` makes a list the key) is the user's error, not the
// YAML::BadConversion that as<std::string>() throws (fuzz finding 6).
Result<std::string> key_name(const std::filesystem::path& file, const std::string& context,
                             const YAML::Node& key) {
  if (!key.IsScalar())
    return tl::unexpected(
        config_error(file, fmt::format("{}a key must be a name, not a list or a map", context)));
  return key.Scalar();
}

}  // namespace

std::string PipelineConfig::where(const std::string& key) const {
  return fmt::format("{}: {}", file.empty() ? std::string("command line") : file.string(), key);
}

Result<PipelineConfig> PipelineConfig::read(const std::filesystem::path& path) {
  PipelineConfig c;
  c.file = path;
  YAML::Node root;
  try {
    root = YAML::LoadFile(path.string());
  } catch (const YAML::BadFile&) {
    return make_error(ErrorCode::kNotFound, "{}: cannot read the pipeline file", path.string());
  } catch (const YAML::Exception& e) {
    return make_error(ErrorCode::kCorruptData, "{}: line {}: not valid YAML ({})", path.string(),
                      e.mark.line + 1, e.msg);
  }
  if (root.IsNull()) return c;  // an empty file: defaults
  if (!root.IsMap())
    return tl::unexpected(config_error(path, "expected a map with analyzers and/or roles"));
  for (const auto& kv : root) {
    DS_ASSIGN_OR_RETURN(const std::string key, key_name(path, "", kv.first));
    if (key == "version") {
      int v = 0;
      try {
        v = kv.second.as<int>();
      } catch (const YAML::Exception&) {
      }
      if (v != 1) return tl::unexpected(config_error(path, "version: this build reads version 1"));
    } else if (key == "analyzers") {
      if (!kv.second.IsMap())
        return tl::unexpected(config_error(path, "analyzers: expected a map of analyser names"));
      for (const auto& a : kv.second) {
        DS_ASSIGN_OR_RETURN(const std::string name, key_name(path, "analyzers: ", a.first));
        AnalyzerConfig ac;
        const YAML::Node n = a.second;
        if (n.IsScalar()) {
          try {
            ac.enabled = n.as<bool>();
          } catch (const YAML::Exception&) {
            return tl::unexpected(config_error(
                path, fmt::format("analyzers.{}: expected true, false or a map", name)));
          }
        } else if (n.IsMap()) {
          for (const auto& e : n) {
            DS_ASSIGN_OR_RETURN(const std::string k,
                                key_name(path, fmt::format("analyzers.{}: ", name), e.first));
            if (k == "enabled") {
              try {
                ac.enabled = e.second.as<bool>();
              } catch (const YAML::Exception&) {
                return tl::unexpected(config_error(
                    path, fmt::format("analyzers.{}.enabled: expected true or false", name)));
              }
            } else if (k == "options") {
              if (!e.second.IsMap() && !e.second.IsNull())
                return tl::unexpected(
                    config_error(path, fmt::format("analyzers.{}.options: expected a map", name)));
              ac.options = e.second;
            } else {
              return tl::unexpected(config_error(
                  path, fmt::format("analyzers.{}.{}: unknown key (expected enabled, options)",
                                    name, k)));
            }
          }
        } else if (!n.IsNull()) {
          return tl::unexpected(
              config_error(path, fmt::format("analyzers.{}: expected true, false or a map", name)));
        }
        c.analyzers[name] = ac;
      }
    } else if (key == "roles") {
      if (!kv.second.IsMap())
        return tl::unexpected(config_error(path, "roles: expected a map of stream ids"));
      for (const auto& r : kv.second) {
        DS_ASSIGN_OR_RETURN(const std::string id, key_name(path, "roles: ", r.first));
        auto list = role_list(path, id, r.second);
        if (!list) return tl::unexpected(list.error());
        c.roles[id] = *list;
      }
    } else {
      return tl::unexpected(config_error(
          path, fmt::format("{}: unknown key (expected version, analyzers, roles)", key)));
    }
  }
  return c;
}

}  // namespace dreamsense::runner
