// Declared pipeline entry of the objects analyser (perception/analyzer_registry.hpp): the toys on
// the table seen by the stream with role table_camera, on the table plane of the desk calibration
// (V19) or, without one, of a depth stream's first frame.

#include "dreamsense/core/log.hpp"
#include "dreamsense/geometry/plane.hpp"
#include "dreamsense/objects/identification.hpp"
#include "dreamsense/objects/objects_analyzer.hpp"
#include "dreamsense/objects/table_geometry.hpp"
#include "dreamsense/perception/analyzer_registry.hpp"
#include "dreamsense/sources/session.hpp"

#include <fmt/format.h>

#include <cmath>

namespace dreamsense::objects {
namespace fs = std::filesystem;
namespace {

// The metadata key naming a session's desk calibration (`calibrate desk` output).
constexpr const char* kTableCalibrationKey = "table_calibration";

std::string describe(const geometry::Plane& p) {
  return fmt::format("normal ({:.3f}, {:.3f}, {:.3f}), offset {:.3f} m", p.normal[0], p.normal[1],
                     p.normal[2], p.offset);
}

// The first frame of a recorded depth stream (nullopt: the session has no recording of it, e.g.
// live capture; the analyser then fits the plane to the first frame it receives).
Result<std::optional<cv::Mat>> first_depth_frame(const PlanContext& ctx, const SensorId& id) {
  std::error_code ec;
  if (ctx.absolute_paths_allowed || ctx.session_dir.empty() || !fs::exists(ctx.manifest_path, ec))
    return std::optional<cv::Mat>{};
  sources::SessionReaderOptions ro;
  ro.only = {id};
  ro.decode_threads = 0;
  DS_ASSIGN_OR_RETURN(auto reader, sources::SessionReader::open(ctx.session_dir, ro));
  auto frame = reader->next();
  if (!frame) {
    if (frame.error().code == ErrorCode::kEndOfStream) return std::optional<cv::Mat>{};
    return tl::unexpected(frame.error());
  }
  const DepthImage* d = (*frame)->as<DepthImage>();
  if (d == nullptr)
    return make_error(ErrorCode::kCorruptData, "{}: stream {} is not depth",
                      ctx.manifest_path.string(), id);
  return std::optional<cv::Mat>{d->depth_mm};
}

// The depth stream the table plane is fitted to: the table_depth stream (looking down on the
// table), else `wanted` (option plane_depth), else the first calibrated depth stream (a front
// sensor looking across the table). nullptr: none.
const StreamDescription* plane_depth_stream(const PlanContext& ctx, const std::string& wanted) {
  auto calibrated_depth = [](const StreamDescription& s) {
    return s.kind == SensorKind::kDepth && s.camera.has_value();
  };
  if (const auto* s = ctx.first_with_role(roles::kTableDepth); s && calibrated_depth(*s)) return s;
  for (const auto& s : ctx.streams)
    if (calibrated_depth(s) && (wanted.empty() || s.id == wanted)) return &s;
  return nullptr;
}

Result<PlannedAnalyzers> plan(const PlanContext& ctx, OptionsNode& options) {
  ObjectsAnalyzerOptions o;
  fs::path gallery_path = default_gallery_path();
  fs::path table_file;
  std::string plane_depth;
  DS_RETURN_IF_ERROR(options.get("gallery", gallery_path));
  DS_RETURN_IF_ERROR(options.get("identifier", o.objects.identifier));
  DS_RETURN_IF_ERROR(options.get("table", table_file));
  DS_RETURN_IF_ERROR(options.get("plane_depth", plane_depth));
  DS_RETURN_IF_ERROR(options.get("max_missing_frames", o.objects.max_missing_frames));
  DS_RETURN_IF_ERROR(options.get("visual_tracker", o.objects.visual_tracker));
  DS_RETURN_IF_ERROR(options.get("trajectory_s", o.trajectory_s));
  OptionsNode& grip = options.child("grip");
  DS_RETURN_IF_ERROR(grip.get("max_opening_m", o.grip.max_opening_m));
  DS_RETURN_IF_ERROR(grip.get("clearance_m", o.grip.clearance_m));
  if (o.objects.identifier != "gallery" && o.objects.identifier != "hog_svm")
    return make_error(ErrorCode::kInvalidArgument,
                      "{}.identifier: '{}' is unknown (gallery, hog_svm)", options.where(),
                      o.objects.identifier);

  const StreamDescription* top = ctx.first_with_role(roles::kTableCamera);
  if (top == nullptr) return PlannedAnalyzers::skip("no stream with role table_camera");
  if (!top->camera)
    return PlannedAnalyzers::skip(fmt::format(
        "table_camera stream {} has no calibration (positions on the table need it)", top->id));
  PlannedAnalyzers p;
  o.camera = top->id;
  o.camera_model = *top->camera;
  if (top->approximate_calibration)
    p.notes.push_back(fmt::format("{} has assumed intrinsics: positions are approximate", top->id));

  // The table plane (V19): the desk calibration, else fitted to a depth stream.
  std::optional<fs::path> desk;
  if (!table_file.empty()) {
    desk = table_file;
  } else {
    DS_ASSIGN_OR_RETURN(desk, ctx.metadata_file(kTableCalibrationKey));
  }
  if (desk) {
    DS_ASSIGN_OR_RETURN(const geometry::TableFrame tf, geometry::read_table_frame(*desk));
    o.table = tf.plane;
    p.notes.push_back(fmt::format("table plane from the desk calibration {}: {}", desk->string(),
                                  describe(tf.plane)));
  } else {
    const StreamDescription* depth = plane_depth_stream(ctx, plane_depth);
    if (depth == nullptr)
      return PlannedAnalyzers::skip(
          plane_depth.empty()
              ? "no table plane: no desk calibration (option table, metadata table_calibration) "
                "and no calibrated depth stream to fit it to"
              : fmt::format("no table plane: no calibrated depth stream '{}' (option "
                            "plane_depth) and no desk calibration",
                            plane_depth));
    TablePlaneFitOptions fo;
    // A sensor that does not look down on the table (the front one) sees it below its
    // optical axis: the table's normal is the camera's "up" (-y).
    if (!depth->has_role(roles::kTableDepth))
      fo.up_prior = depth->camera->R.t() * cv::Vec3d(0, -1, 0);
    DS_ASSIGN_OR_RETURN(const auto frame, first_depth_frame(ctx, depth->id));
    if (frame) {
      auto fit = fit_table_plane_from_depth(*frame, *depth->camera, fo);
      if (!fit)
        return PlannedAnalyzers::skip(fmt::format("no table plane in the first frame of {}: {}",
                                                  depth->id, fit.error().message));
      o.table = fit->plane;
      p.notes.push_back(
          fmt::format("table plane fitted to the first frame of {} ({} inliers, rms {:.1f} mm): {}",
                      depth->id, fit->inliers, fit->rms_m * 1e3, describe(fit->plane)));
    } else {
      o.depth = depth->id;
      o.depth_model = *depth->camera;
      o.depth_up = fo.up_prior;
      p.notes.push_back(
          fmt::format("table plane: fitted to the first frame of {} when it arrives", depth->id));
    }
  }

  DS_ASSIGN_OR_RETURN(ObjectGallery gallery, ObjectGallery::load(gallery_path));
  std::string labels;
  for (const auto& c : gallery.classes())
    labels += fmt::format("{}{} {}", labels.empty() ? "" : ", ", c.id, c.label);
  p.notes.push_back(fmt::format("object gallery {} ({})", gallery_path.string(), labels));
  DS_ASSIGN_OR_RETURN(
      auto analyzer,
      ObjectsAnalyzer::create(o, std::make_shared<const ObjectGallery>(std::move(gallery))));
  p.analyzers.push_back(std::move(analyzer));
  return p;
}

}  // namespace

void register_analyzers(AnalyzerRegistry& registry) {
  AnalyzerFactory f;
  f.name = "objects";
  f.summary =
      "toys on the table: table-top detection against a learnt background, identification "
      "(colour + fHOG gallery with rejection), tracks (dreamsense tracker), 3-D on the table plane";
  f.roles = {roles::kTableCamera, roles::kTableDepth};
  f.plan = plan;
  registry.add(std::move(f));
}

}  // namespace dreamsense::objects
