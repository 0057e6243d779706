#include "dreamsense/eval/session_eval.hpp"

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/sensor_frame.hpp"
#include "dreamsense/eval/metrics.hpp"
#include "dreamsense/sources/session.hpp"
#include "dreamsense/sources/truth.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include "records.hpp"

namespace dreamsense::eval {
namespace fs = std::filesystem;
using nlohmann::json;

Status SessionEvalOptions::check() const {
  if (session_dir.empty() || analysis_dir.empty())
    return make_error(ErrorCode::kInvalidArgument,
                      "eval session: session and analysis folders are required");
  return ok_status();
}

namespace {

// Which primitive each metric needs, so a disabled one is reported as such, not as zero.
const std::map<std::string, std::string> kMetricPrimitive = {
    {"face_recall", "getFaces"},
    {"face_false_positive_rate", "getFaces"},
    {"camera_selection_accuracy", "getFaces"},
    {"head_pose_median_deg", "getHeadGaze"},
    {"gaze_median_deg", "getEyeGaze"},
    {"mutual_gaze_f1", "checkMutualGaze"},
    {"eye_center_median_px", "getEyes"},
    {"doa_mae_deg", "getSoundDirection"},
    {"doa_within_10deg", "getSoundDirection"},
    {"speech_accuracy", "recognizeSpeech"},
    {"speaker_accuracy", "identifyVoice"},
    {"action_accuracy", "identifyTrajectory"},
    {"object_track_mean_iou", "getObjects"},
    {"object_position_median_m", "getObjects"},
    {"body_joint_median_error_m", "getBodyPose"},
    {"camera_selection_accuracy_within_10deg", "getFaces"},
    {"face_position_median_m", "getFaces"},
    {"speech_false_accept_rate", "recognizeSpeech"},
    {"head_position_median_m", "getHead"},
    {"head_gaze_median_deg", "getHeadGaze"},
    {"gaze_coverage", "getEyeGaze"},
    {"mutual_gaze_precision", "checkMutualGaze"},
    {"mutual_gaze_recall", "checkMutualGaze"},
};

// Face detection and camera selection against the truth `face` records of the same tick.
//  - A detection in camera c matches when that camera's truth face is visible and the
//    detection's box centre lies inside the truth box.
//  - face_recall: camera frames with a matched detection / camera frames whose truth face is
//    visible with |yaw| <= 45 deg (issue 4's protocol).
//  - face_false_positive_rate: camera frames with an unmatched detection / camera frames searched.
//  - camera_selection_accuracy: ticks whose selected camera is the truth best_camera (the most
//    frontal view) / ticks with a truth best_camera. Strict; the _within_10deg variant also
//    accepts a camera whose face is at most 10 deg less frontal than the best one's.
//  - face_position_median_m: the first face's 3-D position against the truth head position.
// Ticks whose getFaces is stale or sensor_offline are skipped (nothing was observed); no_data
// means every camera was searched and found nothing.
void evaluate_faces(const std::vector<json>& truth, const std::vector<json>& records, json& metrics,
                    json& not_evaluated) {
  std::map<int64_t, const json*> truth_faces;
  for (const auto& t : truth)
    if (t.value("type", "") == "face") truth_faces[t.value("stamp_ns", int64_t{0})] = &t;
  int visible = 0, found = 0, searched = 0, false_pos = 0, sel_total = 0, sel_exact = 0,
      sel_near = 0;
  std::vector<double> position_errors;
  auto inside = [](const json& box, double x, double y) {
    return x >= box[0].get<double>() && y >= box[1].get<double>() &&
           x <= box[0].get<double>() + box[2].get<double>() &&
           y <= box[1].get<double>() + box[3].get<double>();
  };
  for (const auto& r : records) {
    if (r.value("primitive", "") != "getFaces") continue;
    const std::string status = r.value("status", "");
    if (status != "ok" && status != "no_data") continue;
    auto it = truth_faces.find(r.value("stamp_ns", int64_t{-1}));
    if (it == truth_faces.end()) continue;
    const json& tf = *it->second;
    const json empty = json::object();
    const json& seen = status == "ok" ? r["value"]["cameras"] : empty;
    std::map<std::string, bool> matched_in;
    for (const auto& [cam, tc] : tf["cameras"].items()) {
      const bool is_visible = tc.value("visible", false);
      const json dets = seen.contains(cam) ? seen[cam] : json::array();
      if (status == "ok" && !seen.contains(cam)) continue;  // no frame from it this tick
      ++searched;
      bool matched = false, unmatched = false;
      for (const auto& d : dets) {
        const auto& b = d["box_px"];
        const double cx = b[0].get<double>() + b[2].get<double>() / 2;
        const double cy = b[1].get<double>() + b[3].get<double>() / 2;
        if (is_visible && inside(tc["box"], cx, cy))
          matched = true;
        else
          unmatched = true;
      }
      matched_in[cam] = matched;
      if (unmatched) ++false_pos;
      if (is_visible && std::abs(tc.value("yaw_deg", 180.0)) <= 45) {
        ++visible;
        if (matched) ++found;
      }
    }
    const json best = tf.value("best_camera", json(nullptr));
    if (!best.is_null()) {
      ++sel_total;
      const json sel =
          status == "ok" ? r["value"].value("selected_camera", json(nullptr)) : json(nullptr);
      if (!sel.is_null()) {
        const std::string s = sel.get<std::string>(), b = best.get<std::string>();
        if (s == b) {
          ++sel_exact;
          ++sel_near;
        } else if (matched_in[s] && tf["cameras"].contains(s) && tf["cameras"].contains(b) &&
                   std::abs(tf["cameras"][s].value("yaw_deg", 180.0)) <=
                       std::abs(tf["cameras"][b].value("yaw_deg", 180.0)) + 10.0) {
          ++sel_near;
        }
      }
    }
    if (status == "ok" && !r["value"]["faces"].empty() && tf.contains("head_position_m")) {
      const auto& p = r["value"]["faces"][0]["position_m"];
      const auto& q = tf["head_position_m"];
      double d2 = 0;
      for (int k = 0; k < 3; ++k) d2 += std::pow(p[k].get<double>() - q[k].get<double>(), 2);
      position_errors.push_back(std::sqrt(d2));
    }
  }
  if (visible > 0)
    metrics["face_recall"] = static_cast<double>(found) / visible;
  else
    not_evaluated["face_recall"] = "no truth face visible with |yaw| <= 45 deg";
  if (searched > 0) metrics["face_false_positive_rate"] = static_cast<double>(false_pos) / searched;
  if (sel_total > 0) {
    metrics["camera_selection_accuracy"] = static_cast<double>(sel_exact) / sel_total;
    metrics["camera_selection_accuracy_within_10deg"] = static_cast<double>(sel_near) / sel_total;
  }
  if (auto m = median(position_errors)) metrics["face_position_median_m"] = *m;
}

double angle_deg(const cv::Vec3d& a, const cv::Vec3d& b) {
  const double c = a.dot(b) / (cv::norm(a) * cv::norm(b));
  return std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / M_PI;
}

// Head pose, gaze, mutual gaze and eye centres against the truth `face` record of the same tick.
//  - head_pose_median_deg: geodesic angle between the estimated and true head rotations (all
//    three axes at once); head_gaze_median_deg: angle between the head-gaze directions;
//    head_position_median_m: getHead against the truth head position.
//  - gaze_median_deg: getEyeGaze (both eyes) against the truth eye-gaze direction, over ticks
//    with a gaze; gaze_coverage: those ticks / ticks whose truth face is visible in some camera.
//  - mutual_gaze_f1: per tick with a truth face, checkMutualGaze's `mutual` (false when there is
//    no face or no gaze) against the truth mutual_gaze.
//  - eye_center_median_px: getEyes pixel centres against the truth pupil pixels in the same
//    camera (eyes_px), over found eyes.
void evaluate_head_and_gaze(const std::vector<json>& truth, const std::vector<json>& records,
                            json& metrics, json& not_evaluated) {
  std::map<int64_t, const json*> truth_faces;
  for (const auto& t : truth)
    if (t.value("type", "") == "face") truth_faces[t.value("stamp_ns", int64_t{0})] = &t;
  std::vector<double> pose_err, head_gaze_err, head_pos_err, gaze_err, eye_err;
  int face_ticks = 0, gaze_ticks = 0, tp = 0, fp = 0, fn = 0, mutual_ticks = 0;
  std::map<int64_t, int> visible_ticks;
  for (const auto& [stamp, tf] : truth_faces) {
    bool visible = false;
    for (const auto& [cam, tc] : (*tf)["cameras"].items()) visible |= tc.value("visible", false);
    visible_ticks[stamp] = visible;
  }
  for (const auto& r : records) {
    const std::string p = r.value("primitive", "");
    if (p != "getHeadGaze" && p != "getHead" && p != "getEyeGaze" && p != "checkMutualGaze" &&
        p != "getEyes")
      continue;
    const auto it = truth_faces.find(r.value("stamp_ns", int64_t{-1}));
    if (it == truth_faces.end()) continue;
    const json& tf = *it->second;
    const std::string status = r.value("status", "");
    if (p == "checkMutualGaze") {
      if (status == "stale" || status == "sensor_offline" || status == "disabled") continue;
      ++mutual_ticks;
      const bool predicted = status == "ok" && r["value"].value("mutual", false);
      const bool actual = tf.value("mutual_gaze", false);
      tp += predicted && actual;
      fp += predicted && !actual;
      fn += !predicted && actual;
      continue;
    }
    if (status == "disabled") continue;
    if (p == "getEyeGaze" && visible_ticks[it->first]) ++face_ticks;
    if (status != "ok") continue;
    const json& v = r["value"];
    if (p == "getHeadGaze") {
      const cv::Matx33d d = ypr_rotation(v).t() * ypr_rotation(tf);
      const double c = (d(0, 0) + d(1, 1) + d(2, 2) - 1) / 2;
      pose_err.push_back(std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / M_PI);
      if (tf.contains("head_gaze_dir"))
        head_gaze_err.push_back(angle_deg(vec3(v["direction"]), vec3(tf["head_gaze_dir"])));
    } else if (p == "getHead") {
      head_pos_err.push_back(cv::norm(vec3(v["position_m"]) - vec3(tf["head_position_m"])));
    } else if (p == "getEyeGaze") {
      ++gaze_ticks;
      gaze_err.push_back(angle_deg(vec3(v["direction"]), vec3(tf["eye_gaze_dir"])));
    } else if (p == "getEyes") {
      const std::string cam = v.value("camera", "");
      if (!tf["cameras"].contains(cam) || !tf["cameras"][cam].contains("eyes_px")) continue;
      const json& te = tf["cameras"][cam]["eyes_px"];
      for (const char* eye : {"right", "left"}) {
        const json& e = v[std::string(eye) + "_px"];
        if (e.is_null() || !te.contains(eye) || te[eye].is_null()) continue;
        eye_err.push_back(std::hypot(e[0].get<double>() - te[eye][0].get<double>(),
                                     e[1].get<double>() - te[eye][1].get<double>()));
      }
    }
  }
  auto put = [&](const char* name, const std::vector<double>& v, const char* why) {
    if (auto m = median(v))
      metrics[name] = *m;
    else if (!not_evaluated.contains(name))
      not_evaluated[name] = why;
  };
  put("head_pose_median_deg", pose_err, "no ok getHeadGaze record at a truth face tick");
  put("head_gaze_median_deg", head_gaze_err, "no ok getHeadGaze record at a truth face tick");
  put("head_position_median_m", head_pos_err, "no ok getHead record at a truth face tick");
  put("gaze_median_deg", gaze_err, "no ok getEyeGaze record at a truth face tick");
  put("eye_center_median_px", eye_err, "no found eye centre in a camera with truth pupils");
  if (face_ticks > 0) metrics["gaze_coverage"] = static_cast<double>(gaze_ticks) / face_ticks;
  if (mutual_ticks > 0) {
    metrics["mutual_gaze_f1"] =
        tp + fp + fn > 0 ? 2.0 * tp / (2.0 * tp + fp + fn) : 1.0;  // nothing to find, none found
    metrics["mutual_gaze_precision"] = tp + fp > 0 ? json(1.0 * tp / (tp + fp)) : json(nullptr);
    metrics["mutual_gaze_recall"] = tp + fn > 0 ? json(1.0 * tp / (tp + fn)) : json(nullptr);
  }
}

// Speech against the truth utterances: an in-grammar utterance is right when exactly its text
// is recognised (an ok recognizeSpeech whose words overlap it); an out-of-grammar one is right
// when nothing is recognised during it. speech_false_accept_rate: out-of-grammar utterances
// with a recognition / out-of-grammar utterances.
void evaluate_speech(const std::vector<json>& truth, const std::vector<json>& records,
                     json& metrics, json& not_evaluated) {
  std::vector<std::pair<int64_t, int64_t>> heard_spans;
  std::vector<std::string> heard_text;
  for (const auto& r : records)
    if (r.value("primitive", "") == "recognizeSpeech" && r.value("status", "") == "ok") {
      heard_spans.emplace_back(r["value"].value("start_ns", int64_t{0}),
                               r["value"].value("end_ns", int64_t{0}));
      heard_text.push_back(r["value"].value("text", ""));
    }
  int total = 0, right = 0, oog = 0, oog_accepted = 0;
  for (const auto& t : truth) {
    if (t.value("type", "") != "speech" || !t.contains("in_grammar")) continue;
    const int64_t s = t.value("start_ns", int64_t{0}), e = t.value("end_ns", int64_t{0});
    std::vector<std::string> said;
    for (size_t i = 0; i < heard_spans.size(); ++i)
      if (heard_spans[i].first < e && heard_spans[i].second > s) said.push_back(heard_text[i]);
    ++total;
    if (t.value("in_grammar", false)) {
      if (said.size() == 1 && said[0] == t.value("text", "")) ++right;
    } else {
      ++oog;
      if (said.empty())
        ++right;
      else
        ++oog_accepted;
    }
  }
  if (total == 0) {
    not_evaluated["speech_accuracy"] = "the truth has no speech records with in_grammar";
    return;
  }
  metrics["speech_accuracy"] = static_cast<double>(right) / total;
  if (oog > 0) metrics["speech_false_accept_rate"] = static_cast<double>(oog_accepted) / oog;
}

// Who spoke: each truth utterance with a `speaker` against the ok identifyVoice record whose
// utterance [start_ns, end_ns] overlaps it most; right when its speaker_id is the truth speaker
// (child / therapist). A truth utterance no identity overlaps counts as wrong (missed).
void evaluate_speaker(const std::vector<json>& truth, const std::vector<json>& records,
                      json& metrics, json& not_evaluated) {
  std::vector<std::pair<int64_t, int64_t>> spans;
  std::vector<std::string> who;
  for (const auto& r : records)
    if (r.value("primitive", "") == "identifyVoice" && r.value("status", "") == "ok") {
      spans.emplace_back(r["value"].value("start_ns", int64_t{0}),
                         r["value"].value("end_ns", int64_t{0}));
      who.push_back(r["value"].value("speaker_id", ""));
    }
  int total = 0, right = 0;
  for (const auto& t : truth) {
    if (t.value("type", "") != "speech" || !t.contains("speaker")) continue;
    const int64_t s = t.value("start_ns", int64_t{0}), e = t.value("end_ns", int64_t{0});
    int64_t best = 0;
    std::string said;
    for (size_t i = 0; i < spans.size(); ++i) {
      const int64_t overlap = std::min(e, spans[i].second) - std::max(s, spans[i].first);
      if (overlap > best) best = overlap, said = who[i];
    }
    ++total;
    right += !said.empty() && said == t.value("speaker", "");
  }
  if (total == 0) {
    not_evaluated["speaker_accuracy"] = "the truth has no speech records with a speaker";
    return;
  }
  metrics["speaker_accuracy"] = static_cast<double>(right) / total;
}

}  // namespace

Result<json> evaluate_session(const SessionEvalOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  auto manifest = sources::read_manifest(options.session_dir);
  if (!manifest) return tl::unexpected(manifest.error());
  if (manifest->truth.empty())
    return make_error(ErrorCode::kNotFound, "{}: the session has no truth.jsonl to compare with",
                      (options.session_dir / sources::kManifestName).string());
  auto truth = sources::read_truth(options.session_dir / manifest->truth);
  if (!truth) return tl::unexpected(truth.error());
  auto records = read_jsonl(options.analysis_dir / "primitives.jsonl");
  if (!records) return tl::unexpected(records.error());

  // Status per primitive over the run; a metric is only computed for an enabled primitive.
  std::map<std::string, std::map<std::string, int>> status;
  int evaluated = 0, ok = 0;
  for (const auto& r : *records) {
    const std::string p = r.value("primitive", "");
    const std::string st = r.value("status", "");
    status[p][st]++;
    if (st != "disabled") {
      ++evaluated;
      if (st == "ok") ++ok;
    }
  }
  auto enabled = [&](const std::string& primitive) {
    auto it = status.find(primitive);
    if (it == status.end()) return false;
    int n = 0;
    for (const auto& [st, c] : it->second)
      if (st != "disabled") n += c;
    return n > 0;
  };

  json metrics = json::object(), not_evaluated = json::object();
  for (const auto& [metric, primitive] : kMetricPrimitive) {
    metrics[metric] = nullptr;
    if (!enabled(primitive)) not_evaluated[metric] = primitive + " is disabled (no analyser yet)";
  }
  metrics["primitives_ok_fraction"] =
      evaluated > 0 ? json(static_cast<double>(ok) / evaluated) : json(nullptr);

  // Body: getBodyPose joints against the truth skeleton of the same skeleton frame.
  if (enabled("getBodyPose")) {
    std::map<int64_t, const json*> truth_skeleton;
    for (const auto& t : *truth)
      if (t.value("type", "") == "skeleton") truth_skeleton[t.value("stamp_ns", int64_t{0})] = &t;
    std::vector<double> errors;
    for (const auto& r : *records) {
      if (r.value("primitive", "") != "getBodyPose" || r.value("status", "") != "ok") continue;
      auto it = truth_skeleton.find(r.value("data_stamp_ns", int64_t{-1}));
      if (it == truth_skeleton.end()) continue;
      const json& tj = (*it->second)["joints"];
      for (const auto& [name, jv] : r["value"]["joints"].items()) {
        if (!tj.contains(name) || jv.value("confidence", 0.0) <= 0) continue;
        const auto p = jv["position_m"];
        const auto q = tj[name];
        const double dx = p[0].get<double>() - q[0].get<double>();
        const double dy = p[1].get<double>() - q[1].get<double>();
        const double dz = p[2].get<double>() - q[2].get<double>();
        errors.push_back(std::sqrt(dx * dx + dy * dy + dz * dz));
      }
    }
    if (auto m = median(errors))
      metrics["body_joint_median_error_m"] = *m;
    else
      not_evaluated["body_joint_median_error_m"] =
          "no getBodyPose record matches a truth skeleton frame";
  }

  // Sound direction: getSoundDirection azimuth of ok records during each truth utterance
  // [start_ns, end_ns] against the utterance's truth azimuth (array frame).
  if (enabled("getSoundDirection")) {
    std::vector<std::pair<int64_t, int64_t>> spans;
    std::vector<double> truth_az;
    for (const auto& t : *truth)
      if (t.value("type", "") == "speech" && t.contains("azimuth_deg")) {
        spans.emplace_back(t.value("start_ns", int64_t{0}), t.value("end_ns", int64_t{0}));
        truth_az.push_back(t["azimuth_deg"].get<double>());
      }
    std::vector<double> errors;
    for (const auto& r : *records) {
      if (r.value("primitive", "") != "getSoundDirection" || r.value("status", "") != "ok")
        continue;
      const int64_t stamp = r.value("stamp_ns", int64_t{-1});
      for (size_t i = 0; i < spans.size(); ++i)
        if (stamp >= spans[i].first && stamp <= spans[i].second) {
          errors.push_back(std::abs(r["value"]["azimuth_deg"].get<double>() - truth_az[i]));
          break;
        }
    }
    if (!errors.empty()) {
      double sum = 0;
      int within = 0;
      for (double e : errors) {
        sum += e;
        if (e <= 10) ++within;
      }
      metrics["doa_mae_deg"] = sum / static_cast<double>(errors.size());
      metrics["doa_within_10deg"] =
          static_cast<double>(within) / static_cast<double>(errors.size());
    } else {
      const char* why = spans.empty() ? "the truth has no speech records"
                                      : "no ok getSoundDirection record during a truth utterance";
      not_evaluated["doa_mae_deg"] = why;
      not_evaluated["doa_within_10deg"] = why;
    }
  }

  if (enabled("getFaces")) evaluate_faces(*truth, *records, metrics, not_evaluated);
  if (enabled("getHeadGaze") || enabled("getEyeGaze"))
    evaluate_head_and_gaze(*truth, *records, metrics, not_evaluated);
  if (enabled("recognizeSpeech")) evaluate_speech(*truth, *records, metrics, not_evaluated);
  if (enabled("identifyVoice")) evaluate_speaker(*truth, *records, metrics, not_evaluated);

  json out;
  out["task"] = "session";
  out["dataset"] = {{"name", manifest->name}, {"items", records->size() / 25}};
  out["protocol"] = "primitives.jsonl of the analysis against the session's truth.jsonl";
  out["metrics"] = metrics;
  out["timing"] = json::object();
  out["per_class"] = json::object();
  out["not_evaluated"] = not_evaluated;
  out["primitive_status"] = status;
  return out;
}

}  // namespace dreamsense::eval
