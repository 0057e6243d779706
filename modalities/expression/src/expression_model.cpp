#include "dreamsense/expression/expression_model.hpp"

#include "dreamsense/core/file_storage_check.hpp"
#include "dreamsense/expression/labels.hpp"
#include "dreamsense/vision/face_api_net.hpp"

#include <opencv2/core.hpp>

#include <algorithm>
#include <array>
#include <exception>
#include <fstream>

namespace dreamsense::expression {
namespace {

constexpr const char* kFormat = "dreamsense-expression-model";

const char* to_string(ClassifierKind k) {
  return k == ClassifierKind::kOneVsRestSvm ? "one_vs_rest_svm" : "softmax";
}

// `p` with its label, index and confidence set from its probabilities (the most probable).
ExpressionPrediction with_top_label(ExpressionPrediction p,
                                    const std::vector<std::string>& labels) {
  p.index = static_cast<int>(std::max_element(p.probabilities.begin(), p.probabilities.end()) -
                             p.probabilities.begin());
  p.label = labels[static_cast<size_t>(p.index)];
  p.confidence = p.probabilities[static_cast<size_t>(p.index)];
  return p;
}

}  // namespace

Status ExpressionMethod::check() const {
  if (name.empty())
    return make_error(ErrorCode::kInvalidArgument, "expression method without a name");
  if (auto s = features.check(); !s) return s;
  for (const std::string* a : {&train_augment, &test_augment})
    if (!a->empty())
      if (auto j = face_jitters(*a); !j) return tl::unexpected(j.error());
  if (auto s = svm.check(); !s) return s;
  if (!(xception_weight >= 0 && xception_weight < 1))
    return make_error(ErrorCode::kInvalidArgument, "xception_weight {} is not in [0, 1)",
                      xception_weight);
  return softmax.check();
}

namespace {
std::vector<FaceJitter> jitters_of(const std::string& sets, bool mirrored) {
  std::string all = sets;
  if (mirrored && all.find("flip") == std::string::npos) all += all.empty() ? "flip" : "+flip";
  auto j = face_jitters(all);
  return j ? *j : std::vector<FaceJitter>{FaceJitter{}};
}
}  // namespace

std::vector<FaceJitter> ExpressionMethod::train_jitters() const {
  return jitters_of(train_augment, train_mirrored);
}
std::vector<FaceJitter> ExpressionMethod::test_jitters() const {
  return jitters_of(test_augment, test_mirrored);
}

Result<ExpressionMethod> expression_method(const std::string& spec) {
  // "preset[:modifier...]"
  std::vector<std::string> parts;
  for (size_t start = 0;;) {
    const size_t colon = spec.find(':', start);
    parts.push_back(spec.substr(start, colon - start));
    if (colon == std::string::npos) break;
    start = colon + 1;
  }
  const std::string& name = parts.front();
  ExpressionMethod m;
  m.name = spec;
  if (name == "lbp_svm") {
    m.features.blocks = {"lbp1"};
    m.classifier = ClassifierKind::kOneVsRestSvm;
    m.standardize = false;
    m.svm.c = 0.1;
  } else if (name == "lbp_hog") {
    m.features.blocks = {"lbp1", "lbp2", "hog", "geometry"};
    m.features.lbp_sqrt = true;
    m.softmax.l2 = 1e-2;
  } else if (name == "face_api") {
    m.features.blocks = {"face_api"};
    m.softmax.l2 = 1e-2;
  } else if (name == "fusion") {
    m.features.blocks = {"lbp1", "lbp2", "hog", "geometry", "face_api"};
    m.features.lbp_sqrt = true;
    m.softmax.l2 = 1e-2;
  } else {
    return make_error(ErrorCode::kInvalidArgument,
                      "unknown expression method '{}' (lbp_svm, lbp_hog, face_api, fusion)", name);
  }
  for (size_t i = 1; i < parts.size(); ++i) {
    const std::string& p = parts[i];
    const size_t eq = p.find('=');
    const std::string key = p.substr(0, eq),
                      value = eq == std::string::npos ? "" : p.substr(eq + 1);
    try {
      if (key == "l2")
        m.softmax.l2 = std::stod(value);
      else if (key == "c")
        m.svm.c = std::stod(value);
      else if (key == "mirror")
        m.train_mirrored = m.test_mirrored = true;
      else if (key == "train_mirror")
        m.train_mirrored = true;
      else if (key == "test_mirror")
        m.test_mirrored = true;
      else if (key == "grid")
        m.features.lbp_grid = std::stoi(value);
      else if (key == "size")
        m.features.alignment.size = std::stoi(value);
      else if (key == "eye_distance")
        m.features.alignment.eye_distance = std::stod(value);
      else if (key == "eye_row")
        m.features.alignment.eye_row = std::stod(value);
      else if (key == "sqrt")
        m.features.lbp_sqrt = value != "0";
      else if (key == "hog_cell")
        m.features.hog.cell_px = std::stoi(value);
      else if (key == "aug")
        m.train_augment = value;
      else if (key == "tta")
        m.test_augment = value;
      else if (key == "unbalanced")
        m.softmax.balance_classes = false;
      else if (key == "no_flip")
        m.features.face_api_flip = false;
      else if (key == "blocks") {
        m.features.blocks.clear();
        for (size_t start = 0;;) {
          const size_t plus = value.find('+', start);
          m.features.blocks.push_back(value.substr(start, plus - start));
          if (plus == std::string::npos) break;
          start = plus + 1;
        }
      } else {
        return make_error(ErrorCode::kInvalidArgument,
                          "expression method '{}': unknown modifier '{}'", spec, p);
      }
    } catch (const std::exception&) {
      return make_error(ErrorCode::kInvalidArgument, "expression method '{}': bad value in '{}'",
                        spec, p);
    }
  }
  if (auto s = m.check(); !s) return tl::unexpected(s.error());
  return m;
}

Result<ExpressionModel> ExpressionModel::train(
    const ExpressionMethod& method, const cv::Mat& samples, const std::vector<int>& labels,
    std::vector<std::string> label_names, ExpressionTrainingInfo info, std::string face_api_hash) {
  if (auto s = method.check(); !s) return tl::unexpected(s.error());
  ExpressionModel m;
  m.method_ = method;
  m.labels_ = std::move(label_names);
  m.training_ = std::move(info);
  m.face_api_hash_ = std::move(face_api_hash);
  cv::Mat x = samples.clone();
  if (method.standardize) {
    m.standardizer_ = vision::Standardizer::fit(x);
    m.standardizer_.apply(x);
  }
  const int classes = static_cast<int>(m.labels_.size());
  auto c = method.classifier == ClassifierKind::kSoftmax
               ? vision::train_softmax(x, labels, classes, method.softmax)
               : vision::train_one_vs_rest_svm(x, labels, classes, method.svm);
  if (!c) return tl::unexpected(c.error());
  m.classifier_ = std::move(*c);
  return m;
}

ExpressionPrediction ExpressionModel::predict(std::vector<float> features) const {
  if (!standardizer_.empty()) standardizer_.apply(features);
  ExpressionPrediction p;
  p.probabilities = vision::softmax(classifier_.scores(features));
  return with_top_label(std::move(p), labels_);
}

ExpressionPrediction ExpressionModel::predict(std::vector<float> features,
                                              std::vector<float> mirrored) const {
  ExpressionPrediction p = predict(std::move(features));
  const ExpressionPrediction q = predict(std::move(mirrored));
  for (size_t k = 0; k < p.probabilities.size(); ++k)
    p.probabilities[k] = 0.5f * (p.probabilities[k] + q.probabilities[k]);
  return with_top_label(std::move(p), labels_);
}

ExpressionPrediction ExpressionModel::predict(std::vector<std::vector<float>> variants) const {
  DS_CHECK(!variants.empty());
  if (variants.size() == 1) return predict(std::move(variants.front()));
  ExpressionPrediction p;
  for (std::vector<float>& v : variants) {
    const ExpressionPrediction q = predict(std::move(v));
    if (p.probabilities.empty()) p.probabilities.assign(q.probabilities.size(), 0.f);
    for (size_t k = 0; k < q.probabilities.size(); ++k) p.probabilities[k] += q.probabilities[k];
  }
  for (float& x : p.probabilities) x /= static_cast<float>(variants.size());
  return with_top_label(std::move(p), labels_);
}

Status ExpressionModel::save(const std::filesystem::path& path) const {
  try {
    cv::FileStorage fs(path.string(), cv::FileStorage::WRITE | cv::FileStorage::BASE64 |
                                          cv::FileStorage::FORMAT_YAML);
    if (!fs.isOpened()) return make_error(ErrorCode::kIoError, "{}: cannot write", path.string());
    const ExpressionFeatureOptions& f = method_.features;
    fs << "format" << kFormat << "version" << kExpressionModelVersion;
    fs << "method"
       << "{";
    fs << "name" << method_.name << "blocks" << f.blocks;
    fs << "alignment_size" << f.alignment.size << "eye_distance" << f.alignment.eye_distance
       << "eye_row" << f.alignment.eye_row;
    fs << "lbp_grid" << f.lbp_grid << "lbp_sqrt" << static_cast<int>(f.lbp_sqrt);
    fs << "hog_cell_px" << f.hog.cell_px << "hog_bins" << f.hog.bins;
    fs << "face_api_flip" << static_cast<int>(f.face_api_flip);
    fs << "classifier" << to_string(method_.classifier) << "standardize"
       << static_cast<int>(method_.standardize) << "train_mirrored"
       << static_cast<int>(method_.train_mirrored) << "test_mirrored"
       << static_cast<int>(method_.test_mirrored);
    fs << "train_augment" << method_.train_augment << "test_augment" << method_.test_augment;
    fs << "svm_c" << method_.svm.c << "softmax_l2" << method_.softmax.l2 << "balance_classes"
       << static_cast<int>(method_.softmax.balance_classes);
    if (method_.xception_weight > 0) fs << "xception_weight" << method_.xception_weight;
    if (!f.face_api_dir.empty())  // relative to the model file, so the pair can move together
      fs << "face_api_network"
         << std::filesystem::proximate(f.face_api_dir, path.parent_path()).generic_string();
    fs << "}";
    fs << "labels" << labels_;
    fs << "training"
       << "{"
       << "dataset" << training_.dataset << "items" << static_cast<int>(training_.items) << "note"
       << training_.note << "}";
    fs << "face_api_weights_hash" << face_api_hash_;
    if (!standardizer_.empty()) vision::write_standardizer(fs, "standardizer", standardizer_);
    vision::write_linear(fs, "classifier", classifier_);
    fs.release();
  } catch (const cv::Exception& e) {
    return make_error(ErrorCode::kIoError, "{}: cannot write ({})", path.string(), e.what());
  }
  return ok_status();
}

Result<ExpressionModel> ExpressionModel::load(const std::filesystem::path& path) {
  const std::string where = path.string();
  if (!std::filesystem::is_regular_file(path))
    return make_error(ErrorCode::kNotFound, "{}: no such expression model", where);
  DS_ASSIGN_OR_RETURN(cv::FileStorage fs, open_file_storage(path));
  ExpressionModel m;
  try {
    if (static_cast<std::string>(fs["format"]) != kFormat)
      return make_error(ErrorCode::kCorruptData, "{}: not a dreamsense expression model", where);
    const int version = static_cast<int>(fs["version"]);
    if (version != kExpressionModelVersion)
      return make_error(ErrorCode::kUnsupported,
                        "{}: expression model version {} (this build reads version {}; retrain "
                        "with `dreamsense train expression`)",
                        where, version, kExpressionModelVersion);
    const cv::FileNode mn = fs["method"];
    if (!mn.isMap()) return make_error(ErrorCode::kCorruptData, "{}: missing method", where);
    ExpressionMethod& me = m.method_;
    ExpressionFeatureOptions& f = me.features;
    me.name = static_cast<std::string>(mn["name"]);
    f.blocks.clear();
    mn["blocks"] >> f.blocks;
    f.alignment.size = static_cast<int>(mn["alignment_size"]);
    f.alignment.eye_distance = static_cast<double>(mn["eye_distance"]);
    f.alignment.eye_row = static_cast<double>(mn["eye_row"]);
    f.lbp_grid = static_cast<int>(mn["lbp_grid"]);
    f.lbp_sqrt = static_cast<int>(mn["lbp_sqrt"]) != 0;
    f.hog.cell_px = static_cast<int>(mn["hog_cell_px"]);
    f.hog.bins = static_cast<int>(mn["hog_bins"]);
    f.face_api_flip = static_cast<int>(mn["face_api_flip"]) != 0;
    const std::string kind = static_cast<std::string>(mn["classifier"]);
    if (kind != "softmax" && kind != "one_vs_rest_svm")
      return make_error(ErrorCode::kCorruptData, "{}: unknown classifier '{}'", where, kind);
    me.classifier = kind == "softmax" ? ClassifierKind::kSoftmax : ClassifierKind::kOneVsRestSvm;
    me.standardize = static_cast<int>(mn["standardize"]) != 0;
    me.train_mirrored = static_cast<int>(mn["train_mirrored"]) != 0;
    me.test_mirrored = static_cast<int>(mn["test_mirrored"]) != 0;
    me.train_augment = static_cast<std::string>(mn["train_augment"]);  // absent: ""
    me.test_augment = static_cast<std::string>(mn["test_augment"]);
    me.svm.c = static_cast<double>(mn["svm_c"]);
    me.softmax.l2 = static_cast<double>(mn["softmax_l2"]);
    me.softmax.balance_classes = static_cast<int>(mn["balance_classes"]) != 0;
    me.xception_weight =
        mn["xception_weight"].empty() ? 0.0 : static_cast<double>(mn["xception_weight"]);
    // A model with its own (fine-tuned) network names the network's folder beside it; without
    // it the package's weights (vision::default_face_api_model_dir()).
    if (const std::string network = static_cast<std::string>(mn["face_api_network"]);
        !network.empty())
      f.face_api_dir = path.parent_path() / network;
    if (auto s = me.check(); !s)
      return make_error(ErrorCode::kCorruptData, "{}: {}", where, s.error().message);
    fs["labels"] >> m.labels_;
    m.training_.dataset = static_cast<std::string>(fs["training"]["dataset"]);
    m.training_.items = static_cast<size_t>(static_cast<int>(fs["training"]["items"]));
    m.training_.note = static_cast<std::string>(fs["training"]["note"]);
    m.face_api_hash_ = static_cast<std::string>(fs["face_api_weights_hash"]);
    if (me.standardize) {
      auto s = vision::read_standardizer(fs["standardizer"], where);
      if (!s) return tl::unexpected(s.error());
      m.standardizer_ = std::move(*s);
    }
    auto c = vision::read_linear(fs["classifier"], where);
    if (!c) return tl::unexpected(c.error());
    m.classifier_ = std::move(*c);
  } catch (const std::exception&) {
    return make_error(ErrorCode::kCorruptData, "{}: not a readable expression model", where);
  }
  if (m.labels_.size() < 2 || static_cast<int>(m.labels_.size()) != m.classifier_.classes())
    return make_error(ErrorCode::kCorruptData, "{}: {} labels for {} classifier rows", where,
                      m.labels_.size(), m.classifier_.classes());
  if (!m.standardizer_.empty() &&
      static_cast<int>(m.standardizer_.mean.size()) != m.classifier_.dims())
    return make_error(ErrorCode::kCorruptData, "{}: standardizer and classifier sizes differ",
                      where);
  return m;
}

Result<ExpressionRecognizer> ExpressionRecognizer::create(ExpressionModel model) {
  auto e = ExpressionFeatureExtractor::create(model.method().features);
  if (!e) return tl::unexpected(e.error());
  if (static_cast<int>(e->length()) != model.feature_length())
    return make_error(ErrorCode::kCorruptData,
                      "expression model: {} features expected, the "
                      "method gives {}",
                      model.feature_length(), e->length());
  if (e->face_api_hash() != model.face_api_hash())
    return make_error(ErrorCode::kUnsupported,
                      "expression model was trained on face-api weights {} but {} are installed "
                      "(retrain with `dreamsense train expression`)",
                      model.face_api_hash(), e->face_api_hash());
  std::shared_ptr<vision::FerXceptionNet> xception;
  if (model.method().xception_weight > 0) {
    auto net = vision::FerXceptionNet::load(vision::default_human_models_dir());
    if (!net)
      return make_error(net.error().code,
                        "{} (the expression model's second network; "
                        "tools/setup.sh installs it)",
                        net.error().message);
    xception = std::make_shared<vision::FerXceptionNet>(std::move(*net));
  }
  return ExpressionRecognizer(std::move(model), std::move(*e), std::move(xception));
}

ExpressionRecognizer::ExpressionRecognizer(ExpressionModel m, ExpressionFeatureExtractor e,
                                           std::shared_ptr<vision::FerXceptionNet> xception)
    : model_(std::move(m)), extractor_(std::move(e)), xception_(std::move(xception)) {
  // The network's FER2013 class names in the project's spelling (labels.hpp).
  for (const std::string& label : model_.labels()) {
    int index = -1;
    for (size_t k = 0; k < vision::kFerXceptionLabels.size(); ++k)
      if (canonical_label(vision::kFerXceptionLabels[k]) == label) index = static_cast<int>(k);
    xception_index_.push_back(index);
  }
}

ExpressionPrediction ExpressionRecognizer::recognize(const cv::Mat& image_grey,
                                                     const vision::AlignedFace& face) {
  const std::vector<FaceJitter> jitters = model_.method().test_jitters();
  std::vector<std::vector<float>> variants;
  for (const FaceJitter& j : jitters)
    variants.push_back(extractor_.extract(image_grey, jitter_face(image_grey, face, j)));
  ExpressionPrediction p = model_.predict(std::move(variants));
  if (!xception_) return p;
  // The second network on the same two views as the face_api blocks, the face as it is (its
  // mirror image adds a pass per view and nothing measurable: models/MODEL_CARD.md).
  std::array<float, 7> second{};
  for (const cv::Mat& view : {vision::resample_face(image_grey, face, vision::kFaceApiInputPx),
                              face_api_box_crop(image_grey, face)}) {
    const std::array<float, 7> q = xception_->probabilities(view);
    for (size_t k = 0; k < q.size(); ++k) second[k] += q[k] / 2;
  }
  const float w = static_cast<float>(model_.method().xception_weight);
  for (size_t k = 0; k < p.probabilities.size(); ++k) {
    const int x = xception_index_[k];
    p.probabilities[k] =
        (1 - w) * p.probabilities[k] + (x >= 0 ? w * second[static_cast<size_t>(x)] : 0.f);
  }
  return with_top_label(std::move(p), model_.labels());
}

}  // namespace dreamsense::expression
