// Experiment tool (issue 20, FER2013): dumps face-api features of every face of an expression
// dataset under several crop transforms, so that heads and augmentations can be compared
// quickly on the same folds (fer_cv.cpp). Not part of the pipeline.
//   fer_features DATASET DIR OUT.bin
// Layout: int32 n, int32 T, int32 per_transform, int32 extra; then per item int32 label index
// (kExpressionLabels order), int32 has_face, float[T * per_transform + extra].
// Per transform: pooled 256, logits 7, dense3 2x2 grid means (1024), dense2 global mean (128).
// Extra: landmark-net pooled 256 and recognition descriptor 128 of the untransformed crop.
#include "dreamsense/eval/faces/datasets.hpp"
#include "dreamsense/expression/labels.hpp"
#include "dreamsense/face_detection/face_detector.hpp"
#include "dreamsense/vision/face_alignment.hpp"
#include "dreamsense/vision/face_api_net.hpp"
#include "dreamsense/vision/face_crops.hpp"
#include "dreamsense/vision/face_locator.hpp"
#include "dreamsense/vision/image_io.hpp"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <string>

using namespace dreamsense;

namespace {

struct Jitter {
  bool mirror = false;
  double rot_deg = 0, scale = 1, dx = 0, dy = 0;  // dx, dy in crop fractions
};

// The face's crop transform composed with a similarity about the crop centre.
vision::AlignedFace jitter(const vision::AlignedFace& f, const Jitter& j) {
  vision::AlignedFace g = j.mirror ? vision::mirror_face(f) : f;
  const double s = f.grey.cols, c = (s - 1) / 2.0;
  const double a = j.rot_deg * CV_PI / 180.0;
  const double ca = j.scale * std::cos(a), sa = j.scale * std::sin(a);
  const cv::Matx33d m(ca, -sa, c - ca * c + sa * c + j.dx * s, sa, ca,
                      c - sa * c - ca * c + j.dy * s, 0, 0, 1);
  const cv::Matx23d& t = g.crop_from_image;
  const cv::Matx33d t3(t(0, 0), t(0, 1), t(0, 2), t(1, 0), t(1, 1), t(1, 2), 0, 0, 1);
  const cv::Matx33d r = m * t3;
  g.crop_from_image = cv::Matx23d(r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2));
  return g;
}

void grid_means(const cv::Mat& map, int channels, int side, int cells, std::vector<float>& out) {
  // overlapping cells: cell k covers [k * step, k * step + width)
  const int width = (side + cells - 1) / cells + (cells > 1 ? 1 : 0);
  const int step = cells > 1 ? (side - width) / (cells - 1) : 0;
  const float* p = map.ptr<float>();
  for (int cy = 0; cy < cells; ++cy)
    for (int cx = 0; cx < cells; ++cx)
      for (int ch = 0; ch < channels; ++ch) {
        double acc = 0;
        int n = 0;
        for (int y = cy * step; y < std::min(side, cy * step + (cells > 1 ? width : side)); ++y)
          for (int x = cx * step; x < std::min(side, cx * step + (cells > 1 ? width : side)); ++x) {
            acc += p[(static_cast<size_t>(ch) * side + y) * side + x];
            ++n;
          }
        out.push_back(static_cast<float>(acc / n));
      }
}

