// Objects: the toys on the table (getObjects and the other object primitives) against the
// session's truth `object` records (demo sessions: one record per toy and top-camera frame, with
// its top-camera box, the top face centre and the DREAM id as `label`).
//
// Frames: every top-camera frame the analysis looked at (the data_stamp of a getObjects record,
// whatever its status) that has truth toys. Per (frame, truth toy) pair, the reported toy whose
// box overlaps the truth box most (IoU > 0) is its match (the same rule as `eval objects`):
//   object_track_mean_iou          mean IoU over all pairs (0 for a pair without a match)
//   object_position_median_m       median 3-D distance of matched positions to the truth
//   object_identification_accuracy fraction of all pairs whose match carries the true id (the id
//                                  getObjects reports is the one identifyObject answers with)
//   object_false_objects_per_frame reported toys that are no truth toy's match (hands taken for
//                                  toys, split blobs), per frame
//   object_primitives_ok_fraction  over the ticks whose newest top frame has truth toys: the
//                                  smallest, over the six object primitives, fraction of ticks
//                                  answered ok (F14 with the evaluator's default circle counts
//                                  only ticks where a truth toy lies in that circle)

#include "dreamsense/primitives/objects.hpp"

#include "dreamsense/eval/metrics.hpp"
#include "dreamsense/eval/session_metrics.hpp"

#include <opencv2/core.hpp>

#include <map>
#include <optional>
#include <set>

