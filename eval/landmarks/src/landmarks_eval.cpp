// The `eval landmarks` protocol: every detector chain and the annotated box on the same images.

#include "dreamsense/eval/landmarks/landmarks_eval.hpp"

#include "dreamsense/face_detection/face_detector.hpp"
#include "dreamsense/face_detection/hog_face_detector.hpp"
#include "dreamsense/face_landmarks/landmarker.hpp"
#include "dreamsense/perception/face_landmarks.hpp"
#include "dreamsense/vision/face_api_net.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <set>

namespace dreamsense::eval::landmarks {
namespace {

namespace fd = dreamsense::face_detection;
namespace fl = dreamsense::face_landmarks;

// Each detector chain and the detectors it runs ("wide": the wider Haar search of hog_haar and
// union, with smaller faces and the profile cascades). A new chain is one line here (and its box
// rule in run_landmarks_eval).
struct DetectorChain {
  std::string name;
  std::set<std::string> runs;
};
const std::vector<DetectorChain> kDetectors{{"haar", {"haar"}},
                                            {"hog", {"hog"}},
                                            {"hog_haar", {"hog", "wide"}},
                                            {"union", {"hog", "wide"}},
                                            {"tiny", {"tiny"}},
                                            {"union_tiny", {"hog", "wide", "tiny"}},
                                            {"tiny_union", {"hog", "wide", "tiny"}},
                                            {"ssd", {"ssd"}},
                                            {"union_ssd", {"hog", "wide", "ssd"}},
                                            {"union_tiny_ssd", {"hog", "wide", "tiny", "ssd"}},
                                            {"ssd_union", {"hog", "wide", "ssd"}},
                                            {"ssd_hybrid", {"hog", "wide", "ssd"}},
                                            {"ssd_paired", {"hog", "wide", "ssd"}}};

const DetectorChain* detector_chain(const std::string& name) {
  const auto d = std::find_if(kDetectors.begin(), kDetectors.end(),
                              [&](const DetectorChain& c) { return c.name == name; });
  return d == kDetectors.end() ? nullptr : &*d;
}
using LandmarkFitResult = face_landmarks::LandmarkFit;

std::optional<double> mean(const std::vector<double>& v) {
  if (v.empty()) return std::nullopt;
  double s = 0;
  for (double x : v) s += x;
  return s / static_cast<double>(v.size());
}

// One chain's outcome on one annotated face.
struct FaceResult {
  bool detected = false;             // a detector box with IoU >= min_iou (the rule)
  bool detected_fitted_box = false;  // the box of the points fitted from a detection does
  std::optional<double> nme, eye_error;
  double ms = 0;        // detection of the image + the fit of the matched face
  double best_iou = 0;  // of the detector boxes with the annotated points' box
  size_t detections = 0;
  std::optional<double> spread;  // the landmarker's (LandmarkFit::spread)
};

// Probability that a failed fit (NME > failure_nme) has a larger spread than a good one (ROC AUC;
// 0.5 = the spread says nothing). Faces without a spread are left out.
std::optional<double> failure_auc(const std::vector<FaceResult>& faces, double failure_nme) {
  std::vector<double> bad, good;
  for (const FaceResult& f : faces)
    if (f.nme && f.spread && std::isfinite(*f.spread))
      (*f.nme > failure_nme ? bad : good).push_back(*f.spread);
  if (bad.empty() || good.empty()) return std::nullopt;
  double wins = 0;
  for (double b : bad)
    for (double g : good) wins += b > g ? 1.0 : (b == g ? 0.5 : 0.0);
  return wins / static_cast<double>(bad.size() * good.size());
}

struct ChainScores {
  std::vector<FaceResult> faces;
  nlohmann::json metrics(double failure_nme, bool with_detection) const {
    std::vector<double> nmes, eyes, ms;
    size_t detected = 0, detected_fitted = 0, failures = 0;
    for (const FaceResult& f : faces) {
      detected += f.detected;
      detected_fitted += f.detected_fitted_box;
      if (f.nme) {
        nmes.push_back(*f.nme);
        failures += *f.nme > failure_nme;
      }
      if (f.eye_error) eyes.push_back(*f.eye_error);
    }
    const double n = static_cast<double>(faces.size());
    nlohmann::json j;
    if (with_detection) {
      j["detection_rate"] = faces.empty() ? nlohmann::json(nullptr) : nlohmann::json(detected / n);
      j["detection_rate_fitted_box"] =
          faces.empty() ? nlohmann::json(nullptr) : nlohmann::json(detected_fitted / n);
      j["faces_detected"] = detected;
    }
    j["faces_fitted"] = nmes.size();
    j["nme_outer_corners"] = number_or_null(mean(nmes));
    j["nme_outer_corners_median"] = number_or_null(median(nmes));
    j["failure_rate_08"] =
        nmes.empty() ? nlohmann::json(nullptr) : nlohmann::json(failures / double(nmes.size()));
    j["eye_center_error"] = number_or_null(mean(eyes));
    j["eye_center_error_median"] = number_or_null(median(eyes));
    j["spread_failure_auc"] = number_or_null(failure_auc(faces, failure_nme));
    // Occlusion-aware confidence: fits with spread_confidence >= 0.5 are "confident".
    std::vector<double> confident;
    size_t confident_failures = 0;
    for (const FaceResult& f : faces)
      if (f.nme && face_landmarks::spread_confidence(f.spread.value_or(std::nan(""))) >= 0.5) {
        confident.push_back(*f.nme);
        confident_failures += *f.nme > failure_nme;
      }
    j["confident_fraction"] = nmes.empty() ? nlohmann::json(nullptr)
                                           : nlohmann::json(confident.size() / double(nmes.size()));
    j["nme_confident"] = number_or_null(mean(confident));
    j["confident_failure_rate"] =
        confident.empty() ? nlohmann::json(nullptr)
                          : nlohmann::json(confident_failures / double(confident.size()));
    return j;
  }
  std::optional<double> ms_median() const {
    std::vector<double> v;
    for (const FaceResult& f : faces) v.push_back(f.ms);
    return median(v);
  }
};

// A chain: a detector (haar, hog, hog_haar, union) and a landmarker (plain, or "+tta").
struct Chain {
  std::string name, detector;
  bool tta = false;
  // 0 dlib (pipeline), 1 dlib+tta, 2 face-api CNN, 3 mean of 1 and 2, 4 dlib+tta from the CNN,
  // 5 dlib+tta when the pipeline dlib's spread is confident, else the CNN; 6 the same with dlib
  // started from the box of the CNN's points (used on face-api's boxes only, 5 on the others).
  int landmarker = 0;
};

const std::map<std::string, int> kLandmarkerSuffixes{
    {"+tta", 1},    {"+cnn", 2},        {"+mean", 3},        {"+cnn_dlib", 4},
    {"+switch", 5}, {"+cnn_switch", 6}, {"+plain_switch", 7}};

std::optional<Chain> parse_chain(const std::string& name) {
  Chain c{name, name, false, 0};
  if (const auto plus = name.find('+'); plus != std::string::npos) {
    const auto s = kLandmarkerSuffixes.find(name.substr(plus));
    if (s == kLandmarkerSuffixes.end()) return std::nullopt;
    c.detector = name.substr(0, plus);
    c.landmarker = s->second;
    c.tta = c.landmarker == 1;
  }
  if (!detector_chain(c.detector)) return std::nullopt;
  return c;
}

struct DetectorOutput {
  std::vector<cv::Rect2d> boxes;
  double ms = 0;
};

// Fits of one image, cached per (landmarker, box): chains sharing boxes fit once.
struct Fit {
  std::optional<LandmarkFitResult> fit;
  double ms = 0;
};

double iou(const cv::Rect2d& a, const cv::Rect2d& b) {
  const double inter = (a & b).area();
  const double uni = a.area() + b.area() - inter;
  return uni > 0 ? inter / uni : 0.0;
}

// The SSD on the whole image, and with LandmarksEvalOptions::ssd_tiles also on 2 x 2 tiles
// (see there), merged by greedy suppression in score order.
std::vector<vision::FaceApiDetection> ssd_detect(vision::FaceApiSsdDetector& ssd,
                                                 const cv::Mat& image,
                                                 const LandmarksEvalOptions& o) {
  std::vector<vision::FaceApiDetection> all = ssd.detect(image, o.ssd_min_score);
  const int side = std::max(image.cols, image.rows);
  if (!o.ssd_tiles || side <= 3 * vision::kFaceApiSsdInputPx / 2) return all;
  const int tw = static_cast<int>(std::ceil(o.ssd_tile_fraction * image.cols));
  const int th = static_cast<int>(std::ceil(o.ssd_tile_fraction * image.rows));
  constexpr double kBorderPx = 2;  // a box this close to an inner tile border is cut by it
  for (const int x0 : {0, image.cols - tw})
    for (const int y0 : {0, image.rows - th}) {
      const cv::Rect tile(x0, y0, tw, th);
      for (vision::FaceApiDetection d : ssd.detect(image(tile), o.ssd_min_score)) {
        const cv::Rect2d& b = d.box;
        const bool cut = (x0 > 0 && b.x < kBorderPx) || (y0 > 0 && b.y < kBorderPx) ||
                         (x0 + tw < image.cols && b.x + b.width > tw - kBorderPx) ||
                         (y0 + th < image.rows && b.y + b.height > th - kBorderPx);
        if (cut || std::max(b.width, b.height) > 0.5 * std::min(tw, th)) continue;
        d.box.x += x0;
        d.box.y += y0;
        all.push_back(d);
      }
    }
  std::stable_sort(all.begin(), all.end(),
                   [](const auto& a, const auto& b) { return a.score > b.score; });
  std::vector<vision::FaceApiDetection> kept;
  for (const vision::FaceApiDetection& d : all)
    if (std::none_of(kept.begin(), kept.end(),
                     [&](const auto& k) { return iou(k.box, d.box) > 0.5; }))
      kept.push_back(d);
  return kept;
}

FaceResult score(const std::vector<cv::Rect2d>& boxes, const std::vector<const Fit*>& fits,
                 double detect_ms, const std::vector<cv::Point2d>& truth,
                 const cv::Rect2d& truth_box, double min_iou) {
  FaceResult r;
  r.ms = detect_ms;
  r.detections = boxes.size();
  for (const cv::Rect2d& b : boxes) r.best_iou = std::max(r.best_iou, iou(b, truth_box));
  const int k = match_detection(boxes, truth_box, min_iou);
  std::vector<cv::Rect2d> fitted;
  for (const Fit* f : fits) fitted.push_back(f->fit ? points_extent(f->fit->points) : cv::Rect2d());
  r.detected_fitted_box = match_detection(fitted, truth_box, min_iou) >= 0;
  if (k < 0) return r;
  r.detected = true;
  const Fit& f = *fits[static_cast<size_t>(k)];
  r.ms += f.ms;
  if (f.fit) {
    r.nme = nme_outer_corners(f.fit->points, truth);
    r.eye_error = eye_center_error(f.fit->points, truth);
    r.spread = f.fit->spread;
  } else {
    r.nme = r.eye_error = std::numeric_limits<double>::infinity();  // rejected face: a failure
  }
  return r;
}

std::vector<cv::Rect2d> boxes_of(const std::vector<DetectedFace>& faces) {
  std::vector<cv::Rect2d> b;
  for (const DetectedFace& f : faces) b.push_back(f.box_px);
  return b;
}

// Boxes of `extra` that overlap none of `base` (IoU < 0.3) appended to `base`.
std::vector<cv::Rect2d> merge(std::vector<cv::Rect2d> base, const std::vector<cv::Rect2d>& extra) {
  const size_t n = base.size();
  for (const cv::Rect2d& e : extra) {
    bool overlaps = false;
    for (size_t i = 0; i < n && !overlaps; ++i) overlaps = iou(base[i], e) >= 0.3;
    if (!overlaps) base.push_back(e);
  }
  return base;
}

}  // namespace

Status LandmarksEvalOptions::check() const {
  std::string bad;
  auto add = [&](const std::string& s) { bad += (bad.empty() ? "" : "; ") + s; };
  if (dataset != "300w") add(fmt::format("unknown dataset '{}' (known: 300w)", dataset));
  if (detectors.empty()) add("no detector chain");
  std::vector<std::string> chain_names, suffixes;
  for (const DetectorChain& c : kDetectors) chain_names.push_back(c.name);
  for (const auto& [suffix, landmarker] : kLandmarkerSuffixes) suffixes.push_back(suffix);
  for (const std::string& d : detectors)
    if (!parse_chain(d))
      add(fmt::format("unknown detector chain '{}' (known: {}, each optionally with one of {})", d,
                      fmt::join(chain_names, ", "), fmt::join(suffixes, ", ")));
  if (!(min_iou > 0 && min_iou <= 1)) add("min_iou must be in (0, 1]");
  if (!(failure_nme > 0)) add("failure_nme must be > 0");
  if (stride < 1) add("stride must be >= 1");
  if (!(ssd_min_score > 0 && ssd_min_score < 1)) add("ssd_min_score must be in (0, 1)");
  if (!(ssd_tile_fraction > 0.5 && ssd_tile_fraction < 1))
    add("ssd_tile_fraction must be in (0.5, 1)");
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "eval landmarks: " + bad);
  return ok_status();
}

