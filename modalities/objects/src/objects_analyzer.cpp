// The objects Analyzer adapter (see the header).

#include "dreamsense/objects/objects_analyzer.hpp"

#include "dreamsense/core/log.hpp"

#include <algorithm>

namespace dreamsense::objects {

Status ObjectsAnalyzerOptions::check() const {
  if (camera.empty())
    return make_error(ErrorCode::kInvalidArgument, "objects analyser: no camera stream");
  if (depth && !depth_model)
    return make_error(ErrorCode::kInvalidArgument,
                      "objects analyser: depth stream {} has no calibration", *depth);
  if (camera_model) {
    if (auto s = camera_model->check(); !s) return s;
  }
  if (!(trajectory_s >= 0))
    return make_error(ErrorCode::kInvalidArgument, "objects analyser: trajectory_s must be >= 0");
  DS_RETURN_IF_ERROR(grip.check());
  return objects.check();
}

TableObjects to_table_objects(const std::vector<ObjectState>& states,
                              const std::optional<geometry::Plane>& table,
                              const TableTopObjects& tracks, const ObjectsAnalyzerOptions& o) {
  TableObjects out;
  out.camera = o.camera;
  if (table) out.table = TablePlane{table->normal, table->offset};
  out.objects.reserve(states.size());
  for (const ObjectState& s : states) {
    TableObject t;
    t.track_id = s.track_id;
    t.id = s.id;
    t.label = s.label;
    t.id_score = s.id_score;
    t.stamp = Timestamp::from_ns(s.stamp_ns);
    t.box_px = s.box;
    t.position_m = s.position_m;
    t.axis_m = s.axis_m;
    t.velocity_mps = s.velocity_mps;
    t.size_m = s.size_m;
    t.detected = s.detected;
    t.missing_frames = s.missing_frames;
    if (table && s.position_m) {
      // Heights are measured only when the position came from depth; today it assumes the toy
      // rests on the table (README, "Not done").
      if (auto d = table_distance(s, *table, false)) {
        t.height_m = d->top_m;
        t.lift_m = d->lift_m;
        t.height_measured = d->measured;
      }
      if (auto g = grip_location(s, *table, o.grip))
        t.grip = ObjectGrip{g->point_m, g->approach, g->closing_axis, g->opening_m};
    }
    const auto& history = tracks.history(s.track_id);
    const int64_t since = s.stamp_ns - static_cast<int64_t>(o.trajectory_s * 1e9);
    for (const ObjectState& h : history)
      if (h.stamp_ns >= since && h.position_m)
        t.trajectory.push_back({Timestamp::from_ns(h.stamp_ns), *h.position_m, h.detected});
    out.objects.push_back(std::move(t));
  }
  std::sort(out.objects.begin(), out.objects.end(),
            [](const TableObject& a, const TableObject& b) { return a.track_id < b.track_id; });
  return out;
}

Result<std::unique_ptr<ObjectsAnalyzer>> ObjectsAnalyzer::create(
    ObjectsAnalyzerOptions options, std::shared_ptr<const ObjectGallery> gallery) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  std::unique_ptr<ObjectsAnalyzer> a(new ObjectsAnalyzer());
  a->o_ = std::move(options);
  a->gallery_ = std::move(gallery);
  a->table_ = a->o_.table;
  if (auto s = a->make_pipeline(); !s) return tl::unexpected(s.error());
  return a;
}

Status ObjectsAnalyzer::make_pipeline() {
  auto p = TableTopObjects::create(o_.objects, gallery_, o_.camera_model, table_);
  if (!p) return tl::unexpected(p.error());
  pipeline_ = std::move(*p);
  return ok_status();
}

AnalyzerContract ObjectsAnalyzer::contract() const {
  AnalyzerContract c;
  c.required_inputs = {o_.camera};
  if (o_.depth) c.optional_inputs = {*o_.depth};
  c.writes = {keys::kTableObjects.name};
  return c;
}

void ObjectsAnalyzer::reset() {
  table_ = o_.table;
  plane_failed_ = false;
  (void)make_pipeline();
}

Status ObjectsAnalyzer::process(const MultiFrame& in, const BlackboardView&,
                                BlackboardWriter& out) {
  // The table plane from the first depth frame, once (the tracks start again with it).
  if (!table_ && o_.depth && !plane_failed_) {
    if (FramePtr f = in.frame(*o_.depth)) {
      if (const DepthImage* d = f->as<DepthImage>()) {
        TablePlaneFitOptions fo;
        fo.up_prior = o_.depth_up;
        if (auto fit = fit_table_plane_from_depth(d->depth_mm, *o_.depth_model, fo)) {
          table_ = fit->plane;
          if (auto s = make_pipeline(); !s) return s;
        } else {
          // No table in that depth frame: 2-D boxes only, said once.
          log::warn("objects: no table plane in {}: {}", *o_.depth, fit.error().message);
          plane_failed_ = true;
        }
      }
    }
  }
  FramePtr f = in.frame(o_.camera);
  if (!f) return ok_status();  // no top frame this tick: nothing new to say
  const ColorImage* img = f->as<ColorImage>();
  if (!img)
    return make_error(ErrorCode::kInvalidArgument, "objects: {} is not a colour stream", o_.camera);
  if (img->image.type() != CV_8UC3)
    return make_error(ErrorCode::kInvalidArgument, "objects: {} frames must be BGR", o_.camera);
  auto states = pipeline_->process(img->image, f->stamp.ns());
  if (!states) return tl::unexpected(states.error());
  out.set(keys::kTableObjects, to_table_objects(*states, table_, *pipeline_, o_), f->stamp, 1.f);
  return ok_status();
}

}  // namespace dreamsense::objects
