// Object identification: the seed's HOG + RBF-SVM and our colour + fHOG nearest-neighbour
// gallery with rejection (see the header).

#include "dreamsense/objects/identification.hpp"

#include "dreamsense/core/file_storage_check.hpp"
#include "dreamsense/objects/fhog.hpp"

#include <opencv2/imgproc.hpp>
#include <opencv2/objdetect.hpp>

#include <algorithm>
#include <cmath>
#include <exception>
#include <map>
#include <set>

namespace dreamsense::objects {
namespace {

constexpr int kColourBins = 42;  // 12 hues x 3 saturations + 6 grey levels
constexpr int kHogW = 48, kHogH = 32, kHogCell = 8;
constexpr int kHogDims = kFhogChannels * (kHogW / kHogCell) * (kHogH / kHogCell);
constexpr int kFeatureDims = kColourBins + kHogDims;

cv::Mat colour_histogram(const ObjectView& v) {
  cv::Mat hsv;
  cv::cvtColor(v.crop, hsv, cv::COLOR_BGR2HSV);
  std::vector<float> h(kColourBins, 0.f);
  float n = 0;
  for (int y = 0; y < hsv.rows; ++y) {
    const cv::Vec3b* p = hsv.ptr<cv::Vec3b>(y);
    const uchar* m = v.mask.ptr<uchar>(y);
    for (int x = 0; x < hsv.cols; ++x) {
      if (!m[x]) continue;
      const int hue = p[x][0], sat = p[x][1], val = p[x][2];
      int bin;
      if (sat >= 40 && val >= 30)
        bin = std::min(hue * 12 / 180, 11) * 3 + std::min((sat - 40) * 3 / 216, 2);
      else
        bin = 36 + std::min(val * 6 / 256, 5);
      h[static_cast<size_t>(bin)] += 1, n += 1;
    }
  }
  cv::Mat out(1, kColourBins, CV_32F);
  for (int i = 0; i < kColourBins; ++i)
    out.at<float>(i) = n > 0 ? std::sqrt(h[static_cast<size_t>(i)] / n) : 0.f;
  return out;
}

// The footprint rectangle resampled to kHogW x kHogH grey with its long side horizontal.
cv::Mat upright_patch(const ObjectView& v) {
  cv::RotatedRect r = v.footprint;
  double angle = r.angle * CV_PI / 180.0;
  double len = r.size.width, wid = r.size.height;
  if (wid > len) {
    std::swap(len, wid);
    angle += CV_PI / 2;
  }
  len = std::max(len, 4.0);
  wid = std::max(wid, 4.0);
  const double c = std::cos(angle), s = std::sin(angle);
  const double kx = len / kHogW, ky = wid / kHogH;
  // Output (u, v) -> crop: centre + R * ((u + 0.5 - W/2) kx, (v + 0.5 - H/2) ky).
  const double ox = -(kHogW / 2.0 - 0.5) * kx, oy = -(kHogH / 2.0 - 0.5) * ky;
  const cv::Matx23d m(c * kx, -s * ky, r.center.x + c * ox - s * oy,  //
                      s * kx, c * ky, r.center.y + s * ox + c * oy);
  cv::Mat grey, out;
  cv::cvtColor(v.crop, grey, cv::COLOR_BGR2GRAY);
  cv::warpAffine(grey, out, m, cv::Size(kHogW, kHogH), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                 cv::BORDER_REPLICATE);
  return out;
}

cv::Mat hog_row(const cv::Mat& patch) {
  cv::Mat out(1, kHogDims, CV_32F);
  compute_fhog(patch, kHogCell, out.ptr<float>(0));
  const double n = cv::norm(out);
  if (n > 0) out /= n;
  return out;
}

double distance(const float* a, const float* b, double hog_weight) {
  double dc = 0, dh = 0;
  for (int i = 0; i < kColourBins; ++i) dc += (a[i] - b[i]) * (a[i] - b[i]);
  for (int i = kColourBins; i < kFeatureDims; ++i) dh += (a[i] - b[i]) * (a[i] - b[i]);
  return std::sqrt(dc) + hog_weight * std::sqrt(dh);
}

const cv::HOGDescriptor& dream_hog() {
  static const cv::HOGDescriptor hog(cv::Size(32, 32), cv::Size(16, 16), cv::Size(8, 8),
                                     cv::Size(8, 8), 9);
  return hog;
}

}  // namespace

Result<ObjectView> make_view(const cv::Mat& frame, const cv::Rect& box_in, const cv::Mat& mask,
                             const std::optional<cv::RotatedRect>& footprint) {
  if (frame.empty() || frame.type() != CV_8UC3)
    return make_error(ErrorCode::kInvalidArgument, "object view: need a BGR frame");
  const cv::Rect box = box_in & cv::Rect(0, 0, frame.cols, frame.rows);
  if (box.width < 4 || box.height < 4)
    return make_error(ErrorCode::kInvalidArgument,
                      "object view: box ({}, {}, {}x{}) is empty or outside the {}x{} frame",
                      box_in.x, box_in.y, box_in.width, box_in.height, frame.cols, frame.rows);
  ObjectView v;
  v.crop = frame(box);
  if (!mask.empty() && mask.size() == box_in.size() && box == box_in) {
    v.mask = mask;
  } else {
    // Separate the object from the table by colour: the crop's border is mostly table.
    std::vector<uchar> b, g, r;
    auto take = [&](int x, int y) {
      const cv::Vec3b p = v.crop.at<cv::Vec3b>(y, x);
      b.push_back(p[0]), g.push_back(p[1]), r.push_back(p[2]);
    };
    for (int x = 0; x < v.crop.cols; ++x) take(x, 0), take(x, v.crop.rows - 1);
    for (int y = 1; y + 1 < v.crop.rows; ++y) take(0, y), take(v.crop.cols - 1, y);
    auto median = [](std::vector<uchar>& c) {
      std::nth_element(c.begin(), c.begin() + static_cast<long>(c.size() / 2), c.end());
      return static_cast<int>(c[c.size() / 2]);
    };
    const int mb = median(b), mg = median(g), mr = median(r);
    cv::Mat m(v.crop.size(), CV_8U);
    for (int y = 0; y < v.crop.rows; ++y) {
      const cv::Vec3b* p = v.crop.ptr<cv::Vec3b>(y);
      uchar* o = m.ptr<uchar>(y);
      for (int x = 0; x < v.crop.cols; ++x)
        o[x] =
            std::abs(p[x][0] - mb) + std::abs(p[x][1] - mg) + std::abs(p[x][2] - mr) > 60 ? 255 : 0;
    }
    cv::morphologyEx(m, m, cv::MORPH_OPEN, cv::getStructuringElement(cv::MORPH_ELLIPSE, {3, 3}));
    std::vector<cv::Point> pts;
    cv::findNonZero(m, pts);
    v.mask = cv::Mat::zeros(v.crop.size(), CV_8U);
    if (pts.size() >= 0.1 * v.crop.total()) {
      std::vector<cv::Point> hull;
      cv::convexHull(pts, hull);
      cv::fillConvexPoly(v.mask, hull, cv::Scalar(255));
    } else {
      v.mask.setTo(255);
    }
  }
  if (footprint && box == box_in) {
    v.footprint = *footprint;
    v.footprint.center -= cv::Point2f(static_cast<float>(box.x), static_cast<float>(box.y));
    return v;
  }
  std::vector<cv::Point> pts;
  cv::findNonZero(v.mask, pts);
  if (pts.size() < 3)
    v.footprint = cv::RotatedRect(
        cv::Point2f(v.crop.cols / 2.f, v.crop.rows / 2.f),
        cv::Size2f(static_cast<float>(v.crop.cols), static_cast<float>(v.crop.rows)), 0);
  else
    v.footprint = cv::minAreaRect(pts);
  return v;
}

std::filesystem::path default_gallery_path() {
  return std::filesystem::path(DREAMSENSE_OBJECTS_MODELS_DIR) / "demo_toys.gallery.yaml";
}

std::vector<ObjectClass> dream_toy_classes() {
  return {{0, "car", {0.10, 0.075, 0.03}},
          {1, "cup", {0.10, 0.075, 0.03}},
          {2, "flower", {0.10, 0.075, 0.03}},
          {3, "plane", {0.10, 0.075, 0.03}}};
}

cv::Mat gallery_features(const ObjectView& v) {
  const cv::Mat colour = colour_histogram(v);
  cv::Mat patch = upright_patch(v), turned;
  cv::flip(patch, turned, -1);
  cv::Mat out(2, kFeatureDims, CV_32F);
  colour.copyTo(out(cv::Rect(0, 0, kColourBins, 1)));
  colour.copyTo(out(cv::Rect(0, 1, kColourBins, 1)));
  hog_row(patch).copyTo(out(cv::Rect(kColourBins, 0, kHogDims, 1)));
  hog_row(turned).copyTo(out(cv::Rect(kColourBins, 1, kHogDims, 1)));
  return out;
}

cv::Mat dream_hog_features(const ObjectView& v) {
  cv::Mat grey, small;
  cv::cvtColor(v.crop, grey, cv::COLOR_BGR2GRAY);
  cv::resize(grey, small, cv::Size(32, 32), 0, 0, cv::INTER_AREA);
  std::vector<float> d;
  dream_hog().compute(small, d);
  return cv::Mat(1, static_cast<int>(d.size()), CV_32F, d.data()).clone();
}

Status GalleryOptions::check() const {
  if (!(hog_weight >= 0) || !(rejection_factor > 0) || max_exemplars_per_class < 1)
    return make_error(ErrorCode::kInvalidArgument,
                      "object gallery: need hog_weight >= 0, rejection_factor > 0, "
                      "max_exemplars_per_class >= 1");
  return ok_status();
}

const ObjectClass* ObjectGallery::find(int id) const {
  for (const auto& c : classes_)
    if (c.id == id) return &c;
  return nullptr;
}

Status ObjectGallery::append(const std::vector<LabelledView>& views) {
  // Evenly thinned to at most max_exemplars_per_class views per class.
  std::map<int, std::vector<const LabelledView*>> by_class;
  for (const auto& v : views) {
    if (!find(v.id))
      return make_error(ErrorCode::kInvalidArgument, "object gallery: view of unknown class id {}",
                        v.id);
    if (v.view.crop.empty() || v.view.mask.empty())
      return make_error(ErrorCode::kInvalidArgument, "object gallery: empty view of class {}",
                        v.id);
    by_class[v.id].push_back(&v);
  }
  int next_view = feature_views_.empty() ? 0 : feature_views_.back() + 1;
  for (auto& [id, list] : by_class) {
    const size_t keep =
        std::min(list.size(), static_cast<size_t>(options_.max_exemplars_per_class));
    for (size_t k = 0; k < keep; ++k) {
      const LabelledView& v = *list[k * list.size() / keep];
      const cv::Mat f = gallery_features(v.view);
      features_.push_back(f);
      feature_ids_.insert(feature_ids_.end(), 2, id);
      feature_views_.insert(feature_views_.end(), 2, next_view++);
      baseline_samples_.push_back(dream_hog_features(v.view));
      baseline_ids_.push_back(id);
    }
  }
  return ok_status();
}

Status ObjectGallery::finish() {
  for (const auto& c : classes_)
    if (std::find(feature_ids_.begin(), feature_ids_.end(), c.id) == feature_ids_.end())
      return make_error(ErrorCode::kInvalidArgument, "object gallery: class {} ({}) has no view",
                        c.id, c.label);
  // Rejection threshold from the leave-one-view-out nearest distances within each class.
  std::vector<double> within;
  for (int r = 0; r < features_.rows; r += 2) {
    int id;
    double d;
    nearest(features_.row(r), id, d, feature_views_[static_cast<size_t>(r)]);
    if (id == feature_ids_[static_cast<size_t>(r)]) within.push_back(d);
  }
  if (within.empty()) {
    threshold_ = 0.6;  // a single view per class: a conservative default
  } else {
    std::sort(within.begin(), within.end());
    threshold_ =
        options_.rejection_factor * within[std::min(within.size() - 1, within.size() * 95 / 100)];
  }
  svm_.release();
  std::set<int> ids(baseline_ids_.begin(), baseline_ids_.end());
  if (options_.train_baseline && ids.size() >= 2) {
    svm_ = cv::ml::SVM::create();
    svm_->setType(cv::ml::SVM::C_SVC);
    svm_->setKernel(cv::ml::SVM::RBF);
    svm_->setGamma(0.09);
    svm_->setC(10);
    const cv::Mat labels(static_cast<int>(baseline_ids_.size()), 1, CV_32S, baseline_ids_.data());
    if (!svm_->train(baseline_samples_, cv::ml::ROW_SAMPLE, labels.clone()))
      return make_error(ErrorCode::kInternal, "object gallery: the baseline SVM did not train");
  }
  return ok_status();
}

Result<ObjectGallery> ObjectGallery::enrol(const std::vector<ObjectClass>& classes,
                                           const std::vector<LabelledView>& views,
                                           const GalleryOptions& options) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  if (classes.empty()) return make_error(ErrorCode::kInvalidArgument, "object gallery: no class");
  std::set<int> ids;
  for (const auto& c : classes) {
    if (c.id < 0 || !ids.insert(c.id).second)
      return make_error(ErrorCode::kInvalidArgument,
                        "object gallery: class ids must be >= 0 and unique (id {})", c.id);
    if (!(c.size_m[0] > 0 && c.size_m[1] > 0 && c.size_m[2] >= 0))
      return make_error(ErrorCode::kInvalidArgument, "object gallery: class {} has a bad size",
                        c.label);
  }
  ObjectGallery g;
  g.options_ = options;
  g.classes_ = classes;
  if (auto s = g.append(views); !s) return tl::unexpected(s.error());
  if (auto s = g.finish(); !s) return tl::unexpected(s.error());
  return g;
}

