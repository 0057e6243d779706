#pragma once
// pipeline.yaml: which analysers run, with which options, and which stream plays which role
// (docs/pipeline.md). Every key is checked: an unknown analyser, option or stream is a one-line
// error naming the file and the key.
//
//   version: 1
//   analyzers:
//     voice_id: false                    # disable (true: enable)
//     speech:
//       enabled: true
//       options: {grammar: grammars/commands.gram, steer_to_sound_direction: false}
//     gaze:
//       options: {mutual: {mode: camera_plane}}
//   roles:                               # override session.yaml's roles
//     cam1: child_camera
//     ceiling: [table_camera]

#include "dreamsense/core/status.hpp"

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace dreamsense::runner {

struct AnalyzerConfig {
  std::optional<bool> enabled;  // unset: the analyser's default
  YAML::Node options;           // a map (possibly empty)
};

struct PipelineConfig {
  std::filesystem::path file;  // where it was read from (empty: defaults / command line)
  std::map<std::string, AnalyzerConfig> analyzers;
  std::map<std::string, std::vector<std::string>> roles;  // stream id -> roles

  // Reads and checks the file's shape (analyser and option names are checked when planning,
  // against the registered analysers).
  static Result<PipelineConfig> read(const std::filesystem::path& path);
  // Names in messages: "<file>: analyzers.<name>.options" or "command line: ...".
  std::string where(const std::string& key) const;
};

}  // namespace dreamsense::runner
