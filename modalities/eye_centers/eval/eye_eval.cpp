#include "eye_eval.hpp"

#include "dreamsense/face_detection/face_detector.hpp"
#include "dreamsense/face_landmarks/landmarker.hpp"
#include "dreamsense/perception/eye_centers.hpp"
#include "dreamsense/perception/face_detection.hpp"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>

#include "bioid.hpp"

namespace dreamsense::eye_centers {
namespace {

using Clock = std::chrono::steady_clock;
constexpr double kInf = std::numeric_limits<double>::infinity();

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

nlohmann::json median_or_null(std::vector<double> v) {
  if (v.empty()) return nullptr;
  std::sort(v.begin(), v.end());
  const double m =
      v.size() % 2 == 1 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
  if (!std::isfinite(m)) return nullptr;
  return m;
}

struct MethodRecord {
  std::vector<double> errors;  // one per image, inf = failure
  std::vector<double> eye_ms, face_ms;
  size_t found_both = 0, with_landmarks = 0;
};

nlohmann::json method_metrics(const MethodRecord& r, size_t faces_detected) {
  const double n = static_cast<double>(r.errors.size());
  auto acc = [&](double t) {
    return static_cast<double>(
               std::count_if(r.errors.begin(), r.errors.end(), [t](double e) { return e <= t; })) /
           n;
  };
  nlohmann::json m;
  m["acc_e005"] = acc(0.05);
  m["acc_e010"] = acc(0.10);
  m["acc_e025"] = acc(0.25);
  m["median_e"] = median_or_null(r.errors);
  m["face_detection_rate"] = static_cast<double>(faces_detected) / n;
  m["found_rate"] = r.with_landmarks > 0
                        ? static_cast<double>(r.found_both) / static_cast<double>(r.with_landmarks)
                        : 0.0;
  return m;
}

}  // namespace

Status EyeEvalOptions::check() const {
  if (dataset != "bioid" && dataset != "synthetic-eyes")
    return make_error(ErrorCode::kInvalidArgument,
                      "eval eyes: dataset '{}' is not supported (bioid, synthetic-eyes)", dataset);
  if (dir.empty()) return make_error(ErrorCode::kInvalidArgument, "eval eyes: no dataset folder");
  if (generate)
    if (auto s = generate->check(); !s) return s;
  if (auto m = expand_eye_methods(methods); !m) return tl::unexpected(m.error());
  if (!(min_face_px >= 20))
    return make_error(ErrorCode::kInvalidArgument, "eval eyes: min_face_px must be >= 20");
  return locator.check();
}

Result<std::vector<std::string>> expand_eye_methods(const std::vector<std::string>& names) {
  std::vector<std::string> out;
  auto add = [&](const std::string& m) {
    if (std::find(out.begin(), out.end(), m) == out.end()) out.push_back(m);
  };
  for (const std::string& n : names) {
    if (n == "all") {
      for (const char* m : {"improved_integro_differential", "daugman", "timm_barth"}) add(m);
      add(kLandmarkCentroid);
    } else if (n == kLandmarkCentroid) {
      add(n);
    } else if (auto m = eye_center_method_from_string(n)) {
      add(std::string(to_string(*m)));
    } else {
      return make_error(ErrorCode::kInvalidArgument,
                        "eval eyes: unknown method '{}' (improved, daugman, timm_barth, "
                        "landmark_centroid, all)",
                        n);
    }
  }
  if (out.empty()) return make_error(ErrorCode::kInvalidArgument, "eval eyes: no method");
  return out;
}

Result<nlohmann::json> run_eye_eval(const EyeEvalOptions& options,
                                    const std::function<void(double)>& progress) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  const std::vector<std::string> methods = *expand_eye_methods(options.methods);
  const double gen_share = options.generate ? 0.2 : 0.0;
  if (options.generate) {
    auto s = write_synthetic_eye_set(*options.generate, options.dir, [&](double f) {
      if (progress) progress(gen_share * f);
    });
    if (!s) return tl::unexpected(s.error());
  }
  auto items = load_bioid(options.dir);
  if (!items) return tl::unexpected(items.error());

  face_detection::FaceDetectorOptions fo;
  fo.frontal_cascade = options.face_cascade;
  fo.min_face_px = options.min_face_px;
  fo.detection_width = 640;  // BioID's 384 px: no shrinking
  fo.estimate_frontalness = false;
  auto detector = face_detection::FaceDetector::create(fo);
  if (!detector) return tl::unexpected(detector.error());
  face_landmarks::DlibLandmarkerOptions lo;
  lo.model = options.landmark_model;
  auto landmarker = face_landmarks::make_dlib_landmarker(lo);
  if (!landmarker) return tl::unexpected(landmarker.error());
  std::map<std::string, EyeCenterLocator> locators;
  for (const std::string& m : methods) {
    if (m == kLandmarkCentroid) continue;
    EyeCenterLocatorOptions lopt = options.locator;
    lopt.method = *eye_center_method_from_string(m);
    auto l = EyeCenterLocator::create(lopt);
    if (!l) return tl::unexpected(l.error());
    locators.emplace(m, *l);
  }