Status ObjectGallery::add(const std::vector<ObjectClass>& classes,
                          const std::vector<LabelledView>& views) {
  for (const auto& c : classes) {
    if (const ObjectClass* known = find(c.id)) {
      if (known->label != c.label)
        return make_error(ErrorCode::kInvalidArgument,
                          "object gallery: id {} is already '{}' (not '{}')", c.id, known->label,
                          c.label);
    } else {
      classes_.push_back(c);
    }
  }
  if (auto s = append(views); !s) return s;
  return finish();
}

void ObjectGallery::nearest(const cv::Mat& f, int& id, double& d, int skip_view) const {
  id = kUnknownObject;
  d = std::numeric_limits<double>::infinity();
  const float* q = f.ptr<float>(0);
  for (int r = 0; r < features_.rows; ++r) {
    if (feature_views_[static_cast<size_t>(r)] == skip_view) continue;
    const double dr = distance(q, features_.ptr<float>(r), options_.hog_weight);
    if (dr < d) d = dr, id = feature_ids_[static_cast<size_t>(r)];
  }
}

Identification ObjectGallery::identify(const ObjectView& view) const {
  Identification out;
  if (features_.empty()) return out;
  const cv::Mat f = gallery_features(view);
  int id;
  double d;
  nearest(f.row(0), id, d);
  out.distance = d;
  out.score = threshold_ > 0 ? 1.0 - d / threshold_ : 0.0;
  if (d <= threshold_) {
    out.id = id;
    if (const ObjectClass* c = find(id)) out.label = c->label;
  }
  return out;
}