Result<EvalReport> run_landmarks_eval(const LandmarksEvalOptions& o, const Progress& progress) {
  if (auto s = o.check(); !s) return tl::unexpected(s.error());
  auto all = list_300w(o.dir);
  if (!all) return tl::unexpected(all.error());
  std::vector<LandmarkItem> items;
  for (size_t i = 0; i < all->size(); i += o.stride) {
    if (o.max_items > 0 && items.size() >= o.max_items) break;
    items.push_back((*all)[i]);
  }
  // Annotations first: a malformed file stops the run before minutes of detection.
  std::vector<std::vector<cv::Point2d>> truths;
  for (const LandmarkItem& it : items) {
    auto pts = read_pts(it.pts);
    if (!pts) return tl::unexpected(pts.error());
    if (o.one_based_annotations)
      for (cv::Point2d& p : *pts) p -= cv::Point2d(1, 1);
    if (!(outer_corner_distance(*pts) > 0))
      return make_error(
          ErrorCode::kCorruptData,
          fmt::format("{}: outer eye corners (points 37, 46) coincide", it.pts.string()));
    truths.push_back(std::move(*pts));
  }

  std::vector<Chain> chains;
  for (const std::string& d : o.detectors) chains.push_back(*parse_chain(d));
  const Chain& top_chain = chains.front();
  // The pipeline's landmarker, and the one with test-time augmentation.
  fl::DlibLandmarkerOptions lo;
  lo.model = o.landmark_model;
  lo.refit_passes = o.landmark_refit_passes;
  lo.quantized_leaves = o.landmark_quantized_leaves;
  auto plain = fl::make_dlib_landmarker(lo);
  if (!plain) return tl::unexpected(plain.error());
  lo.box_scales = o.tta_box_scales;
  lo.mirror = o.tta_mirror;
  auto tta = fl::make_dlib_landmarker(lo);
  if (!tta) return tl::unexpected(tta.error());
  const fl::Landmarker* landmarkers[2] = {plain->get(), tta->get()};
  // face-api's CNN (a pretrained alternative, compared in the same run).
  std::unique_ptr<fl::Landmarker> cnn;
  if (o.with_cnn ||
      std::any_of(chains.begin(), chains.end(), [](const Chain& c) { return c.landmarker >= 2; })) {
    fl::FaceApiLandmarkerOptions co;
    co.model_dir = o.face_api_model_dir;
    auto c = fl::make_face_api_landmarker(co);
    if (!c) return tl::unexpected(c.error());
    cnn = std::move(*c);
  }

  // Whether any chain runs `detector` (kDetectors).
  auto uses = [&](const std::string& detector) {
    return std::any_of(chains.begin(), chains.end(), [&](const Chain& c) {
      return detector_chain(c.detector)->runs.count(detector) > 0;
    });
  };
  std::optional<fd::FaceDetector> haar;
  if (uses("haar")) {
    auto h = fd::FaceDetector::create(fd::FaceDetectorOptions{});  // the pipeline's defaults
    if (!h) return tl::unexpected(h.error());
    haar.emplace(std::move(*h));
  }
  // The Haar search of hog_haar and union: also smaller faces and the profile cascades.
  std::optional<fd::FaceDetector> haar_wide;
  if (uses("wide")) {
    fd::FaceDetectorOptions w;
    w.min_face_px = o.wide_haar_min_face_px;
    w.use_profile = o.wide_haar_profile;
    auto h = fd::FaceDetector::create(w);
    if (!h) return tl::unexpected(h.error());
    haar_wide.emplace(std::move(*h));
  }
  std::optional<fd::HogFaceDetector> hog;
  if (uses("hog")) {
    fd::HogFaceDetectorOptions ho;
    ho.min_face_px = o.hog_min_face_px;
    ho.max_work_side_px = o.hog_max_work_side_px;
    auto h = fd::HogFaceDetector::create(ho);
    if (!h) return tl::unexpected(h.error());
    hog.emplace(std::move(*h));
  }

  std::optional<vision::FaceApiTinyFaceDetector> tiny;
  if (uses("tiny")) {
    auto t = vision::FaceApiTinyFaceDetector::load(
        o.face_api_model_dir.empty() ? vision::default_face_api_model_dir() : o.face_api_model_dir);
    if (!t) return tl::unexpected(t.error());
    tiny.emplace(std::move(*t));
  }
  std::optional<vision::FaceApiSsdDetector> ssd;
  if (uses("ssd")) {
    auto t = vision::FaceApiSsdDetector::load(
        o.face_api_model_dir.empty() ? vision::default_face_api_model_dir() : o.face_api_model_dir);
    if (!t) return tl::unexpected(t.error());
    ssd.emplace(std::move(*t));
  }

  std::map<std::string, ChainScores> scores;
  ChainScores from_box, from_box_plain, from_box_cnn;
  nlohmann::json per_face = nlohmann::json::array();
  cv::Point2d bias[2] = {{0, 0}, {0, 0}};
  double width_ratio[2] = {0, 0}, height_ratio[2] = {0, 0};
  size_t fitted[2] = {0, 0};
  for (size_t i = 0; i < items.size(); ++i) {
    const LandmarkItem& it = items[i];
    const std::vector<cv::Point2d>& truth = truths[i];
    cv::Mat image = cv::imread(it.image.string(), cv::IMREAD_COLOR);
    if (image.empty())
      return make_error(ErrorCode::kCorruptData,
                        fmt::format("{}: cannot decode the image (not an image, damaged, or "
                                    "larger than OpenCV's pixel limit)",
                                    it.image.string()));
    const cv::Rect2d truth_box = points_extent(truth);
    nlohmann::json face = {{"name", it.name}};

    DetectorOutput haar_out, hog_out, wide_out, tiny_out, ssd_out;
    if (ssd) {
      const auto t0 = std::chrono::steady_clock::now();
      for (const auto& d : ssd_detect(*ssd, image, o)) ssd_out.boxes.push_back(d.box);
      ssd_out.ms = ms_since(t0);
    }
    if (tiny) {
      const auto t0 = std::chrono::steady_clock::now();
      // About the image's own resolution (the package's default 416 loses small faces).
      const int side = std::max(image.cols, image.rows);
      const int input_px = std::clamp((side + 31) / 32 * 32, 32, o.tiny_max_input_px);
      for (const auto& d : tiny->detect(image, input_px, o.tiny_min_score))
        tiny_out.boxes.push_back(d.box);
      tiny_out.ms = ms_since(t0);
    }
    if (haar) {
      const auto t0 = std::chrono::steady_clock::now();
      haar_out.boxes = boxes_of(haar->detect(image));
      haar_out.ms = ms_since(t0);
    }
    if (haar_wide) {
      const auto t0 = std::chrono::steady_clock::now();
      wide_out.boxes = boxes_of(haar_wide->detect(image));
      wide_out.ms = ms_since(t0);
    }
    if (hog) {
      const auto t0 = std::chrono::steady_clock::now();
      hog_out.boxes = boxes_of(hog->detect(image));
      hog_out.ms = ms_since(t0);
    }
    // fit(which, b, cnn_b): landmarker `which` from box b; in the +switch family face-api's CNN
    // starts from cnn_b (ssd_paired: the SSD's box, in the CNN's own convention), dlib from b.
    std::map<std::tuple<int, double, double, double, double, double, double, double, double>, Fit>
        cache;
    std::function<Result<const Fit*>(int, const cv::Rect2d&, const cv::Rect2d&)> fit;
    fit = [&](int which, const cv::Rect2d& b, const cv::Rect2d& cnn_b) -> Result<const Fit*> {
      // The CNN alone depends on its own box only: one cache entry per box for every chain.
      if (which == 2 && b != cnn_b) return fit(2, cnn_b, cnn_b);
      const auto key = std::make_tuple(which, b.x, b.y, b.width, b.height, cnn_b.x, cnn_b.y,
                                       cnn_b.width, cnn_b.height);
      if (auto f = cache.find(key); f != cache.end()) return &f->second;
      const auto t0 = std::chrono::steady_clock::now();
      Fit f;
      if (which <= 2) {
        auto p = (which == 2 ? cnn.get() : landmarkers[which])->fit_with_spread(image, b);
        if (!p) return tl::unexpected(p.error());
        f.fit = std::move(*p);
        f.ms = ms_since(t0);
      } else {
        auto c = fit(2, cnn_b, cnn_b);
        if (!c) return tl::unexpected(c.error());
        f.ms = (*c)->ms;
        if (which == 5 || which == 6 || which == 7) {
          // 6: dlib's box from the CNN's points (the detector's box in dlib's convention).
          const cv::Rect2d dlib_box =
              which == 6 && (*c)->fit
                  ? landmarkers[0]->box_for_extent(points_extent((*c)->fit->points))
                  : b;
          auto plain_fit = fit(0, dlib_box, dlib_box);
          if (!plain_fit) return tl::unexpected(plain_fit.error());
          // The fit kept where dlib is confident: +tta's, or with 7 (the pipeline's rule,
          // face_landmarks' cnn_fallback) the plain fit itself.
          const Fit* kept = *plain_fit;
          if (which != 7) {
            auto d = fit(1, dlib_box, dlib_box);
            if (!d) return tl::unexpected(d.error());
            kept = *d;
          }
          f.ms += (*plain_fit)->ms + (kept != *plain_fit ? kept->ms : 0.0);
          const bool confident =
              (*plain_fit)->fit && kept->fit &&
              fl::spread_confidence((*plain_fit)->fit->spread) >= o.switch_min_confidence;
          f.fit = confident ? kept->fit : (*c)->fit;
          if (confident || !f.fit) {
          } else if ((*plain_fit)->fit) {  // the CNN's points; spread = its distance from dlib's
            const double d = fl::mean_point_distance(f.fit->points, (*plain_fit)->fit->points);
            if (std::isfinite(d)) f.fit->spread = d;
          }
        } else if (which == 3) {  // mean of dlib+tta and the CNN; spread = their disagreement
          auto d = fit(1, b, b);
          if (!d) return tl::unexpected(d.error());
          f.ms += (*d)->ms;
          if ((*c)->fit && (*d)->fit) {
            LandmarkFitResult m;
            const auto& a = (*c)->fit->points;
            const auto& e = (*d)->fit->points;
            double sum = 0;
            for (size_t k = 0; k < a.size(); ++k) {
              m.points.push_back(0.5 * (a[k] + e[k]));
              sum += 0.5 * cv::norm(a[k] - e[k]);
            }
            const double dist = cv::norm(m.points[36] - m.points[45]);
            if (dist > 0) m.spread = sum / static_cast<double>(a.size()) / dist;
            f.fit = std::move(m);
          } else {
            f.fit = (*d)->fit ? (*d)->fit : (*c)->fit;
          }
        } else if ((*c)->fit) {  // 4: dlib+tta started from the CNN's points
          const auto t1 = std::chrono::steady_clock::now();
          auto p = landmarkers[1]->fit_with_spread(
              image, landmarkers[1]->box_for_extent(points_extent((*c)->fit->points)));
          if (!p) return tl::unexpected(p.error());
          f.fit = std::move(*p);
          f.ms += ms_since(t1);
        }
      }
      return &cache.emplace(key, std::move(f)).first->second;
    };
    for (const Chain& c : chains) {
      std::vector<cv::Rect2d> boxes;
      double detect_ms = 0;
      if (c.detector == "haar") boxes = haar_out.boxes, detect_ms = haar_out.ms;
      if (c.detector == "hog") boxes = hog_out.boxes, detect_ms = hog_out.ms;
      if (c.detector == "hog_haar") {
        boxes = hog_out.boxes.empty() ? wide_out.boxes : hog_out.boxes;
        detect_ms = hog_out.ms + (hog_out.boxes.empty() ? wide_out.ms : 0.0);
      }
      if (c.detector == "union") {
        boxes = merge(hog_out.boxes, wide_out.boxes);
        detect_ms = hog_out.ms + wide_out.ms;
      }
      if (c.detector == "tiny") boxes = tiny_out.boxes, detect_ms = tiny_out.ms;
      if (c.detector == "tiny_union") {  // the same boxes, tiny's kept where they overlap
        boxes = merge(tiny_out.boxes, merge(hog_out.boxes, wide_out.boxes));
        detect_ms = hog_out.ms + wide_out.ms + tiny_out.ms;
      }
      if (c.detector == "union_tiny") {
        boxes = merge(merge(hog_out.boxes, wide_out.boxes), tiny_out.boxes);
        detect_ms = hog_out.ms + wide_out.ms + tiny_out.ms;
      }
      if (c.detector == "ssd") boxes = ssd_out.boxes, detect_ms = ssd_out.ms;
      if (c.detector == "union_ssd") {
        boxes = merge(merge(hog_out.boxes, wide_out.boxes), ssd_out.boxes);
        detect_ms = hog_out.ms + wide_out.ms + ssd_out.ms;
      }
      if (c.detector == "ssd_union") {  // the same boxes, SSD's kept where they overlap
        boxes = merge(ssd_out.boxes, merge(hog_out.boxes, wide_out.boxes));
        detect_ms = hog_out.ms + wide_out.ms + ssd_out.ms;
      }
      if (c.detector == "union_tiny_ssd") {
        boxes = merge(merge(merge(hog_out.boxes, wide_out.boxes), tiny_out.boxes), ssd_out.boxes);
        detect_ms = hog_out.ms + wide_out.ms + tiny_out.ms + ssd_out.ms;
      }
      // Where the landmarker starts: the reported box, except in ssd_hybrid and ssd_paired
      // (below); cnn_starts: where face-api's CNN starts (ssd_paired: the reported box).
      std::vector<cv::Rect2d> starts = boxes;
      if (c.detector == "ssd_hybrid" || c.detector == "ssd_paired") {
        // ssd_union's boxes; dlib starts from a union box
        const std::vector<cv::Rect2d> union_boxes = merge(hog_out.boxes, wide_out.boxes);
        boxes = merge(ssd_out.boxes, union_boxes);
        detect_ms = hog_out.ms + wide_out.ms + ssd_out.ms;
        starts = boxes;
        for (size_t k = 0; k < ssd_out.boxes.size(); ++k) {
          double best = 0.3;  // the merge's overlap rule
          for (const cv::Rect2d& u : union_boxes)
            if (const double v = iou(boxes[k], u); v >= best) best = v, starts[k] = u;
        }
      }
      const std::vector<cv::Rect2d>& cnn_starts = c.detector == "ssd_paired" ? boxes : starts;
      std::vector<const Fit*> fits;
      for (size_t k = 0; k < starts.size(); ++k) {
        const cv::Rect2d& b = starts[k];
        // +cnn_switch: only face-api's boxes reach dlib through the CNN; HOG/Haar boxes are
        // dlib's convention (or near it) and go to it directly, as +switch.
        const bool face_api_box =
            std::find(tiny_out.boxes.begin(), tiny_out.boxes.end(), b) != tiny_out.boxes.end() ||
            std::find(ssd_out.boxes.begin(), ssd_out.boxes.end(), b) != ssd_out.boxes.end();
        auto f = fit(c.landmarker == 6 && !face_api_box ? 5 : c.landmarker, b, cnn_starts[k]);
        if (!f) return tl::unexpected(f.error());
        fits.push_back(*f);
      }
      FaceResult r = score(boxes, fits, detect_ms, truth, truth_box, o.min_iou);
      face[c.name] = {{"nme", r.nme && std::isfinite(*r.nme) ? nlohmann::json(*r.nme)
                                                             : nlohmann::json(nullptr)},
                      {"best_iou", r.best_iou},
                      {"detections", r.detections},
                      {"spread", r.spread && std::isfinite(*r.spread) ? nlohmann::json(*r.spread)
                                                                      : nlohmann::json(nullptr)}};
      scores[c.name].faces.push_back(r);
    }
    // The landmarker alone, started from the annotated points' box in its own convention: the
    // top chain's landmarker (from_box) and the pipeline's (from_box_plain).
    for (int pass = 0; pass < (cnn ? 3 : 2); ++pass) {
      const int which = pass == 0 ? (top_chain.tta ? 1 : 0) : 0;
      const fl::Landmarker& lm = pass == 2 ? *cnn : *landmarkers[which];
      const auto t0 = std::chrono::steady_clock::now();
      auto p = lm.fit_with_spread(image, lm.box_for_extent(truth_box));
      if (!p) return tl::unexpected(p.error());
      FaceResult r;
      r.ms = ms_since(t0);
      r.detected = true;
      if (*p) {
        r.nme = nme_outer_corners((*p)->points, truth);
        r.eye_error = eye_center_error((*p)->points, truth);
        r.spread = (*p)->spread;
        if (pass >= 1) {  // systematic offset and scale of the landmarker vs the annotations
          const size_t b = pass - 1;
          for (size_t k = 0; k < truth.size(); ++k) bias[b] += (*p)->points[k] - truth[k];
          const cv::Rect2d e = points_extent((*p)->points);
          width_ratio[b] += e.width / truth_box.width;
          height_ratio[b] += e.height / truth_box.height;
          ++fitted[b];
        }
      } else {
        r.nme = r.eye_error = std::numeric_limits<double>::infinity();
      }
      const char* key = pass == 0 ? "from_box" : pass == 1 ? "from_box_plain" : "from_box_cnn";
      face[key] = r.nme && std::isfinite(*r.nme) ? nlohmann::json(*r.nme) : nlohmann::json(nullptr);
      (pass == 0 ? from_box : pass == 1 ? from_box_plain : from_box_cnn).faces.push_back(r);
    }
    per_face.push_back(std::move(face));
    if (progress) progress(static_cast<double>(i + 1) / static_cast<double>(items.size()));
  }

  EvalReport report;
  report.task = "landmarks";
  report.dataset = o.dataset;
  report.items = items.size();
  std::string names;
  for (const std::string& c : o.detectors) names += (names.empty() ? "" : ", ") + c;
  report.protocol = fmt::format(
      "every annotated face (NAME.jpg + NAME.pts{}): detector chains {} on the same images, a "
      "face detected when a detector box has IoU >= {} with the box of the annotated points; "
      "68-point dlib landmarks (refit_passes {}; +tta: median of fits from box scales and the "
      "mirrored face) on the matched detection; NME = mean point error / outer-eye-corner "
      "distance (points 37, 46); failure = NME > {}; from_box = the top chain's landmarker "
      "from the annotated points' box (from_box_plain: the pipeline's landmarker); SSD {}",
      o.stride > 1 ? fmt::format(", every {}th", o.stride) : "", names, o.min_iou,
      o.landmark_refit_passes, o.failure_nme,
      o.ssd_tiles ? fmt::format("on the whole image and on 2 x 2 tiles of {} of it (images over "
                                "768 px)",
                                o.ssd_tile_fraction)
                  : std::string("on the whole image only"));
  const ChainScores& top = scores.at(top_chain.name);
  report.metrics = top.metrics(o.failure_nme, true);
  report.metrics["from_box"] = from_box.metrics(o.failure_nme, false);
  report.metrics["from_box_plain"] = from_box_plain.metrics(o.failure_nme, false);
  if (cnn) report.metrics["from_box_cnn"] = from_box_cnn.metrics(o.failure_nme, false);
  for (size_t b = 0; b < 2; ++b) {
    if (fitted[b] == 0) continue;
    const double n = static_cast<double>(fitted[b]), n_pts = n * 68;
    nlohmann::json& m = report.metrics[b == 0 ? "from_box_plain" : "from_box_cnn"];
    m["mean_offset_px"] = {bias[b].x / n_pts, bias[b].y / n_pts};
    m["extent_ratio"] = {width_ratio[b] / n, height_ratio[b] / n};  // fitted / annotated
  }
  report.timing["ms_per_face_median"] = number_or_null(top.ms_median());
  report.timing["from_box"] = {{"ms_per_face_median", number_or_null(from_box.ms_median())}};
  report.timing["from_box_plain"] = {
      {"ms_per_face_median", number_or_null(from_box_plain.ms_median())}};
  if (cnn)
    report.timing["from_box_cnn"] = {
        {"ms_per_face_median", number_or_null(from_box_cnn.ms_median())}};
  nlohmann::json chain_names = nlohmann::json::array();
  for (const Chain& c : chains) {
    chain_names.push_back(c.name);
    report.metrics[c.name] = scores.at(c.name).metrics(o.failure_nme, true);
    report.timing[c.name] = {{"ms_per_face_median", number_or_null(scores.at(c.name).ms_median())}};
  }
  report.extra = {{"detectors", chain_names}, {"per_face", per_face}};
  return report;
}

}  // namespace dreamsense::eval::landmarks