// A 112 px view of the face framed like FER2013's crops: eye distance d and eye row r of the
// side, with the roll corrected (aligned) or kept (upright), from the face's eye positions.
cv::Mat framed(const cv::Mat& grey, const vision::AlignedFace& f, double d, double r, bool upright,
               bool mirror) {
  const vision::AlignmentOptions a;
  const double S = f.grey.cols;
  cv::Matx23d inv;
  cv::invertAffineTransform(f.crop_from_image, inv);
  auto img = [&](double x, double y) {
    return cv::Point2d(inv(0, 0) * x + inv(0, 1) * y + inv(0, 2),
                       inv(1, 0) * x + inv(1, 1) * y + inv(1, 2));
  };
  const cv::Point2d re = img((0.5 - a.eye_distance / 2) * S, a.eye_row * S),
                    le = img((0.5 + a.eye_distance / 2) * S, a.eye_row * S);
  const double side = 112, iod = std::hypot(le.x - re.x, le.y - re.y);
  const double s = d * side / iod;
  const double ang = upright ? 0 : std::atan2(le.y - re.y, le.x - re.x);
  const double c = s * std::cos(ang), sn = s * std::sin(ang);
  const cv::Point2d mid = (re + le) * 0.5;
  // crop = R(-ang) * s * (p - mid) + (side/2, r*side)
  cv::Matx23d t(c, sn, 0, -sn, c, 0);
  t(0, 2) = side / 2 - (t(0, 0) * mid.x + t(0, 1) * mid.y);
  t(1, 2) = r * side - (t(1, 0) * mid.x + t(1, 1) * mid.y);
  cv::Mat out;
  cv::warpAffine(grey, out, cv::Mat(t), cv::Size(112, 112), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  if (mirror) cv::flip(out, out, 1);
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4 && argc != 6) {
    std::fprintf(stderr, "usage: fer_features DATASET DIR OUT.bin [FIRST END]\n");
    return 2;
  }
  auto items = eval::faces::read_expression_dataset(argv[1], argv[2]);
  if (!items) {
    std::fprintf(stderr, "%s\n", items.error().message.c_str());
    return 1;
  }
  vision::FaceCropOptions crop;
  crop.alignment = vision::AlignmentOptions{};
  auto landmarker = vision::load_landmarker();
  auto aligner = vision::make_face_crop_aligner(crop, *landmarker);
  auto net = vision::FaceApiExpressionNet::load(vision::default_face_api_model_dir());
  auto lnet = vision::FaceApiLandmarkNet::load(vision::default_face_api_model_dir());
  auto rnet = vision::FaceApiRecognitionNet::load(vision::default_face_api_model_dir());
  if (!aligner || !net || !lnet || !rnet) {
    std::fprintf(stderr, "cannot load models\n");
    return 1;
  }
  std::vector<Jitter> jitters;
  for (bool mirror : {false, true}) {
    jitters.push_back({mirror, 0, 1, 0, 0});
    jitters.push_back({mirror, 10, 1, 0, 0});
    jitters.push_back({mirror, -10, 1, 0, 0});
    jitters.push_back({mirror, 0, 1.1, 0, 0});
    jitters.push_back({mirror, 0, 0.9, 0, 0});
    jitters.push_back({mirror, 0, 1, 0.05, 0});
    jitters.push_back({mirror, 0, 1, -0.05, 0});
    jitters.push_back({mirror, 0, 1, 0, 0.05});
    jitters.push_back({mirror, 0, 1, 0, -0.05});
  }
  // FER_MODE=crops: pooled + logits only, of other framings: the whole image, the package's
  // crop (landmark box + 10 %), zoomed-out aligned crops (x0.8, x0.7); each with its mirror.
  // Extra: the alignment source (0 landmarks, 1 landmarks on the crop, 2 crop geometry).
  const bool crops_mode = std::getenv("FER_MODE") != nullptr;
  // FER_MODE=detbox: views 0 whole image, 1 aligned crop, 2 package box, 3-5 the cascade's own
  // box (as the aligner finds it; whole image when it finds none) grown x1.0, x1.2, x1.4.
  const bool detbox = crops_mode && std::string(std::getenv("FER_MODE")) == "detbox";
  auto detector = face_detection::FaceDetector::create(vision::crop_finder_options(crop));
  if (!detector) return 1;
  const int T = detbox ? 12 : crops_mode ? 8 : static_cast<int>(jitters.size());
  const int per = crops_mode ? 263 : 256 + 7 + 1024 + 128, extra = crops_mode ? 1 : 256 + 128;
  std::ofstream out(argv[3], std::ios::binary);
  const int header[4] = {static_cast<int>(items->size()), T, per, extra};
  out.write(reinterpret_cast<const char*>(header), sizeof header);
  cv::setNumThreads(1);
  const size_t first = argc == 6 ? std::stoul(argv[4]) : 0,
               end = argc == 6 ? std::min(items->size(), std::stoul(argv[5])) : items->size();
  for (size_t i = first; i < end; ++i) {
    const auto& it = (*items)[i];
    auto grey = vision::read_grey_image(it.path);
    if (!grey) return 1;
    auto face = aligner->align(*grey);
    if (!face) return 1;
    int label = 0;
    for (; label < static_cast<int>(std::size(expression::kExpressionLabels)); ++label)
      if (it.label == expression::kExpressionLabels[label]) break;
    if (std::getenv("FER_STATS")) {  // eye geometry of the given crops (landmark faces only)
      if (*face && !(*face)->landmarks.empty()) {
        cv::Matx23d inv;
        cv::invertAffineTransform((*face)->crop_from_image, inv);
        const auto pts = vision::transform_points(inv, (*face)->landmarks);
        const auto [r, l] = vision::eye_centres(pts);
        const double iod = std::hypot(l.x - r.x, l.y - r.y);
        std::printf("%d %.4f %.4f %.4f %.4f\n", static_cast<int>((*face)->source), iod / grey->cols,
                    (r.y + l.y) / 2 / grey->rows, (r.x + l.x) / 2 / grey->cols,
                    std::atan2(l.y - r.y, l.x - r.x) * 180 / CV_PI);
      }
      continue;
    }
    const int has = *face ? 1 : 0;
    out.write(reinterpret_cast<const char*>(&label), 4);
    out.write(reinterpret_cast<const char*>(&has), 4);
    std::vector<float> v;
    v.reserve(static_cast<size_t>(T * per + extra));
    if (*face && crops_mode) {
      const vision::AlignedFace& f = **face;
      std::vector<cv::Mat> views;
      views.push_back(*grey);
      cv::Rect box(0, 0, grey->cols, grey->rows);
      if (!f.landmarks.empty()) {
        cv::Matx23d inv;
        cv::invertAffineTransform(f.crop_from_image, inv);
        box = vision::face_api_crop(vision::transform_points(inv, f.landmarks), grey->size());
        if (box.area() < 16) box = cv::Rect(0, 0, grey->cols, grey->rows);
      }
      views.push_back((*grey)(box).clone());
      if (detbox) {
        views.clear();
        views.push_back(*grey);
        views.push_back(vision::resample_face(*grey, f, vision::kFaceApiInputPx));
        views.push_back((*grey)(box).clone());
        const double k = static_cast<double>(crop.working_px) / std::min(grey->cols, grey->rows);
        cv::Mat work;
        cv::resize(*grey, work, cv::Size(), k, k, cv::INTER_LINEAR);
        cv::Rect2d det(0, 0, grey->cols, grey->rows);
        double best = 0;
        for (const auto& d : detector->detect(work, std::nullopt, false))
          if (d.box_px.area() > best) {
            best = d.box_px.area();
            det =
                cv::Rect2d(d.box_px.x / k, d.box_px.y / k, d.box_px.width / k, d.box_px.height / k);
          }
        for (double grow : {1.0, 1.2, 1.4}) {
          const double side = std::max(det.width, det.height) * grow;
          const double cx = det.x + det.width / 2, cy = det.y + det.height / 2;
          const double s = 112.0 / side;
          const cv::Matx23d t(s, 0, 56 - s * cx, 0, s, 56 - s * cy);
          cv::Mat v;
          cv::warpAffine(*grey, v, cv::Mat(t), cv::Size(112, 112), cv::INTER_LINEAR,
                         cv::BORDER_REPLICATE);
          views.push_back(v);
        }
      } else if (std::string(std::getenv("FER_MODE")) == "frames") {
        views.clear();
        views.push_back(framed(*grey, f, 0.36, 0.40, true, false));
        views.push_back(framed(*grey, f, 0.36, 0.40, false, false));
        views.push_back(framed(*grey, f, 0.40, 0.40, true, false));
        views.push_back(framed(*grey, f, 0.33, 0.40, true, false));
      } else {
        views.push_back(vision::resample_face(*grey, jitter(f, {false, 0, 0.8, 0, 0}), 112));
        views.push_back(vision::resample_face(*grey, jitter(f, {false, 0, 0.7, 0, 0}), 112));
      }
      for (const cv::Mat& view : views)
        for (bool mirror : {false, true}) {
          cv::Mat c = view;
          if (mirror) cv::flip(view, c, 1);
          const vision::FaceApiOutput r = net->run(c);
          v.insert(v.end(), r.features.begin(), r.features.end());
          v.insert(v.end(), r.logits.begin(), r.logits.end());
        }
      v.push_back(static_cast<float>(static_cast<int>(f.source)));
    } else if (*face) {
      for (const Jitter& j : jitters) {
        const vision::AlignedFace g = jitter(**face, j);
        const cv::Mat c = vision::resample_face(*grey, g, vision::kFaceApiInputPx);
        cv::Mat d2, d3;
        const vision::FaceApiOutput r = net->run(c, &d2, &d3);
        v.insert(v.end(), r.features.begin(), r.features.end());
        v.insert(v.end(), r.logits.begin(), r.logits.end());
        grid_means(d3, 256, 7, 2, v);
        grid_means(d2, 128, 14, 1, v);
      }
      const cv::Mat c = vision::resample_face(*grey, **face, vision::kFaceApiInputPx);
      const std::vector<float> lf = lnet->features(c);
      v.insert(v.end(), lf.begin(), lf.end());
      const cv::Mat c150 = vision::resample_face(*grey, **face, vision::kFaceApiRecognitionInputPx);
      const std::vector<float> rf = rnet->describe(c150);
      v.insert(v.end(), rf.begin(), rf.end());
    } else {
      v.assign(static_cast<size_t>(T * per + extra), 0.f);
    }
    if (v.size() != static_cast<size_t>(T * per + extra)) {
      std::fprintf(stderr, "size mismatch %zu\n", v.size());
      return 1;
    }
    out.write(reinterpret_cast<const char*>(v.data()), static_cast<std::streamsize>(v.size() * 4));
    if (i % 100 == 0) std::fprintf(stderr, "%zu/%zu\n", i, items->size());
  }
  return 0;
}