Result<ObjectGallery> ObjectGallery::without(int id) const {
  if (!find(id)) return make_error(ErrorCode::kInvalidArgument, "object gallery: no class {}", id);
  ObjectGallery g;
  g.options_ = options_;
  for (const auto& c : classes_)
    if (c.id != id) g.classes_.push_back(c);
  if (g.classes_.empty())
    return make_error(ErrorCode::kInvalidArgument, "object gallery: no class left");
  for (int r = 0; r < features_.rows; ++r)
    if (feature_ids_[static_cast<size_t>(r)] != id) {
      g.features_.push_back(features_.row(r));
      g.feature_ids_.push_back(feature_ids_[static_cast<size_t>(r)]);
      g.feature_views_.push_back(feature_views_[static_cast<size_t>(r)]);
    }
  for (int r = 0; r < baseline_samples_.rows; ++r)
    if (baseline_ids_[static_cast<size_t>(r)] != id) {
      g.baseline_samples_.push_back(baseline_samples_.row(r));
      g.baseline_ids_.push_back(baseline_ids_[static_cast<size_t>(r)]);
    }
  if (auto s = g.finish(); !s) return tl::unexpected(s.error());
  return g;
}

bool ObjectGallery::has_baseline() const { return svm_ && svm_->isTrained(); }

