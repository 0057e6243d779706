#pragma once
// Declared pipeline: every analyser library registers a factory that plans its analyser(s) from
// the session's streams (by role), the session's metadata, the child's calibration files and its
// own options (pipeline.yaml / command-line overrides). The runner builds the graph from these
// factories and orders the analysers by their contracts' reads and writes; it holds no
// per-analyser code. Adding an analyser = its folder + one `ds_add_analyzer(<name>)` line in
// modalities/CMakeLists.txt (docs/architecture.md, "Adding an analyser").

#include "dreamsense/core/analyzer.hpp"
#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/perception/options_node.hpp"

#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace dreamsense {

// Stream roles (session.yaml `role:`; docs/session_format.md). A stream without a declared role
// gets one from today's id conventions (sources::stream_roles).
namespace roles {
inline constexpr const char* kChildCamera = "child_camera";  // colour, any number: faces
inline constexpr const char* kTableCamera = "table_camera";  // colour, exclusive: toys
inline constexpr const char* kTableDepth = "table_depth";    // depth, exclusive: toys
inline constexpr const char* kBody = "body";                 // skeleton, exclusive
inline constexpr const char* kMicArray = "mic_array";        // audio, exclusive
inline constexpr const char* kRobotAudio = "robot_audio";    // audio, exclusive: the robot's voice
}  // namespace roles

// One stream of the session (or live capture) as a factory sees it.
struct StreamDescription {
  SensorId id;
  SensorKind kind = SensorKind::kColor;
  std::vector<std::string> roles;
  double rate_hz = 0;
  int width = 0, height = 0;
  int sample_rate = 0, channels = 0;
  std::filesystem::path calibration_file;  // absolute; empty when the stream has none
  // The stream's camera model when its calibration file is one (colour, depth, skeleton: the
  // skeleton's sensor pose). Absent for audio streams (their file is a microphone array).
  std::optional<CameraModel> camera;
  // True when `camera` holds assumed intrinsics (a plain video without calibration): 3-D
  // results from it are approximate and flagged so in every output.
  bool approximate_calibration = false;
  bool has_role(std::string_view role) const;
};

// The child's calibration files in effect (empty path = none): the subject folder's
// face_model.yaml, gaze.yaml and speech_model/, or files given explicitly.
struct SubjectFiles {
  std::string subject_id;  // the session's `subject` metadata, if any
  std::filesystem::path folder;
  std::filesystem::path face_model, gaze_model, speech_model;
};

struct PlanContext {
  std::vector<StreamDescription> streams;  // manifest order
  std::map<std::string, std::string> metadata;
  std::filesystem::path session_dir;    // manifest file references are relative to it
  std::filesystem::path manifest_path;  // for error messages ("<dir>/session.yaml")
  SubjectFiles subject;
  double frame_rate = 25.0;  // the tick rate
  // Live capture: the manifest comes from the operator's own configuration, whose file
  // references are absolute paths; a recorded session's must stay inside the session folder.
  bool absolute_paths_allowed = false;
  // Privacy (docs/outputs.md "Names"): false (the default) = analysers write ids only
  // (pseudonymous or role ids: speaker_1, child, a gallery's numeric id) to the blackboard and
  // their notes; true (`--include-names`) = also the names of enrolment folders and galleries.
  bool include_names = false;
  // The analysis runs in real time (`dreamsense live`, `analyze --policy live`, bench's live run):
  // ticks that take too long drop frames, so an analyser may move bursty work off the tick
  // (its reports then depend on timing). false: a replay, reproducible to the bit.
  bool live = false;

  std::vector<const StreamDescription*> with_role(std::string_view role) const;
  const StreamDescription* first_with_role(std::string_view role) const;
  // The camera models of the streams with `role` that have one (keyed by stream id).
  std::map<SensorId, CameraModel> cameras_with_role(std::string_view role) const;
  // The session-relative file named by metadata `key`, resolved inside the session folder
  // (nullopt when the metadata has no such key; an error when it leaves the session).
  Result<std::optional<std::filesystem::path>> metadata_file(std::string_view key) const;
};

// What a factory planned for this session.
struct PlannedAnalyzers {
  std::vector<std::unique_ptr<Analyzer>> analyzers;
  // Why nothing was planned (e.g. "no stream with role mic_array"); empty when planned.
  std::string skipped;
  // One-line facts about the plan worth showing (model files, assumed geometry, ...).
  std::vector<std::string> notes;
  static PlannedAnalyzers skip(std::string why) {
    PlannedAnalyzers p;
    p.skipped = std::move(why);
    return p;
  }
};

struct AnalyzerFactory {
  std::string name;                // unique; the pipeline.yaml key (e.g. "face_detection")
  std::string summary;             // one line: method and what it produces
  std::vector<std::string> roles;  // stream roles it consumes (documentation, --print-pipeline)
  bool enabled_by_default = true;
  // Its plan depends on the child's face model or gaze constants (SubjectFiles::face_model,
  // gaze_model): a live analysis plans it again when its self-calibration finds them.
  bool uses_subject_models = false;
  // Plans the analyser(s) for a session, reading its options from `options` (unknown keys are
  // reported by the runner after planning). A bad option or file is an error.
  std::function<Result<PlannedAnalyzers>(const PlanContext&, OptionsNode&)> plan;
};

class AnalyzerRegistry {
 public:
  // A second factory with the same name is a programmer error (CheckFailure).
  void add(AnalyzerFactory factory);
  const std::vector<AnalyzerFactory>& factories() const { return factories_; }
  const AnalyzerFactory* find(std::string_view name) const;

 private:
  std::vector<AnalyzerFactory> factories_;
};

// Every analyser library built into this executable, in registration order (generated from
// modalities/CMakeLists.txt).
const AnalyzerRegistry& builtin_analyzers();

}  // namespace dreamsense
