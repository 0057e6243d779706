#include "dreamsense/eval/faces/expression_eval.hpp"

#include "dreamsense/eval/classification.hpp"
#include "dreamsense/eval/faces/datasets.hpp"
#include "dreamsense/expression/labels.hpp"
#include "dreamsense/vision/face_locator.hpp"
#include "dreamsense/vision/image_io.hpp"

#include <opencv2/core.hpp>

#include <algorithm>
#include <chrono>
#include <map>
#include <set>

namespace dreamsense::eval::faces {
namespace {

using expression::ExpressionFeatureExtractor;
using expression::ExpressionMethod;
using expression::ExpressionModel;

struct PreparedFace {
  cv::Mat grey;
  std::optional<vision::AlignedFace> face;
  double align_ms = 0;
};

// Reads and aligns every item (single thread, in order).
Result<std::vector<PreparedFace>> prepare(const std::vector<FaceImageItem>& items,
                                          vision::FaceCropOptions crop,
                                          const vision::AlignmentOptions& alignment,
                                          const Progress& progress, double p0, double p1) {
  crop.alignment = alignment;
  auto landmarker = vision::load_landmarker();
  if (!landmarker) return tl::unexpected(landmarker.error());
  auto aligner = vision::make_face_crop_aligner(crop, *landmarker);
  if (!aligner) return tl::unexpected(aligner.error());
  std::vector<PreparedFace> out(items.size());
  for (size_t i = 0; i < items.size(); ++i) {
    auto grey = vision::read_grey_image(items[i].path);
    if (!grey) return tl::unexpected(grey.error());
    out[i].grey = *grey;
    const auto t0 = std::chrono::steady_clock::now();
    auto face = aligner->align(*grey);
    out[i].align_ms = ms_since(t0);
    if (!face)
      return make_error(face.error().code, "{}: {}", items[i].path.string(), face.error().message);
    out[i].face = std::move(*face);
    if (progress && (i % 16 == 0)) progress(p0 + (p1 - p0) * (i + 1.0) / items.size());
  }
  return out;
}

nlohmann::json alignment_counts(const std::vector<PreparedFace>& faces) {
  std::map<std::string, size_t> n{
      {"landmarks", 0}, {"landmarks_from_crop", 0}, {"crop_geometry", 0}, {"no_face", 0}};
  for (const auto& f : faces) ++n[f.face ? vision::to_string(f.face->source) : "no_face"];
  return n;
}

std::vector<std::string> ordered_labels(const std::set<std::string>& present) {
  std::vector<std::string> out;
  for (const char* l : expression::kExpressionLabels)
    if (present.count(l)) out.emplace_back(l);
  return out;
}

std::string block_key(const ExpressionMethod& m, const std::string& block) {
  const auto& f = m.features;
  const auto& a = f.alignment;
  const std::string geometry = fmt::format("{}/{}/{}/{}/{}|", a.size, a.eye_distance, a.eye_row,
                                           a.dlib_template, a.template_padding);
  if (block == "lbp1" || block == "lbp2")
    return geometry + fmt::format("{}/{}/{}", block, f.lbp_grid, f.lbp_sqrt);
  if (block == "hog") return geometry + fmt::format("hog/{}/{}", f.hog.cell_px, f.hog.bins);
  if (block == "face_api" || block == "face_api_box")
    return geometry + fmt::format("{}/{}", block, f.face_api_flip);
  return geometry + block;
}

std::string jitter_key(const expression::FaceJitter& j) {
  return j.identity() ? std::string("|")
                      : fmt::format("{}/{}/{}/{}/{}|", j.mirror, j.rotation_deg, j.scale, j.shift_x,
                                    j.shift_y);
}

// Per-face cost once the landmarks are known: warp + descriptors + classifier, one thread.
std::vector<double> time_recognizer(expression::ExpressionRecognizer& r,
                                    const std::vector<PreparedFace>& faces,
                                    const std::vector<size_t>& which, size_t max_items) {
  const int threads = cv::getNumThreads();
  cv::setNumThreads(1);
  std::vector<double> ms;
  for (size_t k = 0; k < which.size() && ms.size() < max_items; ++k) {
    const PreparedFace& p = faces[which[k]];
    if (!p.face) continue;
    const auto t0 = std::chrono::steady_clock::now();
    const vision::AlignedFace f = vision::warp_face(
        p.grey, p.face->crop_from_image, r.model().method().features.alignment, p.face->source);
    vision::AlignedFace with_landmarks = f;
    with_landmarks.landmarks = p.face->landmarks;
    (void)r.recognize(p.grey, with_landmarks);
    ms.push_back(ms_since(t0));
  }
  cv::setNumThreads(threads);
  return ms;
}

Result<std::vector<ExpressionMethod>> methods_of(const std::vector<std::string>& names) {
  std::vector<ExpressionMethod> out;
  for (const std::string& n : names) {
    auto m = expression::expression_method(n);
    if (!m) return tl::unexpected(m.error());
    out.push_back(std::move(*m));
  }
  if (out.empty()) return make_error(ErrorCode::kInvalidArgument, "no expression method given");
  return out;
}

}  // namespace

Status ExpressionEvalOptions::check() const {
  if (folds < 2) return make_error(ErrorCode::kInvalidArgument, "--folds must be >= 2");
  if (methods.empty()) return make_error(ErrorCode::kInvalidArgument, "no expression method");
  return crop.check();
}

Status ExpressionTrainOptions::check() const { return crop.check(); }

std::vector<std::string> classes_missing_from_model(const std::vector<std::string>& dataset_labels,
                                                    const std::vector<std::string>& model_labels) {
  std::vector<std::string> out;
  for (const std::string& l : dataset_labels)
    if (std::find(model_labels.begin(), model_labels.end(), l) == model_labels.end() &&
        std::find(out.begin(), out.end(), l) == out.end())
      out.push_back(l);
  return out;
}

std::map<std::string, std::string> dataset_class_names(const std::string& dataset) {
  if (dataset == "fer2013")
    return {{"anger", "angry"},      {"disgust", "disgust"}, {"fear", "fear"},
            {"happy", "happy"},      {"neutral", "neutral"}, {"sadness", "sad"},
            {"surprise", "surprise"}};
  std::map<std::string, std::string> same;
  for (const char* l : expression::kExpressionLabels) same[l] = l;
  return same;
}

Result<EvalReport> run_expression_eval(const ExpressionEvalOptions& o, const Progress& progress) {
  if (auto s = o.check(); !s) return tl::unexpected(s.error());
  auto items = read_expression_dataset(o.dataset, o.dir);
  if (!items) return tl::unexpected(items.error());
  std::set<std::string> present;
  for (const auto& it : *items) present.insert(it.label);

  EvalReport report;
  report.task = "expression";
  report.dataset = o.dataset;
  report.items = items->size();

  if (!o.model.empty()) {  // train elsewhere, test here
    auto model = ExpressionModel::load(o.model);
    if (!model) return tl::unexpected(model.error());
    const std::vector<std::string> missing =
        classes_missing_from_model(ordered_labels(present), model->labels());
    for (const auto& l : model->labels()) present.insert(l);
    auto faces = prepare(*items, o.crop, model->method().features.alignment, progress, 0.0, 0.6);
    if (!faces) return tl::unexpected(faces.error());
    auto recognizer = expression::ExpressionRecognizer::create(*model);
    if (!recognizer) return tl::unexpected(recognizer.error());
    ConfusionMatrix cm(ordered_labels(present), "no_face");
    for (size_t i = 0; i < items->size(); ++i) {
      const auto& f = (*faces)[i];
      cm.add((*items)[i].label, f.face ? recognizer->recognize(f.grey, *f.face).label : "no_face");
      if (progress && i % 16 == 0) progress(0.6 + 0.35 * (i + 1.0) / items->size());
    }
    std::vector<size_t> all(items->size());
    for (size_t i = 0; i < all.size(); ++i) all[i] = i;
    const auto ms = time_recognizer(*recognizer, *faces, all, 300);
    std::vector<double> align_ms;
    for (const auto& f : *faces) align_ms.push_back(f.align_ms);
    std::string missing_note;
    for (const auto& l : missing) missing_note += (missing_note.empty() ? "" : ", ") + l;
    // A model with its own (fine-tuned) network names it: the method string alone is the same.
    const auto& network = model->method().features.face_api_dir;
    // So does a second network mixed in (xception_weight).
    const double second = model->method().xception_weight;
    report.protocol = fmt::format(
        "model {} (method {}{}{}, trained on {} {} images) tested on every image of {}; faces "
        "aligned by cascade + dlib landmarks with crop fallbacks{}",
        o.model.string(), model->method().name,
        network.empty() ? std::string() : ", own network " + network.lexically_normal().string(),
        second > 0 ? fmt::format(", mixed with O. Arriaga's FER2013 network, weight {}", second)
                   : std::string(),
        model->training().items, model->training().dataset, o.dir.string(),
        missing.empty()
            ? std::string()
            : fmt::format("; classes the model lacks (counted wrong): {}", missing_note));
    report.metrics = {{"accuracy", number_or_null(cm.accuracy())},
                      {"balanced_accuracy", number_or_null(cm.balanced_accuracy())},
                      {"confusion", cm.confusion_json()},
                      {model->method().name,
                       {{"accuracy", number_or_null(cm.accuracy())},
                        {"balanced_accuracy", number_or_null(cm.balanced_accuracy())}}}};
    report.per_class = cm.per_class_json();
    report.timing = {{"ms_per_face_median", number_or_null(median(ms))},
                     {"ms_alignment_median", number_or_null(median(align_ms))}};
    report.extra = {{"alignment", alignment_counts(*faces)},
                    {"methods", {model->method().name}},
                    {"model", o.model.string()},
                    {"model_labels", model->labels()},
                    {"classes_missing_from_model", missing},
                    {"dataset_class_names", dataset_class_names(o.dataset)}};
    if (progress) progress(1.0);
    return report;
  }

  auto methods = methods_of(o.methods);
  if (!methods) return tl::unexpected(methods.error());
  // Every image aligned once per distinct alignment geometry (the crop path's decisions, and so
  // which images have a face, do not depend on the geometry).
  std::vector<std::pair<vision::AlignmentOptions, std::vector<PreparedFace>>> aligned;
  std::vector<size_t> geometry_of(methods->size());
  for (size_t mi = 0; mi < methods->size(); ++mi) {
    const auto& a = (*methods)[mi].features.alignment;
    auto it =
        std::find_if(aligned.begin(), aligned.end(), [&](const auto& p) { return p.first == a; });
    if (it == aligned.end()) {
      auto prepared = prepare(*items, o.crop, a, progress, 0.0, 0.4);
      if (!prepared) return tl::unexpected(prepared.error());
      aligned.emplace_back(a, std::move(*prepared));
      it = aligned.end() - 1;
    }
    geometry_of[mi] = static_cast<size_t>(it - aligned.begin());
  }
  const std::vector<PreparedFace>* faces = &aligned.front().second;
  auto faces_of = [&](size_t mi) -> const std::vector<PreparedFace>& {
    return aligned[geometry_of[mi]].second;
  };

  // Descriptor blocks, computed once per image and shared by the methods that use them.
  std::vector<ExpressionFeatureExtractor> extractors;
  for (const auto& m : *methods) {
    auto e = ExpressionFeatureExtractor::create(m.features);
    if (!e) return tl::unexpected(e.error());
    extractors.push_back(std::move(*e));
  }
  // Key "<jitter>|<block>": the block of the jittered crop (feature-level augmentation and
  // test-time averaging).
  std::map<std::string, std::vector<std::vector<float>>> cache;
  for (size_t mi = 0; mi < methods->size(); ++mi) {
    const ExpressionMethod& m = (*methods)[mi];
    std::vector<expression::FaceJitter> jitters = m.train_jitters();
    for (const auto& j : m.test_jitters())
      if (std::find(jitters.begin(), jitters.end(), j) == jitters.end()) jitters.push_back(j);
    for (const std::string& b : m.features.blocks)
      for (const auto& j : jitters) {
        auto& column = cache[jitter_key(j) + block_key(m, b)];
        if (!column.empty()) continue;
        column.resize(items->size());
        for (size_t i = 0; i < items->size(); ++i) {
          const auto& f = faces_of(mi)[i];
          if (!f.face) continue;
          column[i] = extractors[mi].block(b, f.grey, expression::jitter_face(f.grey, *f.face, j));
        }
      }
  }
  if (progress) progress(0.8);

  std::vector<std::string> subjects;
  for (const auto& it : *items) subjects.push_back(it.subject);
  const auto folds = subject_folds(subjects, o.folds, o.seed);
  const std::vector<std::string> labels = ordered_labels(present);
  std::vector<ConfusionMatrix> cms(methods->size(), ConfusionMatrix(labels, "no_face"));
  std::vector<std::vector<double>> ms(methods->size());
  for (size_t fi = 0; fi < folds.size(); ++fi) {
    const std::set<std::string> test_subjects(folds[fi].begin(), folds[fi].end());
    std::vector<size_t> train, test;
    for (size_t i = 0; i < items->size(); ++i)
      (test_subjects.count((*items)[i].subject) ? test : train).push_back(i);
    std::set<std::string> train_present;
    for (size_t i : train)
      if ((*faces)[i].face) train_present.insert((*items)[i].label);
    const std::vector<std::string> fold_labels = ordered_labels(train_present);
    for (size_t mi = 0; mi < methods->size(); ++mi) {
      const ExpressionMethod& m = (*methods)[mi];
      auto row = [&](size_t i, const expression::FaceJitter& j) {
        std::vector<float> v;
        for (const std::string& b : m.features.blocks) {
          const auto& part = cache[jitter_key(j) + block_key(m, b)][i];
          v.insert(v.end(), part.begin(), part.end());
        }
        return v;
      };
      cv::Mat x;
      std::vector<int> y;
      for (size_t i : train) {
        if (!(*faces)[i].face) continue;
        for (const auto& j : m.train_jitters()) {
          const std::vector<float> v = row(i, j);
          x.push_back(cv::Mat(1, static_cast<int>(v.size()), CV_32F, const_cast<float*>(v.data())));
          y.push_back(static_cast<int>(
              std::find(fold_labels.begin(), fold_labels.end(), (*items)[i].label) -
              fold_labels.begin()));
        }
      }
      auto model = ExpressionModel::train(m, x, y, fold_labels, {o.dataset, train.size(), "cv"},
                                          extractors[mi].face_api_hash());
      if (!model) return tl::unexpected(model.error());
      for (size_t i : test) {
        std::string predicted = "no_face";
        if ((*faces)[i].face) {
          std::vector<std::vector<float>> variants;
          for (const auto& j : m.test_jitters()) variants.push_back(row(i, j));
          predicted = model->predict(std::move(variants)).label;
        }
        cms[mi].add((*items)[i].label, predicted);
      }
      if (fi + 1 == folds.size()) {  // timing of the full per-face path on the last fold
        auto r = expression::ExpressionRecognizer::create(std::move(*model));
        if (!r) return tl::unexpected(r.error());
        ms[mi] = time_recognizer(*r, faces_of(mi), test, 300);
      }
    }
    if (progress) progress(0.8 + 0.2 * (fi + 1.0) / folds.size());
  }

  std::vector<double> align_ms;
  for (const auto& f : *faces) align_ms.push_back(f.align_ms);
  std::string names;
  for (const auto& m : *methods) names += (names.empty() ? "" : ", ") + m.name;
  report.protocol = fmt::format(
      "{}-fold subject-disjoint cross-validation ({} subjects, seed {}); methods {} on the same "
      "folds; faces aligned by cascade + dlib landmarks with crop fallbacks",
      folds.size(), std::set<std::string>(subjects.begin(), subjects.end()).size(), o.seed, names);
  const ConfusionMatrix& top = cms.front();
  report.metrics = {{"accuracy", number_or_null(top.accuracy())},
                    {"balanced_accuracy", number_or_null(top.balanced_accuracy())},
                    {"confusion", top.confusion_json()}};
  report.timing = {{"ms_per_face_median", number_or_null(median(ms.front()))},
                   {"ms_alignment_median", number_or_null(median(align_ms))}};
  nlohmann::json method_names = nlohmann::json::array();
  for (size_t mi = 0; mi < methods->size(); ++mi) {
    const std::string& n = (*methods)[mi].name;
    method_names.push_back(n);
    report.metrics[n] = {{"accuracy", number_or_null(cms[mi].accuracy())},
                         {"balanced_accuracy", number_or_null(cms[mi].balanced_accuracy())},
                         {"confusion", cms[mi].confusion_json()},
                         {"per_class", cms[mi].per_class_json()}};
    report.timing[n] = {{"ms_per_face_median", number_or_null(median(ms[mi]))}};
  }
  report.per_class = top.per_class_json();
  report.extra = {
      {"alignment", alignment_counts(*faces)}, {"methods", method_names}, {"folds", folds.size()}};
  return report;
}

Result<ExpressionModel> run_expression_train(const ExpressionTrainOptions& o,
                                             ExpressionTrainSummary* summary,
                                             const Progress& progress) {
  if (auto s = o.check(); !s) return tl::unexpected(s.error());
  auto method = expression::expression_method(o.method);
  if (!method) return tl::unexpected(method.error());
  auto items = read_expression_dataset(o.dataset, o.dir);
  if (!items) return tl::unexpected(items.error());
  auto faces = prepare(*items, o.crop, method->features.alignment, progress, 0.0, 0.6);
  if (!faces) return tl::unexpected(faces.error());
  auto extractor = ExpressionFeatureExtractor::create(method->features);
  if (!extractor) return tl::unexpected(extractor.error());
  std::set<std::string> present;
  for (size_t i = 0; i < items->size(); ++i)
    if ((*faces)[i].face) present.insert((*items)[i].label);
  const std::vector<std::string> labels = ordered_labels(present);
  if (labels.size() < 2)
    return make_error(ErrorCode::kInvalidArgument,
                      "{}: fewer than two expression classes with faces", o.dir.string());
  cv::Mat x;
  std::vector<int> y;
  ExpressionTrainSummary s;
  s.images = items->size();
  for (size_t i = 0; i < items->size(); ++i) {
    const auto& f = (*faces)[i];
    if (!f.face) continue;
    for (const auto& j : method->train_jitters()) {
      const std::vector<float> v =
          extractor->extract(f.grey, expression::jitter_face(f.grey, *f.face, j));
      x.push_back(cv::Mat(1, static_cast<int>(v.size()), CV_32F, const_cast<float*>(v.data())));
      y.push_back(static_cast<int>(std::find(labels.begin(), labels.end(), (*items)[i].label) -
                                   labels.begin()));
    }
    ++s.used;
    ++s.per_label[(*items)[i].label];
    if (progress && i % 16 == 0) progress(0.6 + 0.3 * (i + 1.0) / items->size());
  }
  auto model = ExpressionModel::train(*method, x, y, labels, {o.dataset, s.used, o.note},
                                      extractor->face_api_hash());
  if (summary) *summary = s;
  if (progress) progress(1.0);
  return model;
}

}  // namespace dreamsense::eval::faces