Identification ObjectGallery::identify_baseline(const ObjectView& view) const {
  Identification out;
  if (!has_baseline()) return out;
  const int id = static_cast<int>(svm_->predict(dream_hog_features(view)));
  out.id = id;
  out.score = 1;
  if (const ObjectClass* c = find(id)) out.label = c->label;
  return out;
}

Status ObjectGallery::save(const std::filesystem::path& path) const {
  const std::filesystem::path tmp = path.string() + ".tmp.yaml";
  try {
    // Matrices base64-encoded (compact, exact); the rest stays readable YAML.
    cv::FileStorage fs(tmp.string(), cv::FileStorage::WRITE | cv::FileStorage::BASE64);
    if (!fs.isOpened()) return make_error(ErrorCode::kIoError, "{}: cannot write", path.string());
    fs << "format" << kFormatName << "format_version" << kFormatVersion;
    fs << "hog_weight" << options_.hog_weight << "rejection_factor" << options_.rejection_factor;
    fs << "max_exemplars_per_class" << options_.max_exemplars_per_class;
    fs << "threshold" << threshold_;
    fs << "classes"
       << "[";
    for (const auto& c : classes_)
      fs << "{"
         << "id" << c.id << "label" << c.label << "length_m" << c.size_m[0] << "width_m"
         << c.size_m[1] << "height_m" << c.size_m[2] << "}";
    fs << "]";
    fs << "features" << features_;
    fs << "feature_ids" << feature_ids_ << "feature_views" << feature_views_;
    fs << "baseline_samples" << baseline_samples_ << "baseline_ids" << baseline_ids_;
    if (has_baseline()) {
      fs << "baseline_svm"
         << "{";
      svm_->write(fs);
      fs << "}";
    }
    fs.release();
  } catch (const std::exception& e) {
    return make_error(ErrorCode::kIoError, "{}: cannot write: {}", path.string(), e.what());
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec)
    return make_error(ErrorCode::kIoError, "{}: cannot write: {}", path.string(), ec.message());
  return ok_status();
}

