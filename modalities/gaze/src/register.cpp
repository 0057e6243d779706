// Declared pipeline entry of the gaze analyser (perception/analyzer_registry.hpp).

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/gaze/gaze_analyzer.hpp"
#include "dreamsense/perception/analyzer_registry.hpp"

#include <fmt/format.h>

namespace dreamsense::gaze {
namespace {

Status read_mutual_options(OptionsNode& node, MutualGazeOptions& m) {
  std::string mode = m.mode == MutualGazeMode::kCameraPlane ? "camera_plane" : "3d";
  DS_RETURN_IF_ERROR(node.get("mode", mode));
  if (mode != "3d" && mode != "camera_plane")
    return make_error(ErrorCode::kInvalidArgument, "{}.mode: '{}' is unknown (3d, camera_plane)",
                      node.where(), mode);
  m.mode = mode == "camera_plane" ? MutualGazeMode::kCameraPlane : MutualGazeMode::k3d;
  DS_RETURN_IF_ERROR(node.get("radius_m", m.radius_m));
  DS_RETURN_IF_ERROR(node.get("onset_s", m.onset_s));
  DS_RETURN_IF_ERROR(node.get("release_s", m.release_s));
  DS_RETURN_IF_ERROR(node.get("require_visible_pupil", m.require_visible_pupil));
  return ok_status();
}

Status read_fixation_yaw_options(OptionsNode& node, FixationYawOptions& f) {
  DS_RETURN_IF_ERROR(node.get("enabled", f.enabled));
  DS_RETURN_IF_ERROR(node.get("max_yaw_deg", f.max_yaw_deg));
  DS_RETURN_IF_ERROR(node.get("max_pitch_deg", f.max_pitch_deg));
  DS_RETURN_IF_ERROR(node.get("min_fixations", f.min_fixations));
  DS_RETURN_IF_ERROR(node.get("window", f.window));
  DS_RETURN_IF_ERROR(node.get("dead_zone_deg", f.dead_zone_deg));
  DS_RETURN_IF_ERROR(node.get("start_deg", f.start_deg));
  return ok_status();
}

}  // namespace

void register_analyzers(AnalyzerRegistry& registry) {
  AnalyzerFactory f;
  f.name = "gaze";
  f.summary =
      "eye gaze (3-D eyeball model of the child's calibration, else D4.2 eq. 4) and mutual gaze "
      "with the robot (3-D or camera-plane test, hold rule)";
  f.roles = {roles::kChildCamera};
  f.uses_subject_models = true;
  f.plan = [](const PlanContext& ctx, OptionsNode& options) -> Result<PlannedAnalyzers> {
    GazeAnalyzerOptions o;
    OptionsNode& mutual = options.child("mutual");
    DS_RETURN_IF_ERROR(read_mutual_options(mutual, o.mutual));
    DS_RETURN_IF_ERROR(options.get("reference_camera", o.reference_camera));
    o.cameras = ctx.cameras_with_role(roles::kChildCamera);
    if (o.cameras.empty())
      return PlannedAnalyzers::skip("no calibrated stream with role child_camera");
    PlannedAnalyzers p;
    // Gaze constants of the child's calibration (`dreamsense train gaze`), else built in.
    if (!ctx.subject.gaze_model.empty()) {
      DS_ASSIGN_OR_RETURN(const GazeModelFile m, read_gaze_model(ctx.subject.gaze_model));
      o.estimator.plane = m.plane;
      o.estimator.right_eye = m.right_eye;
      o.estimator.left_eye = m.left_eye;
      if (m.right_eyeball && m.left_eyeball) {
        o.estimator.method = GazeMethod::kEyeball;
        o.estimator.right_eyeball = *m.right_eyeball;
        o.estimator.left_eyeball = *m.left_eyeball;
      }
      o.fixation_yaw.enabled = m.fixation_yaw;
      o.fixation_yaw.start_deg = m.fixation_yaw_start_deg;
    }
    DS_RETURN_IF_ERROR(read_fixation_yaw_options(options.child("fixation_yaw"), o.fixation_yaw));
    if (o.fixation_yaw.enabled && o.mutual.mode == MutualGazeMode::k3d)
      p.notes.push_back(
          o.fixation_yaw.start_deg == 0
              ? std::string("the eyes' sideways bias is learnt from fixations on the robot's head")
              : fmt::format("the eyes' sideways bias is learnt from fixations on the robot's "
                            "head, starting from {:+.1f} deg (an earlier session's)",
                            o.fixation_yaw.start_deg));
    p.notes.push_back("gaze constants " + (ctx.subject.gaze_model.empty()
                                               ? std::string("built-in")
                                               : ctx.subject.gaze_model.string()));
    // The robot's head: the option (--robot-head), else the session's robot_head_m metadata.
    if (!mutual.has("robot_head_m")) {
      if (auto it = ctx.metadata.find("robot_head_m"); it != ctx.metadata.end()) {
        auto v = parse_vec3(it->second);
        if (!v)
          return make_error(ErrorCode::kCorruptData,
                            "{}: metadata robot_head_m must be three numbers \"x y z\" in metres "
                            "(got \"{}\")",
                            ctx.manifest_path.string(), it->second);
        o.mutual.robot_head_m = *v;
      } else {
        p.notes.push_back(fmt::format(
            "the session has no robot_head_m metadata: mutual gaze uses ({}, {}, {}) m",
            o.mutual.robot_head_m[0], o.mutual.robot_head_m[1], o.mutual.robot_head_m[2]));
      }
    }
    DS_RETURN_IF_ERROR(mutual.get("robot_head_m", o.mutual.robot_head_m));
    DS_ASSIGN_OR_RETURN(auto analyzer, make_gaze_analyzer(o));
    p.analyzers.push_back(std::move(analyzer));
    return p;
  };
  registry.add(std::move(f));
}

}  // namespace dreamsense::gaze
