#include "dreamsense/face_identity/face_gallery.hpp"

#include "dreamsense/core/file_storage_check.hpp"
#include "dreamsense/vision/face_api_net.hpp"
#include "dreamsense/vision/lbp.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>

namespace dreamsense::face_identity {
namespace {

constexpr const char* kFormat = "dreamsense-face-gallery";

// Best person and its score (or its lead over the second-best person) from per-person scores.
std::pair<int, double> score_of(const std::vector<std::pair<int, double>>& per_person,
                                bool margin) {
  int best_id = -1;
  double best = -std::numeric_limits<double>::infinity(), second = best;
  for (const auto& [id, s] : per_person) {
    if (s > best) {
      second = best;
      best = s, best_id = id;
    } else if (s > second) {
      second = s;
    }
  }
  if (!margin || best_id < 0) return {best_id, best};
  return {best_id, std::isfinite(second) ? best - second : best};
}

double dot(const std::vector<float>& a, const std::vector<float>& b) {
  double s = 0;
  for (size_t i = 0; i < a.size(); ++i) s += static_cast<double>(a[i]) * b[i];
  return s;
}

}  // namespace

Status IdentityMethod::check() const {
  if (name.empty())
    return make_error(ErrorCode::kInvalidArgument, "identity method without a name");
  if (auto s = alignment.check(); !s) return s;
  if (lbp_radii.empty() || lbp_grid < 1 || lbp_grid > alignment.size / 4)
    return make_error(ErrorCode::kInvalidArgument, "identity method {}: bad LBP settings", name);
  for (double r : lbp_radii)
    if (!(r > 0 && r <= 4))
      return make_error(ErrorCode::kInvalidArgument, "identity method {}: LBP radius in (0, 4]",
                        name);
  return svm.check();
}

Result<IdentityMethod> identity_method(const std::string& spec) {
  std::vector<std::string> parts;
  for (size_t start = 0;;) {
    const size_t colon = spec.find(':', start);
    parts.push_back(spec.substr(start, colon - start));
    if (colon == std::string::npos) break;
    start = colon + 1;
  }
  IdentityMethod m;
  m.name = spec;
  if (parts.front() == "lbp_svm") {
    m.matcher = IdentityMethod::Matcher::kSvm;
    m.svm.c = 0.1;
    m.default_threshold = 0.0;  // the SVM's own decision boundary
  } else if (parts.front() == "lbp_tt") {
    m.tan_triggs = true;
    m.lbp_radii = {1.0, 2.0};
    m.lbp_sqrt = true;
    m.l2_normalise = true;
    m.matcher = IdentityMethod::Matcher::kNearestCosine;
    m.default_threshold = 0.8;
  } else if (parts.front() == "face_api") {
    m.face_api = true;
    // The geometry the descriptor network was trained on (dlib's 150 px chips, padding 0.25).
    m.alignment.size = vision::kFaceApiRecognitionInputPx;
    m.alignment.dlib_template = true;
    m.alignment.template_padding = 0.25;
    m.matcher = IdentityMethod::Matcher::kNearestEuclidean;
    m.default_threshold = -0.6;  // dlib's same-person distance
  } else {
    return make_error(ErrorCode::kInvalidArgument,
                      "unknown identity method '{}' (face_api, lbp_tt, lbp_svm)", parts.front());
  }
  for (size_t i = 1; i < parts.size(); ++i) {
    const std::string& p = parts[i];
    const size_t eq = p.find('=');
    const std::string key = p.substr(0, eq),
                      value = eq == std::string::npos ? "" : p.substr(eq + 1);
    try {
      if (key == "grid")
        m.lbp_grid = std::stoi(value);
      else if (key == "size")
        m.alignment.size = std::stoi(value);
      else if (key == "eye_distance")
        m.alignment.eye_distance = std::stod(value);
      else if (key == "eye_row")
        m.alignment.eye_row = std::stod(value);
      else if (key == "tt")
        m.tan_triggs = value != "0";
      else if (key == "sqrt")
        m.lbp_sqrt = value != "0";
      else if (key == "radius")
        m.lbp_radii = {std::stod(value)};
      else if (key == "c")
        m.svm.c = std::stod(value);
      else if (key == "threshold")
        m.default_threshold = std::stod(value);
      else if (key == "margin")
        m.margin_score = value != "0";
      else if (key == "template")
        m.alignment.dlib_template = value != "0";
      else if (key == "padding")
        m.alignment.template_padding = std::stod(value);
      else
        return make_error(ErrorCode::kInvalidArgument,
                          "identity method '{}': unknown modifier '{}'", spec, p);
    } catch (const std::exception&) {
      return make_error(ErrorCode::kInvalidArgument, "identity method '{}': bad value in '{}'",
                        spec, p);
    }
  }
  if (auto s = m.check(); !s) return tl::unexpected(s.error());
  return m;
}

size_t identity_feature_length(const IdentityMethod& m) {
  if (m.face_api) return vision::kFaceApiDescriptorLength;
  return m.lbp_radii.size() * static_cast<size_t>(m.lbp_grid * m.lbp_grid) *
         vision::kUniformLbpBins;
}

struct IdentityFeatureExtractor::Net {
  vision::FaceApiRecognitionNet net;
};

IdentityFeatureExtractor::IdentityFeatureExtractor(IdentityMethod m, std::unique_ptr<Net> net)
    : method_(std::move(m)), net_(std::move(net)) {}
IdentityFeatureExtractor::IdentityFeatureExtractor(IdentityFeatureExtractor&&) noexcept = default;
IdentityFeatureExtractor& IdentityFeatureExtractor::operator=(IdentityFeatureExtractor&&) noexcept =
    default;
IdentityFeatureExtractor::~IdentityFeatureExtractor() = default;

Result<IdentityFeatureExtractor> IdentityFeatureExtractor::create(
    const IdentityMethod& method, const std::filesystem::path& face_api_dir) {
  if (auto s = method.check(); !s) return tl::unexpected(s.error());
  std::unique_ptr<Net> net;
  if (method.face_api) {
    auto n = vision::FaceApiRecognitionNet::load(
        face_api_dir.empty() ? vision::default_face_api_model_dir() : face_api_dir);
    if (!n) return tl::unexpected(n.error());
    net = std::make_unique<Net>(Net{std::move(*n)});
  }
  return IdentityFeatureExtractor(method, std::move(net));
}

std::string IdentityFeatureExtractor::weights_hash() const {
  return net_ ? net_->net.weights_hash() : std::string();
}

std::vector<float> IdentityFeatureExtractor::extract(const cv::Mat& image_grey,
                                                     const vision::AlignedFace& face) {
  const IdentityMethod& m = method_;
  if (m.face_api)
    return net_->net.describe(
        vision::resample_face(image_grey, face, vision::kFaceApiRecognitionInputPx));
  DS_CHECK_EQ(face.grey.cols, m.alignment.size);
  cv::Mat input = m.tan_triggs ? vision::tan_triggs(face.grey) : face.grey;
  std::vector<float> out;
  out.reserve(identity_feature_length(m));
  for (double r : m.lbp_radii)
    vision::grid_histograms(vision::uniform_lbp_labels(input, r), vision::kUniformLbpBins,
                            m.lbp_grid, m.lbp_grid, m.lbp_sqrt, out);
  if (m.l2_normalise) {
    const double n = std::sqrt(dot(out, out));
    if (n > 0)
      for (float& v : out) v = static_cast<float>(v / n);
  }
  return out;
}

Status FaceGallery::add(int id, std::vector<float> features) {
  if (id < 0) return make_error(ErrorCode::kInvalidArgument, "person id {} must be >= 0", id);
  if (features.size() != identity_feature_length(method_))
    return make_error(ErrorCode::kInvalidArgument, "{} features for person {} (method {} gives {})",
                      features.size(), id, method_.name, identity_feature_length(method_));
  auto it = std::lower_bound(persons_.begin(), persons_.end(), id,
                             [](const EnrolledPerson& p, int v) { return p.id < v; });
  if (it == persons_.end() || it->id != id) it = persons_.insert(it, EnrolledPerson{id, {}});
  it->features.push_back(std::move(features));
  return ok_status();
}

std::optional<std::string> FaceGallery::name(int id) const {
  auto it = names_.find(id);
  if (it == names_.end()) return std::nullopt;
  return it->second;
}

size_t FaceGallery::images() const {
  size_t n = 0;
  for (const auto& p : persons_) n += p.features.size();
  return n;
}

Status FaceGallery::save(const std::filesystem::path& path) const {
  try {
    cv::FileStorage fs(path.string(), cv::FileStorage::WRITE | cv::FileStorage::BASE64 |
                                          cv::FileStorage::FORMAT_YAML);
    if (!fs.isOpened()) return make_error(ErrorCode::kIoError, "{}: cannot write", path.string());
    fs << "format" << kFormat << "version" << kFaceGalleryVersion;
    fs << "method" << method_.name << "weights_hash" << weights_hash_;
    fs << "feature_length" << static_cast<int>(identity_feature_length(method_));
    fs << "persons"
       << "[";
    for (const auto& p : persons_) {
      cv::Mat m(static_cast<int>(p.features.size()),
                static_cast<int>(identity_feature_length(method_)), CV_32F);
      for (size_t r = 0; r < p.features.size(); ++r)
        std::copy(p.features[r].begin(), p.features[r].end(), m.ptr<float>(static_cast<int>(r)));
      fs << "{"
         << "id" << p.id << "features" << m << "}";
    }
    fs << "]";
    if (!names_.empty()) {
      fs << "names"
         << "[";
      for (const auto& [id, n] : names_)
        fs << "{"
           << "id" << id << "name" << n << "}";
      fs << "]";
    }
    fs.release();
  } catch (const cv::Exception& e) {
    return make_error(ErrorCode::kIoError, "{}: cannot write ({})", path.string(), e.what());
  }
  return ok_status();
}

Result<FaceGallery> FaceGallery::load(const std::filesystem::path& path) {
  const std::string where = path.string();
  if (!std::filesystem::is_regular_file(path))
    return make_error(ErrorCode::kNotFound, "{}: no such face gallery", where);
  DS_ASSIGN_OR_RETURN(cv::FileStorage fs, open_file_storage(path));
  try {
    if (static_cast<std::string>(fs["format"]) != kFormat)
      return make_error(ErrorCode::kCorruptData, "{}: not a dreamsense face gallery", where);
    const int version = static_cast<int>(fs["version"]);
    if (version != kFaceGalleryVersion)
      return make_error(ErrorCode::kUnsupported,
                        "{}: face gallery version {} (this build reads version {}; enrol the "
                        "faces again with `dreamsense enroll faces`)",
                        where, version, kFaceGalleryVersion);
    auto method = identity_method(static_cast<std::string>(fs["method"]));
    if (!method)
      return make_error(ErrorCode::kUnsupported, "{}: gallery of another method ({}); enrol again",
                        where, method.error().message);
    const int length = static_cast<int>(fs["feature_length"]);
    if (length != static_cast<int>(identity_feature_length(*method)))
      return make_error(ErrorCode::kUnsupported,
                        "{}: gallery features of length {} but method {} gives {} (another "
                        "version; enrol again)",
                        where, length, method->name, identity_feature_length(*method));
    FaceGallery g(*method, static_cast<std::string>(fs["weights_hash"]));
    for (const cv::FileNode& n : fs["persons"]) {
      const int id = static_cast<int>(n["id"]);
      cv::Mat m;
      n["features"] >> m;
      if (m.type() != CV_32FC1 || m.cols != length || m.rows < 1)
        return make_error(ErrorCode::kCorruptData, "{}: person {} has malformed features", where,
                          id);
      for (int r = 0; r < m.rows; ++r)
        if (auto s = g.add(id, std::vector<float>(m.ptr<float>(r), m.ptr<float>(r) + m.cols)); !s)
          return make_error(ErrorCode::kCorruptData, "{}: {}", where, s.error().message);
    }
    for (const cv::FileNode& n : fs["names"])
      g.set_name(static_cast<int>(n["id"]), static_cast<std::string>(n["name"]));
    return g;
  } catch (const std::exception&) {
    return make_error(ErrorCode::kCorruptData, "{}: not a readable face gallery", where);
  }
}

Status check_compatible(const FaceGallery& gallery, const IdentityFeatureExtractor& extractor) {
  if (gallery.method().name != extractor.method().name)
    return make_error(ErrorCode::kUnsupported,
                      "face gallery of method {} cannot be matched with method {} (enrol again)",
                      gallery.method().name, extractor.method().name);
  if (gallery.weights_hash() != extractor.weights_hash())
    return make_error(ErrorCode::kUnsupported,
                      "face gallery enrolled with network weights {} but {} are installed (enrol "
                      "again)",
                      gallery.weights_hash(), extractor.weights_hash());
  return ok_status();
}

std::optional<double> choose_threshold(std::vector<double> genuine, std::vector<double> impostor) {
  if (genuine.empty() || impostor.empty()) return std::nullopt;
  // Candidate cuts between sorted distinct scores; errors(t) = #(g < t) + #(i >= t).
  std::vector<double> all = genuine;
  all.insert(all.end(), impostor.begin(), impostor.end());
  std::sort(all.begin(), all.end());
  all.erase(std::unique(all.begin(), all.end()), all.end());
  std::sort(genuine.begin(), genuine.end());
  std::sort(impostor.begin(), impostor.end());
  auto errors = [&](double t) {
    const auto fr = std::lower_bound(genuine.begin(), genuine.end(), t) - genuine.begin();
    const auto fa = impostor.end() - std::lower_bound(impostor.begin(), impostor.end(), t);
    return fr + fa;
  };
  // Cut points: below everything, between neighbours, above everything.
  std::vector<double> cuts;
  cuts.push_back(all.front() - 1e-6);
  for (size_t i = 0; i + 1 < all.size(); ++i) cuts.push_back(0.5 * (all[i] + all[i + 1]));
  cuts.push_back(all.back() + 1e-6);
  long best = std::numeric_limits<long>::max();
  size_t first = 0, last = 0;
  for (size_t i = 0; i < cuts.size(); ++i) {
    const long e = errors(cuts[i]);
    if (e < best)
      best = e, first = last = i;
    else if (e == best && last + 1 == i)
      last = i;  // contiguous run of equal minima
  }
  return 0.5 * (cuts[first] + cuts[last]);
}

std::pair<int, double> FaceIdentifier::best_match(const std::vector<float>& x, int skip_person,
                                                  int skip_image_person, size_t skip_image) const {
  const auto& persons = gallery_.persons();
  std::vector<std::pair<int, double>> per_person;
  if (gallery_.method().matcher == IdentityMethod::Matcher::kSvm) {
    const std::vector<float> s = svm_.scores(x);
    for (size_t p = 0; p < persons.size(); ++p) per_person.emplace_back(persons[p].id, s[p]);
  } else {
    const bool euclidean = gallery_.method().matcher == IdentityMethod::Matcher::kNearestEuclidean;
    for (const auto& p : persons) {
      if (p.id == skip_person) continue;
      double best = -std::numeric_limits<double>::infinity();
      for (size_t k = 0; k < p.features.size(); ++k) {
        if (p.id == skip_image_person && k == skip_image) continue;
        double s = 0;
        if (euclidean) {
          for (size_t i = 0; i < x.size(); ++i) {
            const double d = static_cast<double>(x[i]) - p.features[k][i];
            s += d * d;
          }
          s = -std::sqrt(s);
        } else {
          s = dot(x, p.features[k]);
        }
        best = std::max(best, s);
      }
      if (std::isfinite(best)) per_person.emplace_back(p.id, best);
    }
  }
  return score_of(per_person, gallery_.method().margin_score);
}

Result<FaceIdentifier> FaceIdentifier::create(FaceGallery gallery) {
  if (gallery.empty())
    return make_error(ErrorCode::kFailedPrecondition,
                      "the face gallery is empty: enrol faces first (dreamsense enroll faces)");
  FaceIdentifier id(std::move(gallery));
  const IdentityMethod& m = id.gallery_.method();
  const auto& persons = id.gallery_.persons();
  std::vector<double> genuine, impostor;
  if (m.matcher == IdentityMethod::Matcher::kSvm) {
    auto train = [&](int skip_person, int skip_image_person,
                     size_t skip_image) -> Result<std::optional<vision::LinearClassifier>> {
      cv::Mat x;
      std::vector<int> y;
      int classes = 0;
      for (size_t p = 0; p < persons.size(); ++p) {
        if (persons[p].id == skip_person) continue;
        for (size_t k = 0; k < persons[p].features.size(); ++k) {
          if (persons[p].id == skip_image_person && k == skip_image) continue;
          const auto& f = persons[p].features[k];
          x.push_back(cv::Mat(1, static_cast<int>(f.size()), CV_32F, const_cast<float*>(f.data())));
          y.push_back(classes);
        }
        ++classes;
      }
      if (classes < 1 || x.rows < 1) return std::optional<vision::LinearClassifier>{};
      if (classes == 1) {  // one person: a classifier against nobody; score = 0
        vision::LinearClassifier c;
        c.weights = cv::Mat::zeros(1, x.cols, CV_32F);
        c.bias = {0.f};
        return std::optional<vision::LinearClassifier>{c};
      }
      auto c = vision::train_one_vs_rest_svm(x, y, classes, m.svm);
      if (!c) return tl::unexpected(c.error());
      return std::optional<vision::LinearClassifier>{std::move(*c)};
    };
    auto full = train(-1, -1, 0);
    if (!full) return tl::unexpected(full.error());
    id.svm_ = std::move(**full);
    // Leave-one-out scores with retrained SVMs (enrolment data only).
    auto best_of = [&](const vision::LinearClassifier& c, const std::vector<float>& x,
                       int skip_person) {
      const std::vector<float> s = c.scores(x);
      std::vector<std::pair<int, double>> per_person;
      size_t row = 0;
      for (const auto& p : persons) {
        if (p.id == skip_person) continue;
        per_person.emplace_back(p.id, s[row++]);
      }
      return score_of(per_person, m.margin_score);
    };
    if (persons.size() >= 2) {
      for (const auto& p : persons) {
        auto without = train(p.id, -1, 0);
        if (!without) return tl::unexpected(without.error());
        for (const auto& f : p.features) impostor.push_back(best_of(**without, f, p.id).second);
        if (p.features.size() < 2) continue;
        for (size_t k = 0; k < p.features.size(); ++k) {
          auto loo = train(-1, p.id, k);
          if (!loo) return tl::unexpected(loo.error());
          const auto [who, score] = best_of(**loo, p.features[k], -1);
          (who == p.id ? genuine : impostor).push_back(score);
        }
      }
    }
  } else {
    for (const auto& p : persons)
      for (size_t k = 0; k < p.features.size(); ++k) {
        const auto other = id.best_match(p.features[k], p.id);
        if (other.first >= 0) impostor.push_back(other.second);
        if (p.features.size() < 2) continue;
        const auto [who, score] = id.best_match(p.features[k], -1, p.id, k);
        if (who == p.id) genuine.push_back(score);
      }
  }
  if (auto t = choose_threshold(genuine, impostor)) {
    id.threshold_ = *t;
    id.threshold_from_enrolment_ = true;
  } else {
    id.threshold_ = m.default_threshold;
  }
  return id;
}

IdentityResult FaceIdentifier::identify(const std::vector<float>& x) const {
  IdentityResult r;
  if (x.size() != identity_feature_length(gallery_.method())) return r;
  const auto [who, score] = best_match(x);
  r.best_id = who;
  r.score = score;
  if (who >= 0 && score >= threshold_) {
    r.id = who;
    r.name = gallery_.name(who).value_or("");
  }
  return r;
}

}  // namespace dreamsense::face_identity