Result<ObjectGallery> ObjectGallery::load(const std::filesystem::path& path) {
  const std::string p = path.string();
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    return make_error(ErrorCode::kNotFound, "{}: no such object gallery", p);
  DS_ASSIGN_OR_RETURN(cv::FileStorage fs, open_file_storage(path));
  try {
    if (static_cast<std::string>(fs["format"]) != kFormatName)
      return make_error(ErrorCode::kCorruptData, "{}: not an object gallery (format '{}')", p,
                        static_cast<std::string>(fs["format"]));
    if (static_cast<int>(fs["format_version"]) != kFormatVersion)
      return make_error(ErrorCode::kUnsupported,
                        "{}: object gallery version {} (this build reads {})", p,
                        static_cast<int>(fs["format_version"]), kFormatVersion);
    ObjectGallery g;
    g.options_.hog_weight = static_cast<double>(fs["hog_weight"]);
    g.options_.rejection_factor = static_cast<double>(fs["rejection_factor"]);
    g.options_.max_exemplars_per_class = static_cast<int>(fs["max_exemplars_per_class"]);
    g.threshold_ = static_cast<double>(fs["threshold"]);
    for (const auto& n : fs["classes"]) {
      ObjectClass c;
      c.id = static_cast<int>(n["id"]);
      c.label = static_cast<std::string>(n["label"]);
      c.size_m = {static_cast<double>(n["length_m"]), static_cast<double>(n["width_m"]),
                  static_cast<double>(n["height_m"])};
      if (!(c.size_m[0] > 0 && c.size_m[1] > 0 && c.size_m[2] >= 0))
        return make_error(ErrorCode::kCorruptData, "{}: class {}: bad length_m/width_m/height_m", p,
                          c.label);
      g.classes_.push_back(c);
    }
    fs["features"] >> g.features_;
    fs["feature_ids"] >> g.feature_ids_;
    fs["feature_views"] >> g.feature_views_;
    fs["baseline_samples"] >> g.baseline_samples_;
    fs["baseline_ids"] >> g.baseline_ids_;
    if (g.classes_.empty() || g.features_.empty() || g.features_.cols != kFeatureDims ||
        g.feature_ids_.size() != static_cast<size_t>(g.features_.rows) ||
        g.feature_views_.size() != g.feature_ids_.size() || !(g.threshold_ > 0))
      return make_error(ErrorCode::kCorruptData,
                        "{}: inconsistent object gallery (features {}x{}, {} ids)", p,
                        g.features_.rows, g.features_.cols, g.feature_ids_.size());
    if (!fs["baseline_svm"].empty()) {
      g.svm_ = cv::ml::SVM::create();
      g.svm_->read(fs["baseline_svm"]);
    }
    return g;
  } catch (const std::exception& e) {
    return make_error(ErrorCode::kCorruptData, "{}: cannot read: {}", p, e.what());
  }
}

}  // namespace dreamsense::objects
