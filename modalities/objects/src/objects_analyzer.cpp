// The objects Analyzer adapter (see the header).

#include "dreamsense/objects/objects_analyzer.hpp"

#include "dreamsense/core/log.hpp"

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
  return objects.check();
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
  c.writes = {kTableObjectsKey.name};
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
  TableObjects value{std::move(*states), table_, o_.camera};
  out.set(kTableObjectsKey, std::move(value), f->stamp, 1.f);
  return ok_status();
}

}  // namespace dreamsense::objects
