#pragma once
// An analyser's options as written in pipeline.yaml (or set on the command line): typed reads
// that keep the given default when a key is absent, one-line errors naming the file and key for a
// wrong type, and a record of every key read with its effective value (shown by
// `analyze --print-pipeline`). Keys nobody read are unknown options: the runner reports them.

#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <string_view>
#include <vector>

namespace dreamsense {

class OptionsNode {
 public:
  // `where` names the node in messages, e.g. "pipeline.yaml: analyzers.gaze.options".
  OptionsNode(std::string where, YAML::Node node);
  OptionsNode() : OptionsNode("options", YAML::Node(YAML::NodeType::Map)) {}

  bool has(std::string_view key) const;
  // Reads `key` into `value` when present (else leaves the default); a value of the wrong type is
  // an error. Supported: bool, int, double, std::string, std::filesystem::path (relative paths
  // are relative to base_dir()), cv::Vec3d ([x, y, z]), std::vector<std::string>.
  template <typename T>
  Status get(std::string_view key, T& value);
  // A nested mapping (an empty one when absent); its reads are recorded under "key.".
  OptionsNode& child(std::string_view key);

  // Sets `key` (a dotted path "a.b.c" creates nested maps) to a YAML scalar/sequence text, e.g.
  // set("mutual.mode", "camera_plane"). Used for command-line overrides.
  Status set(std::string_view dotted_key, const std::string& yaml_value);

  // Keys that were never read (dotted paths), for the "unknown option" error.
  std::vector<std::string> unread_keys() const;
  // Every key read with its effective value (defaults included), dotted paths in read order.
  std::vector<std::pair<std::string, std::string>> effective() const;

  const std::string& where() const { return where_; }
  // Relative paths in options are resolved against this folder (the pipeline.yaml's folder; the
  // current folder for command-line values).
  void set_base_dir(std::filesystem::path dir) { base_dir_ = std::move(dir); }
  const std::filesystem::path& base_dir() const { return base_dir_; }

 private:
  Error type_error(std::string_view key, std::string_view expected) const;
  void record(std::string_view key, std::string value);
  std::string where_;
  YAML::Node node_;
  std::filesystem::path base_dir_;
  std::set<std::string, std::less<>> read_;
  std::vector<std::pair<std::string, std::string>> effective_;
  std::map<std::string, std::unique_ptr<OptionsNode>, std::less<>> children_;
};

}  // namespace dreamsense
