// Table-top toys of a session against its truth (see the header).

#include "dreamsense/eval/objects_session_eval.hpp"

#include "dreamsense/objects/table_geometry.hpp"
#include "dreamsense/objects/tracker.hpp"
#include "dreamsense/sources/session.hpp"
#include "dreamsense/sources/truth.hpp"

#include <algorithm>
#include <chrono>
#include <map>
#include <numeric>
#include <time.h>

namespace dreamsense::eval {
namespace fs = std::filesystem;
namespace {

// CPU time of the calling thread (ms): the pipeline's own cost, whatever else the machine runs.
double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

}  // namespace

Status ObjectsSessionEvalOptions::check() const {
  if (session.empty()) return make_error(ErrorCode::kInvalidArgument, "eval objects: no session");
  if (gallery.empty())
    return make_error(ErrorCode::kInvalidArgument, "eval objects: no object gallery (--gallery)");
  if (identifier != "gallery" && identifier != "hog_svm")
    return make_error(ErrorCode::kInvalidArgument,
                      "eval objects: identifier must be gallery or hog_svm (got '{}')", identifier);
  if (max_frames < 0)
    return make_error(ErrorCode::kInvalidArgument, "eval objects: max_frames < 0");
  return objects.check();
}

Result<geometry::Plane> session_table_plane(const fs::path& session,
                                            const std::optional<fs::path>& table) {
  if (table) {
    auto t = geometry::read_table_frame(*table);
    if (!t) return tl::unexpected(t.error());
    return t->plane;
  }
  auto manifest = sources::read_manifest(session);
  if (!manifest) return tl::unexpected(manifest.error());
  const sources::StreamEntry* depth = manifest->find("top.depth");
  if (!depth) depth = manifest->find("front.depth");
  if (!depth || depth->kind != SensorKind::kDepth)
    return make_error(ErrorCode::kNotFound,
                      "{}: no table calibration given and no depth stream (top.depth or "
                      "front.depth) to find the table plane in",
                      session.string());
  if (depth->calibration.empty())
    return make_error(ErrorCode::kNotFound, "{}: depth stream {} has no calibration",
                      session.string(), depth->id);
  auto cam = read_camera_model(session / depth->calibration);
  if (!cam) return tl::unexpected(cam.error());
  sources::SessionReaderOptions ro;
  ro.only = {depth->id};
  ro.decode_threads = 0;
  auto reader = sources::SessionReader::open(session, ro);
  if (!reader) return tl::unexpected(reader.error());
  auto frame = (*reader)->next();
  if (!frame) return tl::unexpected(frame.error());
  const DepthImage* d = (*frame)->as<DepthImage>();
  if (!d)
    return make_error(ErrorCode::kCorruptData, "{}: {} is not depth", session.string(), depth->id);
  objects::TablePlaneFitOptions fo;
  // A front sensor looks across the table: the table's normal is its "up" (-y of the camera).
  if (depth->id != "top.depth") fo.up_prior = cam->R.t() * cv::Vec3d(0, -1, 0);
  auto fit = objects::fit_table_plane_from_depth(d->depth_mm, *cam, fo);
  if (!fit)
    return make_error(fit.error().code, "{}: {}: {}", session.string(), depth->id,
                      fit.error().message);
  return fit->plane;
}

Result<EvalReport> run_objects_session_eval(const ObjectsSessionEvalOptions& o,
                                            const std::function<void(double)>& progress) {
  if (auto s = o.check(); !s) return tl::unexpected(s.error());
  auto manifest = sources::read_manifest(o.session);
  if (!manifest) return tl::unexpected(manifest.error());
  const sources::StreamEntry* top = manifest->find(o.camera);
  if (!top || top->kind != SensorKind::kColor)
    return make_error(ErrorCode::kNotFound, "{}: no colour stream '{}'", o.session.string(),
                      o.camera);
  if (manifest->truth.empty())
    return make_error(ErrorCode::kNotFound, "{}: no truth.jsonl (eval objects needs ground truth)",
                      o.session.string());
  std::optional<CameraModel> camera;
  if (!top->calibration.empty()) {
    auto c = read_camera_model(o.session / top->calibration);
    if (!c) return tl::unexpected(c.error());
    camera = *c;
  }
  auto plane = session_table_plane(o.session, o.table);
  if (!plane) return tl::unexpected(plane.error());
  auto gallery = objects::ObjectGallery::load(o.gallery);
  if (!gallery) return tl::unexpected(gallery.error());
  if (o.unknown) {
    auto reduced = gallery->without(*o.unknown);
    if (!reduced) return tl::unexpected(reduced.error());
    gallery = std::move(reduced);
  }
  auto shared = std::make_shared<const objects::ObjectGallery>(std::move(*gallery));
  objects::TableTopObjectsOptions oo = o.objects;
  oo.identifier = o.identifier;
  auto pipeline = objects::TableTopObjects::create(oo, shared, camera, *plane);
  if (!pipeline) return tl::unexpected(pipeline.error());

  // Truth toys per stamp.
  auto truth = sources::read_truth(o.session / manifest->truth);
  if (!truth) return tl::unexpected(truth.error());
  struct TruthToy {
    int id;
    cv::Rect2d box;
    cv::Vec3d position;
  };
  std::map<int64_t, std::vector<TruthToy>> toys;
  for (const auto& r : *truth) {
    if (r.value("type", "") != "object") continue;
    const auto& b = r.at("top_box");
    const auto& p = r.at("position_m");
    toys[r.at("stamp_ns").get<int64_t>()].push_back(
        {r.at("label").get<int>(), cv::Rect2d(b[0], b[1], b[2], b[3]),
         cv::Vec3d(p[0].get<double>(), p[1].get<double>(), p[2].get<double>())});
  }
  if (toys.empty())
    return make_error(ErrorCode::kNotFound, "{}: truth has no object records", o.session.string());

  sources::SessionReaderOptions ro;
  ro.only = {o.camera};
  auto reader = sources::SessionReader::open(o.session, ro);
  if (!reader) return tl::unexpected(reader.error());
  std::vector<double> ious, position_errors, ms, cpu_ms;
  size_t pairs = 0, matched = 0, correct = 0, frames = 0, unknown_pairs = 0, rejected = 0;
  size_t truth_frames = 0, extra_objects = 0;
  std::map<int, std::pair<size_t, size_t>> per_class;  // id -> (pairs, correct)
  const double total = static_cast<double>(top->rate_hz > 0 ? top->rate_hz * 20 : 600);
  for (;;) {
    auto f = (*reader)->next();
    if (!f) {
      if (f.error().code == ErrorCode::kEndOfStream) break;
      return tl::unexpected(f.error());
    }
    const ColorImage* img = (*f)->as<ColorImage>();
    if (!img) continue;
    const auto t0 = std::chrono::steady_clock::now();
    const double c0 = thread_cpu_ms();
    auto states = (*pipeline)->process(img->image, (*f)->stamp.ns());
    cpu_ms.push_back(thread_cpu_ms() - c0);
    ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    if (!states) return tl::unexpected(states.error());
    ++frames;
    if (progress) progress(std::min(1.0, static_cast<double>(frames) / total));
    const auto it = toys.find((*f)->stamp.ns());
    if (it != toys.end()) {
      ++truth_frames;
      std::vector<char> used(states->size(), 0);
      for (const auto& t : it->second) {
        const bool is_unknown = o.unknown && t.id == *o.unknown;
        if (is_unknown)
          ++unknown_pairs;
        else
          ++pairs;
        double best = 0;
        int k_best = -1;
        for (size_t k = 0; k < states->size(); ++k) {
          if (used[k]) continue;
          const double v = objects::iou((*states)[k].box, t.box);
          if (v > best) best = v, k_best = static_cast<int>(k);
        }
        if (is_unknown) {
          if (k_best < 0 || (*states)[static_cast<size_t>(k_best)].id == objects::kUnknownObject)
            ++rejected;
          if (k_best >= 0) used[static_cast<size_t>(k_best)] = 1;
          continue;
        }
        ious.push_back(best);
        auto& pc = per_class[t.id];
        ++pc.first;
        if (k_best < 0) continue;
        used[static_cast<size_t>(k_best)] = 1;
        const auto& s = (*states)[static_cast<size_t>(k_best)];
        ++matched;
        if (s.id == t.id) ++correct, ++pc.second;
        if (s.position_m) position_errors.push_back(cv::norm(*s.position_m - t.position));
      }
      extra_objects += static_cast<size_t>(std::count(used.begin(), used.end(), 0));
    }
    if (o.max_frames > 0 && static_cast<int>(frames) >= o.max_frames) break;
  }
  auto median = [](std::vector<double> v) -> nlohmann::json {
    if (v.empty()) return nullptr;
    std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  EvalReport r;
  r.task = "objects";
  r.dataset = "session";
  r.items = pairs;
  r.protocol =
      "top-camera frames of a session with truth: per frame and truth toy the output box with "
      "the largest IoU is its match; mean IoU over all pairs (0 when unmatched), median 3-D "
      "error over matched pairs, identification = matched with the true id over all pairs";
  r.metrics["object_track_mean_iou"] =
      ious.empty()
          ? 0.0
          : std::accumulate(ious.begin(), ious.end(), 0.0) / static_cast<double>(ious.size());
  r.metrics["object_position_median_m"] = median(position_errors);
  r.metrics["object_identification_accuracy"] = pairs ? static_cast<double>(correct) / pairs : 0.0;
  r.metrics["detection_recall"] = pairs ? static_cast<double>(matched) / pairs : 0.0;
  // Reported objects that match no truth toy (hands taken for toys, split blobs), per frame.
  r.metrics["false_objects_per_frame"] =
      truth_frames ? static_cast<double>(extra_objects) / truth_frames : 0.0;
  r.metrics["identifier"] = o.identifier;
  if (o.unknown) {
    r.metrics["unknown_toy"] = *o.unknown;
    r.metrics["unknown_reject_rate"] =
        unknown_pairs ? static_cast<double>(rejected) / unknown_pairs : 0.0;
  }
  r.timing["ms_per_frame_median"] = median(ms);
  r.timing["ms_per_frame_mean"] =
      ms.empty() ? 0.0
                 : std::accumulate(ms.begin(), ms.end(), 0.0) / static_cast<double>(ms.size());
  r.timing["cpu_ms_per_frame_median"] = median(cpu_ms);
  r.timing["cpu_ms_per_frame_mean"] =
      cpu_ms.empty()
          ? 0.0
          : std::accumulate(cpu_ms.begin(), cpu_ms.end(), 0.0) / static_cast<double>(cpu_ms.size());
  r.timing["frames"] = frames;
  for (const auto& [id, pc] : per_class) {
    std::string name = std::to_string(id);
    if (const auto* c = shared->find(id)) name = c->label;
    r.per_class[name] = {
        {"pairs", pc.first},
        {"identification_accuracy", pc.first ? static_cast<double>(pc.second) / pc.first : 0.0}};
  }
  r.extra["session"] = o.session.string();
  r.extra["table_plane"] = {{"normal", {plane->normal[0], plane->normal[1], plane->normal[2]}},
                            {"offset", plane->offset}};
  return r;
}

}  // namespace dreamsense::eval