namespace dreamsense::eval {
using primitives::PrimitiveId;
using primitives::PrimitiveStatus;

namespace {

struct TruthToy {
  int id = -1;
  cv::Rect2d box;
  cv::Vec3d position;
};

double iou(const cv::Rect2d& a, const cv::Rect2d& b) {
  const double inter = (a & b).area();
  const double uni = a.area() + b.area() - inter;
  return uni > 0 ? inter / uni : 0.0;
}

}  // namespace

MetricGroup object_metrics() {
  MetricGroup g;
  g.name = "objects";
  g.metrics = {{"object_track_mean_iou", PrimitiveId::kGetObjects},
               {"object_position_median_m", PrimitiveId::kGetObjects},
               {"object_identification_accuracy", PrimitiveId::kIdentifyObject},
               {"object_false_objects_per_frame", PrimitiveId::kGetObjects},
               {"object_primitives_ok_fraction", PrimitiveId::kGetObjects}};
  g.compute = [](const SessionData& d, nlohmann::json& metrics, nlohmann::json& not_evaluated) {
    std::map<int64_t, std::vector<TruthToy>> truth;
    for (const auto* t : d.truth_of("object")) {
      if (!t->contains("top_box") || !t->contains("position_m") || !t->contains("label")) continue;
      const auto& b = (*t)["top_box"];
      truth[t->value("stamp_ns", int64_t{0})].push_back(
          {(*t)["label"].get<int>(),
           cv::Rect2d(b[0].get<double>(), b[1].get<double>(), b[2].get<double>(),
                      b[3].get<double>()),
           truth_vec3((*t)["position_m"])});
    }
    const char* kNoTruth = "the truth has no object records with top_box and position_m";
    if (truth.empty()) {
      for (const char* m :
           {"object_track_mean_iou", "object_position_median_m", "object_identification_accuracy",
            "object_false_objects_per_frame", "object_primitives_ok_fraction"})
        not_evaluated[m] = kNoTruth;
      return;
    }

    // One getObjects answer per top frame the analysis looked at.
    std::map<int64_t, const primitives::ObjectsValue*> seen;
    for (const auto* r : d.of(PrimitiveId::kGetObjects)) {
      if (!r->data_stamp.is_set() || r->status == PrimitiveStatus::kDisabled) continue;
      const auto* v = r->value_as<primitives::ObjectsValue>();
      auto [it, fresh] = seen.emplace(r->data_stamp.ns(), v);
      if (!fresh && v != nullptr) it->second = v;
    }
    std::vector<double> ious, errors;
    size_t pairs = 0, correct = 0, frames = 0, extra = 0;
    for (const auto& [stamp, toys] : truth) {
      auto s = seen.find(stamp);
      if (s == seen.end()) continue;
      ++frames;
      std::set<const primitives::ObjectValue*> matched;
      for (const auto& t : toys) {
        ++pairs;
        const primitives::ObjectValue* best = nullptr;
        double best_iou = 0;
        if (s->second != nullptr)
          for (const auto& o : s->second->objects) {
            const double v = iou(o.box_px, t.box);
            if (v > best_iou) best_iou = v, best = &o;
          }
        ious.push_back(best_iou);
        if (best == nullptr) continue;
        matched.insert(best);
        errors.push_back(cv::norm(best->position_m - t.position));
        if (best->id == t.id) ++correct;
      }
      if (s->second != nullptr) extra += s->second->objects.size() - matched.size();
    }
    if (pairs == 0) {
      for (const char* m : {"object_track_mean_iou", "object_position_median_m",
                            "object_identification_accuracy", "object_false_objects_per_frame"})
        not_evaluated[m] = "no getObjects record is from a top frame the truth describes";
    } else {
      double sum = 0;
      for (double v : ious) sum += v;
      metrics["object_track_mean_iou"] = sum / static_cast<double>(ious.size());
      metrics["object_identification_accuracy"] =
          static_cast<double>(correct) / static_cast<double>(pairs);
      metrics["object_false_objects_per_frame"] =
          static_cast<double>(extra) / static_cast<double>(frames);
      if (auto m = median(errors))
        metrics["object_position_median_m"] = *m;
      else
        not_evaluated["object_position_median_m"] = "no reported toy overlaps a truth toy";
    }

    // The six primitives at the ticks whose newest top frame has truth toys.
    const primitives::CircleQuery circle =
        primitives::ObjectPrimitiveOptions{}.circle;  // F14's default
    const PrimitiveId six[] = {PrimitiveId::kGetGripLocation,  PrimitiveId::kGetObjects,
                               PrimitiveId::kGetObjectsCircle, PrimitiveId::kGetObjectTableDistance,
                               PrimitiveId::kIdentifyObject,   PrimitiveId::kTrackObject};
    // Ticks with truth toys: from getObjects' data stamps (the top frame behind each tick).
    std::map<int64_t, int64_t> tick_frame;  // tick -> top frame
    for (const auto* r : d.of(PrimitiveId::kGetObjects))
      if (r->data_stamp.is_set()) tick_frame[r->stamp.ns()] = r->data_stamp.ns();
    // The table's normal from the truth positions themselves (toys' top faces lie in planes
    // parallel to it): the direction of least spread; none when they do not span a plane.
    std::optional<cv::Vec3d> normal;
    {
      std::vector<cv::Vec3d> all;
      for (const auto& [stamp, toys] : truth)
        for (const auto& t : toys) all.push_back(t.position);
      cv::Mat pts(static_cast<int>(all.size()), 3, CV_64F);
      for (size_t i = 0; i < all.size(); ++i)
        for (int k = 0; k < 3; ++k) pts.at<double>(static_cast<int>(i), k) = all[i][k];
      cv::PCA pca(pts, cv::Mat(), cv::PCA::DATA_AS_ROW);
      if (pca.eigenvalues.rows == 3 && pca.eigenvalues.at<double>(1) > 1e-4)
        normal = cv::Vec3d(pca.eigenvectors.row(2));
    }
    auto in_default_circle = [&](int64_t frame) {
      for (const auto& t : truth.at(frame)) {
        cv::Vec3d v = t.position - circle.centre_m;
        if (normal) v -= v.dot(*normal) * *normal;  // in the table plane, as F14 measures
        if (cv::norm(v) <= circle.radius_m) return true;
      }
      return false;
    };
    double worst = 1.0;
    bool any = false;
    for (PrimitiveId id : six) {
      size_t n = 0, ok = 0;
      for (const auto* r : d.of(id)) {
        auto f = tick_frame.find(r->stamp.ns());
        if (f == tick_frame.end() || truth.count(f->second) == 0) continue;
        if (id == PrimitiveId::kGetObjectsCircle && !in_default_circle(f->second)) continue;
        ++n;
        if (r->ok()) ++ok;
      }
      if (n == 0) continue;
      any = true;
      worst = std::min(worst, static_cast<double>(ok) / static_cast<double>(n));
    }
    if (any)
      metrics["object_primitives_ok_fraction"] = worst;
    else
      not_evaluated["object_primitives_ok_fraction"] =
          "no tick's top frame has truth toys (or getObjects never looked)";
  };
  return g;
}

}  // namespace dreamsense::eval