  std::map<std::string, MethodRecord> records;
  std::vector<double> detect_ms, landmark_ms;
  size_t faces_detected = 0;
  for (size_t i = 0; i < items->size(); ++i) {
    const BioIdItem& item = (*items)[i];
    const cv::Mat grey = cv::imread(item.image.string(), cv::IMREAD_GRAYSCALE);
    if (grey.empty())
      return make_error(ErrorCode::kCorruptData, "{}: unreadable image", item.image.string());
    const double iod = cv::norm(item.eyes.left_px - item.eyes.right_px);
    if (!(iod > 0))
      return make_error(ErrorCode::kCorruptData, "{}: both eyes at the same point", item.id);

    auto t0 = Clock::now();
    const std::vector<DetectedFace> faces = detector->detect(grey);
    const double det = ms_since(t0);
    detect_ms.push_back(det);
    std::optional<std::vector<cv::Point2d>> points;
    double lm_ms = 0;
    if (!faces.empty()) {
      ++faces_detected;
      t0 = Clock::now();
      auto fit = (*landmarker)->fit(grey, faces.front().box_px);
      lm_ms = ms_since(t0);
      landmark_ms.push_back(lm_ms);
      if (!fit) return tl::unexpected(fit.error());
      points = std::move(*fit);
    }
    for (const std::string& m : methods) {
      MethodRecord& r = records[m];
      if (!points) {
        r.errors.push_back(kInf);
        continue;
      }
      ++r.with_landmarks;
      const std::span<const cv::Point2d> pts(*points);
      EyeCenter right, left;
      double eyes_ms = 0;
      if (m == kLandmarkCentroid) {
        t0 = Clock::now();
        right = {true, eye_region_from_contour(pts.subspan(36, 6)).center_px, 1.0};
        left = {true, eye_region_from_contour(pts.subspan(42, 6)).center_px, 1.0};
        eyes_ms = ms_since(t0);
        r.eye_ms.push_back(eyes_ms / 2);
      } else {
        const EyeCenterLocator& loc = locators.at(m);
        for (int eye = 0; eye < 2; ++eye) {
          t0 = Clock::now();
          auto e = loc.locate(grey, pts.subspan(eye == 0 ? 36 : 42, 6));
          const double ms = ms_since(t0);
          if (!e) return tl::unexpected(e.error());
          (eye == 0 ? right : left) = e->to_eye_center();
          r.eye_ms.push_back(ms);
          eyes_ms += ms;
        }
      }
      r.face_ms.push_back(det + lm_ms + eyes_ms);
      if (!right.found || !left.found) {
        r.errors.push_back(kInf);
        continue;
      }
      ++r.found_both;
      const double dl = cv::norm(left.center_px - item.eyes.left_px);
      const double dr = cv::norm(right.center_px - item.eyes.right_px);
      r.errors.push_back(std::max(dl, dr) / iod);
    }
    if (progress)
      progress(gen_share +
               (1 - gen_share) * static_cast<double>(i + 1) / static_cast<double>(items->size()));
  }

  nlohmann::json j;
  j["task"] = "eyes";
  j["dataset"] = {
      {"name", options.dataset}, {"items", items->size()}, {"dir", options.dir.string()}};
  if (options.generate)
    j["dataset"]["generator"] = {{"count", options.generate->count},
                                 {"seed", options.generate->seed},
                                 {"portrait", options.generate->portrait.string()}};
  j["protocol"] =
      "BioID eye-centre protocol: Haar face detection (haarcascade_frontalface_alt2, best face), "
      "dlib 68 landmarks, eye regions from contours 36-41 / 42-47, eye centres; e = max(d_left, "
      "d_right) / |L - R|; no face, no landmarks or an eye not found = failure (e = inf); "
      "acc_eXXX = fraction of all images with e <= 0.XX";
  j["method"] = methods.front();
  j["methods"] = methods;
  nlohmann::json metrics, timing;
  for (const std::string& m : methods) {
    const MethodRecord& r = records[m];
    metrics[m] = method_metrics(r, faces_detected);
    timing[m] = {{"ms_per_face_median", median_or_null(r.face_ms)},
                 {"ms_per_eye_median", median_or_null(r.eye_ms)}};
  }
  for (const auto& [k, v] : metrics[methods.front()].items()) metrics[k] = v;
  for (const auto& [k, v] : timing[methods.front()].items()) timing[k] = v;
  timing["detection_ms_median"] = median_or_null(detect_ms);
  timing["landmarks_ms_median"] = median_or_null(landmark_ms);
  j["metrics"] = metrics;
  j["timing"] = timing;
  j["per_class"] = nlohmann::json::object();
  return j;
}

}  // namespace dreamsense::eye_centers
