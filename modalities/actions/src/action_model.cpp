#include "dreamsense/actions/action_model.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <set>

#include "model_file.hpp"
#include "svm_backends.hpp"

namespace dreamsense::actions {
namespace fs = std::filesystem;

std::string_view to_string(ClassifierKind k) {
  switch (k) {
    case ClassifierKind::kLinearSvm:
      return "linear_svm";
    case ClassifierKind::kRbfSvm:
      return "rbf_svm";
    case ClassifierKind::kShrinkageLda:
      return "shrinkage_lda";
  }
  return "?";
}

Result<ClassifierKind> classifier_kind_from_string(std::string_view s) {
  if (s == "linear_svm") return ClassifierKind::kLinearSvm;
  if (s == "rbf_svm") return ClassifierKind::kRbfSvm;
  if (s == "shrinkage_lda") return ClassifierKind::kShrinkageLda;
  return make_error(ErrorCode::kInvalidArgument,
                    "unknown classifier '{}' (linear_svm, rbf_svm, shrinkage_lda)", s);
}

Status ClassifierOptions::check() const {
  if (!(c > 0) || !std::isfinite(c))
    return make_error(ErrorCode::kInvalidArgument, "classifier: c must be > 0");
  if (!(gamma >= 0) || !std::isfinite(gamma))
    return make_error(ErrorCode::kInvalidArgument, "classifier: gamma must be >= 0");
  if (reject_folds < 0 || reject_folds == 1 || reject_folds > 20)
    return make_error(ErrorCode::kInvalidArgument,
                      "classifier: reject_folds must be 0 (off) or in [2, 20]");
  if (!(novelty_margin >= 1))
    return make_error(ErrorCode::kInvalidArgument, "classifier: novelty_margin must be >= 1");
  if (!(reject_quantile >= 0 && reject_quantile < 0.5))
    return make_error(ErrorCode::kInvalidArgument,
                      "classifier: reject_quantile must be in [0, 0.5)");
  return ok_status();
}

Status ActionModelOptions::check() const {
  if (auto s = body.check(); !s) return s;
  if (auto s = features.check(); !s) return s;
  if (auto s = classifier.check(); !s) return s;
  if (!(window_s >= 0) || window_s > 60)
    return make_error(ErrorCode::kInvalidArgument, "actions: window_s must be in [0, 60]");
  if (crops < 0 || crops > 16)
    return make_error(ErrorCode::kInvalidArgument, "actions: crops must be in [0, 16]");
  if (!(crop_fraction >= 0.5 && crop_fraction < 1))
    return make_error(ErrorCode::kInvalidArgument, "actions: crop_fraction must be in [0.5, 1)");
  return ok_status();
}

namespace {

struct Fitted {
  detail::LinearSvm linear;  // linear SVM or LDA discriminants
  detail::RbfSvm rbf;
};

// Weights and a bias per class, argmax wins (the linear SVM and LDA).
bool is_linear(ClassifierKind k) { return k != ClassifierKind::kRbfSvm; }

// LDA's discriminants differ from the log posteriors by a constant per window; the log
// posterior (<= 0) is what a rejection threshold can be compared with across windows.
void to_log_posterior(double* d, int n) {
  double mx = -1e300;
  for (int k = 0; k < n; ++k) mx = std::max(mx, d[k]);
  double sum = 0;
  for (int k = 0; k < n; ++k) sum += std::exp(d[k] - mx);
  const double log_sum = mx + std::log(sum);
  for (int k = 0; k < n; ++k) d[k] -= log_sum;
}

Fitted fit(const cv::Mat& x, const std::vector<int>& y, int classes, const ClassifierOptions& o) {
  Fitted f;
  if (o.kind == ClassifierKind::kLinearSvm) {
    f.linear = detail::train_linear_svm(x, y, classes, o.c, o.l1);
  } else if (o.kind == ClassifierKind::kShrinkageLda) {
    f.linear = detail::train_shrinkage_lda(x, y, classes);
  } else {
    const double gamma = o.gamma > 0 ? o.gamma : 1.0 / std::max(x.cols, 1);
    f.rbf = detail::train_rbf_svm(x, y, classes, o.c, gamma);
  }
  return f;
}

// Decision values and the predicted class (linear: argmax; RBF: most votes, ties by decision).
int decide(const Fitted& f, ClassifierKind kind, int classes, const float* x, double* out) {
  std::vector<int> votes(static_cast<size_t>(classes), 0);
  if (is_linear(kind))
    detail::linear_decision(f.linear, x, out);
  else
    detail::rbf_decision(f.rbf, x, out, votes.data());
  if (kind == ClassifierKind::kShrinkageLda) to_log_posterior(out, classes);
  int best = 0;
  for (int k = 1; k < classes; ++k) {
    const bool better = is_linear(kind)
                            ? out[k] > out[best]
                            : (votes[static_cast<size_t>(k)] > votes[static_cast<size_t>(best)] ||
                               (votes[static_cast<size_t>(k)] == votes[static_cast<size_t>(best)] &&
                                out[k] > out[best]));
    if (better) best = k;
  }
  return best;
}

void softmax(const double* d, int n, double t, std::vector<double>& out) {
  out.resize(static_cast<size_t>(n));
  double mx = -1e300;
  for (int k = 0; k < n; ++k) mx = std::max(mx, t * d[k]);
  double sum = 0;
  for (int k = 0; k < n; ++k) sum += (out[static_cast<size_t>(k)] = std::exp(t * d[k] - mx));
  for (auto& v : out) v /= sum;
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return -1e30;
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const size_t i = static_cast<size_t>(std::floor(pos));
  const size_t j = std::min(i + 1, v.size() - 1);
  return v[i] + (pos - static_cast<double>(i)) * (v[j] - v[i]);
}

// Per class: the centroid of its standardised descriptors and their RMS distance to it.
void class_centroids(const cv::Mat& xs, const std::vector<int>& y, int classes, cv::Mat& centroids,
                     cv::Mat& radii) {
  centroids = cv::Mat::zeros(classes, xs.cols, CV_32F);
  radii = cv::Mat::ones(classes, 1, CV_32F);
  std::vector<int> n(static_cast<size_t>(classes), 0);
  for (int r = 0; r < xs.rows; ++r) {
    centroids.row(y[static_cast<size_t>(r)]) += xs.row(r);
    ++n[static_cast<size_t>(y[static_cast<size_t>(r)])];
  }
  std::vector<double> ss(static_cast<size_t>(classes), 0.0);
  for (int c = 0; c < classes; ++c)
    if (n[static_cast<size_t>(c)] > 0) centroids.row(c) /= n[static_cast<size_t>(c)];
  for (int r = 0; r < xs.rows; ++r) {
    const int c = y[static_cast<size_t>(r)];
    const double d = cv::norm(xs.row(r), centroids.row(c), cv::NORM_L2);
    ss[static_cast<size_t>(c)] += d * d;
  }
  for (int c = 0; c < classes; ++c)
    if (n[static_cast<size_t>(c)] > 0)
      radii.at<float>(c, 0) = static_cast<float>(
          std::max(std::sqrt(ss[static_cast<size_t>(c)] / n[static_cast<size_t>(c)]), 1e-3));
}

double centroid_distance(const cv::Mat& centroids, const cv::Mat& radii, const float* x, int c) {
  const float* m = centroids.ptr<float>(c);
  double s = 0;
  for (int k = 0; k < centroids.cols; ++k) {
    const double e = static_cast<double>(x[k]) - m[k];
    s += e * e;
  }
  return std::sqrt(s) / radii.at<float>(c, 0);
}

const ModelFileKind& file_kind() {
  static const ModelFileKind kind{"actions model", ActionModel::kFormatName,
                                  ActionModel::kFormatVersion, "dreamsense train actions"};
  return kind;
}

Error corrupt(const fs::path& path, const std::string& what) {
  return model_corrupt(file_kind(), path, what);
}

}  // namespace

Result<ActionModel> ActionModel::train(const std::vector<LabelledSequence>& sequences,
                                       const ActionModelOptions& o,
                                       const std::function<void(double)>& progress) {
  std::vector<WindowRef> windows;
  windows.reserve(sequences.size());
  for (const auto& e : sequences) windows.push_back({e.frames, e.label, e.subject});
  return train(windows, o, progress);
}

Result<ActionModel> ActionModel::train(const std::vector<WindowRef>& examples,
                                       const ActionModelOptions& o,
                                       const std::function<void(double)>& progress) {
  if (auto s = o.check(); !s) return tl::unexpected(s.error());
  ActionModel m;
  m.options_ = o;
  std::set<std::string> distinct;
  for (const auto& e : examples) distinct.insert(e.label);
  m.labels_.assign(distinct.begin(), distinct.end());
  if (m.labels_.size() < 2)
    return make_error(ErrorCode::kInvalidArgument,
                      "actions: training needs at least two classes (got {})", m.labels_.size());
  std::map<std::string, int> index;
  for (size_t i = 0; i < m.labels_.size(); ++i) index[m.labels_[i]] = static_cast<int>(i);
  const int classes = static_cast<int>(m.labels_.size());
  const int dim = feature_dimension(o.features);

  std::vector<int> y, origin;
  std::vector<std::string> subjects;
  std::vector<double> durations;
  cv::Mat x(0, dim, CV_32F);
  x.reserve(examples.size());
  auto add = [&](const NormalizedWindow& w, size_t i) {
    std::vector<float> f = extract_features(w, o.features);
    if (f.empty()) return;
    x.push_back(cv::Mat(1, dim, CV_32F, f.data()));
    y.push_back(index[examples[i].label]);
    subjects.push_back(examples[i].subject);
    origin.push_back(static_cast<int>(i));
  };
  for (size_t i = 0; i < examples.size(); ++i) {
    const auto& e = examples[i];
    NormalizedWindow w = normalize_window(e.frames, o.body);
    if (!w.usable) {
      ++m.skipped_;
      continue;
    }
    ++m.examples_;
    durations.push_back(w.t_s.back());
    std::vector<NormalizedWindow> variants = {w};
    const int n = static_cast<int>(e.frames.size());
    for (int c = 0; c < o.crops && n >= 4; ++c) {
      const double dur = w.t_s.back(), keep = o.crop_fraction * dur;
      const double start = o.crops > 1 ? (dur - keep) * c / (o.crops - 1) : (dur - keep) / 2;
      size_t a = 0, b = static_cast<size_t>(n);
      while (a + 1 < static_cast<size_t>(n) && w.t_s[a] < start) ++a;
      while (b > a + 2 && w.t_s[b - 1] > start + keep) --b;
      NormalizedWindow cw = normalize_window(e.frames.subspan(a, b - a), o.body);
      if (cw.usable) variants.push_back(std::move(cw));
    }
    if (o.augment_mirror) {
      const size_t k = variants.size();
      for (size_t v = 0; v < k; ++v) {
        NormalizedWindow mw = variants[v];
        mirror_left_right(mw);
        variants.push_back(std::move(mw));
      }
    }
    for (const auto& v : variants) add(v, i);
    if (progress && i % 64 == 0) progress(0.2 * static_cast<double>(i) / examples.size());
  }
  std::set<int> present(y.begin(), y.end());
  if (present.size() < 2)
    return make_error(ErrorCode::kInvalidArgument,
                      "actions: fewer than two classes have usable examples ({} skipped)",
                      m.skipped_);
  if (o.window_s > 0) {
    m.window_s_ = o.window_s;
  } else {
    std::nth_element(durations.begin(), durations.begin() + durations.size() / 2, durations.end());
    m.window_s_ = std::max(durations[durations.size() / 2], 0.1);
  }

  // Standardisation (a constant feature gets weight 0).
  cv::Mat mean, sd;
  m.mean_.create(1, dim, CV_32F);
  m.inv_std_.create(1, dim, CV_32F);
  double mean_sd = 0;
  for (int k = 0; k < dim; ++k) {
    cv::meanStdDev(x.col(k), mean, sd);
    m.mean_.at<float>(0, k) = static_cast<float>(mean.at<double>(0));
    const double s = sd.at<double>(0);
    mean_sd += s / dim;
    m.inv_std_.at<float>(0, k) = s > 1e-6 ? static_cast<float>(1.0 / s) : 0.f;
  }
  if (!o.classifier.standardize_each)  // one scale for all: the descriptor's geometry is kept
    m.inv_std_.setTo(mean_sd > 1e-12 ? 1.0 / mean_sd : 1.0);
  cv::Mat xs(x.rows, dim, CV_32F);
  for (int i = 0; i < x.rows; ++i) {
    const float* a = x.ptr<float>(i);
    float* b = xs.ptr<float>(i);
    for (int k = 0; k < dim; ++k)
      b[k] = (a[k] - m.mean_.at<float>(0, k)) * m.inv_std_.at<float>(0, k);
  }

  const ClassifierOptions& co = o.classifier;
  if (progress) progress(0.25);
  // Held-out decision values: rejection threshold and score temperature.
  if (co.reject_folds >= 2) {
    const int k = co.reject_folds;
    std::vector<int> fold(static_cast<size_t>(xs.rows));
    std::set<std::string> subject_set(subjects.begin(), subjects.end());
    subject_set.erase("");
    if (static_cast<int>(subject_set.size()) >= k) {  // subject-disjoint folds
      std::map<std::string, int> sf;
      int i = 0;
      for (const auto& s : subject_set) sf[s] = i++ % k;
      for (int r = 0; r < xs.rows; ++r)
        fold[static_cast<size_t>(r)] = subjects[static_cast<size_t>(r)].empty()
                                           ? origin[static_cast<size_t>(r)] % k
                                           : sf[subjects[static_cast<size_t>(r)]];
    } else {  // stratified round robin over the original examples (copies follow them)
      std::vector<int> seen(static_cast<size_t>(classes), 0);
      std::map<int, int> of_origin;
      for (int r = 0; r < xs.rows; ++r) {
        const int og = origin[static_cast<size_t>(r)];
        auto it = of_origin.find(og);
        if (it == of_origin.end())
          it = of_origin.emplace(og, seen[static_cast<size_t>(y[static_cast<size_t>(r)])]++ % k)
                   .first;
        fold[static_cast<size_t>(r)] = it->second;
      }
    }
    std::vector<double> held(static_cast<size_t>(xs.rows) * classes);
    std::vector<int> predicted(static_cast<size_t>(xs.rows), -1);
    std::vector<double> novelty(static_cast<size_t>(xs.rows), 0.0);
    for (int f = 0; f < k; ++f) {
      cv::Mat xt(0, dim, CV_32F);
      std::vector<int> yt;
      for (int r = 0; r < xs.rows; ++r)
        if (fold[static_cast<size_t>(r)] != f) {
          xt.push_back(xs.row(r));
          yt.push_back(y[static_cast<size_t>(r)]);
        }
      if (std::set<int>(yt.begin(), yt.end()).size() < 2) continue;
      const Fitted fitted = fit(xt, yt, classes, co);
      cv::Mat fc, fr;
      class_centroids(xt, yt, classes, fc, fr);
      for (int r = 0; r < xs.rows; ++r)
        if (fold[static_cast<size_t>(r)] == f) {
          const int p = decide(fitted, co.kind, classes, xs.ptr<float>(r),
                               &held[static_cast<size_t>(r) * classes]);
          predicted[static_cast<size_t>(r)] = p;
          novelty[static_cast<size_t>(r)] = centroid_distance(fc, fr, xs.ptr<float>(r), p);
        }
      if (progress) progress(0.25 + 0.5 * (f + 1) / k);
    }
    double best_ll = -1e300;
    std::vector<double> p;
    for (double t : {0.25, 0.5, 1.0, 2.0, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0, 24.0, 32.0, 64.0}) {
      double ll = 0;
      int n = 0;
      for (int r = 0; r < xs.rows; ++r) {
        if (predicted[static_cast<size_t>(r)] < 0) continue;
        softmax(&held[static_cast<size_t>(r) * classes], classes, t, p);
        ll += std::log(std::max(p[static_cast<size_t>(y[static_cast<size_t>(r)])], 1e-12));
        ++n;
      }
      if (n > 0 && ll / n > best_ll) {
        best_ll = ll / n;
        m.temperature_ = t;
      }
    }
    std::vector<double> winners, distances;
    for (int r = 0; r < xs.rows; ++r) {
      const int pr = predicted[static_cast<size_t>(r)];
      if (pr >= 0 && pr == y[static_cast<size_t>(r)]) {
        winners.push_back(held[static_cast<size_t>(r) * classes + pr]);
        distances.push_back(novelty[static_cast<size_t>(r)]);
      }
    }
    // A window that no one-vs-rest classifier claims (decision < 0) is never accepted; held-out
    // margins of easy training data can be far above 0, so the quantile only lowers the bar.
    // (LDA's log posteriors are <= 0: there the quantile alone is the bar.)
    m.reject_threshold_ = std::min(quantile(winners, co.reject_quantile), 0.0);
    if (!distances.empty())
      m.novelty_threshold_ = co.novelty_margin * quantile(distances, 1.0 - co.reject_quantile);
  }
  const Fitted fitted = fit(xs, y, classes, co);
  class_centroids(xs, y, classes, m.centroids_, m.radii_);
  m.weights_ = fitted.linear.weights;
  m.bias_ = fitted.linear.bias;
  m.support_vectors_ = fitted.rbf.support_vectors;
  m.coef_ = fitted.rbf.coef;
  m.rho_ = fitted.rbf.rho;
  m.counts_ = fitted.rbf.counts;
  m.gamma_ = fitted.rbf.gamma;
  if (progress) progress(1.0);
  return m;
}

std::vector<float> ActionModel::features(std::span<const SkeletonFrame> window) const {
  if (window.empty()) return {};
  return extract_features(normalize_window(window, options_.body), options_.features);
}

ActionScores ActionModel::classify(std::span<const SkeletonFrame> window, bool reject) const {
  const std::vector<float> f = features(window);
  return classify_features(f, reject);
}

void ActionModel::decision(const float* xs, double* out, int* votes) const {
  const int classes = static_cast<int>(labels_.size());
  if (is_linear(options_.classifier.kind)) {
    detail::LinearSvm l{weights_, bias_};
    detail::linear_decision(l, xs, out);
    if (options_.classifier.kind == ClassifierKind::kShrinkageLda) to_log_posterior(out, classes);
    for (int k = 0; k < classes; ++k) votes[k] = 0;
  } else {
    detail::RbfSvm r{gamma_, support_vectors_, coef_, rho_, counts_};
    detail::rbf_decision(r, xs, out, votes);
  }
}

ActionScores ActionModel::classify_features(std::span<const float> f, bool reject) const {
  ActionScores s;
  const int dim = mean_.cols;
  if (f.empty() || static_cast<int>(f.size()) != dim) {
    s.no_data = true;
    return s;
  }
  const int classes = static_cast<int>(labels_.size());
  std::vector<float> xs(static_cast<size_t>(dim));
  const float* mu = mean_.ptr<float>(0);
  const float* is = inv_std_.ptr<float>(0);
  for (int k = 0; k < dim; ++k)
    xs[static_cast<size_t>(k)] = (f[static_cast<size_t>(k)] - mu[k]) * is[k];
  s.decision.resize(static_cast<size_t>(classes));
  std::vector<int> votes(static_cast<size_t>(classes));
  decision(xs.data(), s.decision.data(), votes.data());
  int best = 0;
  const bool linear = is_linear(options_.classifier.kind);
  for (int k = 1; k < classes; ++k) {
    const size_t a = static_cast<size_t>(k), b = static_cast<size_t>(best);
    if (linear ? s.decision[a] > s.decision[b]
               : (votes[a] > votes[b] || (votes[a] == votes[b] && s.decision[a] > s.decision[b])))
      best = k;
  }
  softmax(s.decision.data(), classes, temperature_, s.scores);
  s.best_decision = s.decision[static_cast<size_t>(best)];
  s.novelty = centroid_distance(centroids_, radii_, xs.data(), best);
  if (reject && (s.best_decision < reject_threshold_ || s.novelty > novelty_threshold_)) {
    s.rejected = true;
    return s;  // label none, index -1
  }
  s.index = best;
  s.label = labels_[static_cast<size_t>(best)];
  return s;
}

Status ActionModel::save(const fs::path& path) const {
  const fs::path tmp = path.string() + ".part";
  try {
    cv::FileStorage f(tmp.string(), cv::FileStorage::WRITE | cv::FileStorage::FORMAT_YAML);
    if (!f.isOpened()) return make_error(ErrorCode::kIoError, "{}: cannot write", path.string());
    const auto& o = options_;
    f << "format" << kFormatName << "version" << kFormatVersion;
    f << "description" << description;
    f << "labels"
      << "[";
    for (const auto& l : labels_) f << l;
    f << "]";
    f << "window_s" << window_s_;
    f << "body"
      << "{"
      << "up" << cv::Mat(o.body.up).reshape(1, 1) << "normalize_facing"
      << static_cast<int>(o.body.normalize_facing) << "normalize_scale"
      << static_cast<int>(o.body.normalize_scale) << "min_confidence" << o.body.min_confidence
      << "default_body_size_m" << o.body.default_body_size_m << "normalize_bones"
      << static_cast<int>(o.body.normalize_bones) << "}";
    f << "features"
      << "{"
      << "method" << std::string(to_string(o.features.method)) << "joints"
      << std::string(to_string(o.features.joints)) << "samples" << o.features.samples
      << "rjp_frames" << o.features.rjp_frames << "pyramid_levels" << o.features.pyramid_levels
      << "velocities" << static_cast<int>(o.features.velocities) << "fourier" << o.features.fourier
      << "rjp_average" << static_cast<int>(o.features.rjp_average) << "pose_relative"
      << static_cast<int>(o.features.pose_relative) << "distances"
      << static_cast<int>(o.features.distances) << "}";
    f << "classifier"
      << "{"
      << "kind" << std::string(to_string(o.classifier.kind)) << "c" << o.classifier.c << "gamma"
      << o.classifier.gamma << "standardize_each" << static_cast<int>(o.classifier.standardize_each)
      << "l1" << static_cast<int>(o.classifier.l1) << "reject_folds" << o.classifier.reject_folds
      << "reject_quantile" << o.classifier.reject_quantile << "novelty_margin"
      << o.classifier.novelty_margin << "reject_threshold" << reject_threshold_
      << "novelty_threshold" << novelty_threshold_ << "score_temperature" << temperature_ << "}";
    f << "training"
      << "{"
      << "examples" << examples_ << "skipped" << skipped_ << "augment_mirror"
      << static_cast<int>(o.augment_mirror) << "crops" << o.crops << "crop_fraction"
      << o.crop_fraction << "}";
    f << "standardize"
      << "{"
      << "mean" << mean_ << "inv_std" << inv_std_ << "}";
    f << "centroids"
      << "{"
      << "means" << centroids_ << "radii" << radii_ << "}";
    if (is_linear(o.classifier.kind)) {
      f << "linear"
        << "{"
        << "weights" << weights_ << "bias" << bias_ << "}";
    } else {
      f << "rbf"
        << "{"
        << "gamma" << gamma_ << "support_vectors" << support_vectors_ << "coef" << coef_ << "rho"
        << rho_ << "counts" << counts_ << "}";
    }
    f.release();
  } catch (const cv::Exception& e) {
    return make_error(ErrorCode::kIoError, "{}: cannot write ({})", path.string(), e.msg);
  }
  return rename_model_file(tmp, path);
}

Result<ActionModel> ActionModel::load(const fs::path& path) {
  ActionModel m;
  try {
    DS_ASSIGN_OR_RETURN(cv::FileStorage f, open_model_file(file_kind(), path));
    auto need = [&](const cv::FileNode& parent, const char* key,
                    const std::string& where) -> cv::FileNode {
      cv::FileNode n = parent[key];
      if (n.empty()) throw std::runtime_error("missing key " + where + key);
      return n;
    };
    auto& o = m.options_;
    if (!f["description"].empty()) f["description"] >> m.description;
    const cv::FileNode labels = need(f.root(), "labels", "");
    if (!labels.isSeq()) return tl::unexpected(corrupt(path, "labels is not a list"));
    for (const auto& l : labels) m.labels_.push_back(static_cast<std::string>(l));
    need(f.root(), "window_s", "") >> m.window_s_;
    const cv::FileNode body = need(f.root(), "body", "");
    cv::Mat up;
    need(body, "up", "body.") >> up;
    if (up.total() != 3) return tl::unexpected(corrupt(path, "body.up must have 3 numbers"));
    up.convertTo(up, CV_64F);
    o.body.up = cv::Vec3d(up.at<double>(0), up.at<double>(1), up.at<double>(2));
    o.body.normalize_facing = static_cast<int>(need(body, "normalize_facing", "body.")) != 0;
    o.body.normalize_scale = static_cast<int>(need(body, "normalize_scale", "body.")) != 0;
    o.body.min_confidence = static_cast<float>(need(body, "min_confidence", "body."));
    o.body.default_body_size_m = static_cast<double>(need(body, "default_body_size_m", "body."));
    o.body.normalize_bones = static_cast<int>(need(body, "normalize_bones", "body.")) != 0;
    const cv::FileNode fe = need(f.root(), "features", "");
    auto method =
        feature_method_from_string(static_cast<std::string>(need(fe, "method", "features.")));
    if (!method) return tl::unexpected(corrupt(path, "features.method: " + method.error().message));
    o.features.method = *method;
    auto joints = joint_set_from_string(static_cast<std::string>(need(fe, "joints", "features.")));
    if (!joints) return tl::unexpected(corrupt(path, "features.joints: " + joints.error().message));
    o.features.joints = *joints;
    o.features.samples = static_cast<int>(need(fe, "samples", "features."));
    o.features.rjp_frames = static_cast<int>(need(fe, "rjp_frames", "features."));
    o.features.pyramid_levels = static_cast<int>(need(fe, "pyramid_levels", "features."));
    o.features.velocities = static_cast<int>(need(fe, "velocities", "features.")) != 0;
    o.features.fourier = static_cast<int>(need(fe, "fourier", "features."));
    o.features.rjp_average = static_cast<int>(need(fe, "rjp_average", "features.")) != 0;
    o.features.pose_relative = static_cast<int>(need(fe, "pose_relative", "features.")) != 0;
    // Models written before the distances existed have none.
    if (!fe["distances"].empty()) o.features.distances = static_cast<int>(fe["distances"]) != 0;
    const cv::FileNode cl = need(f.root(), "classifier", "");
    auto kind =
        classifier_kind_from_string(static_cast<std::string>(need(cl, "kind", "classifier.")));
    if (!kind) return tl::unexpected(corrupt(path, "classifier.kind: " + kind.error().message));
    o.classifier.kind = *kind;
    o.classifier.c = static_cast<double>(need(cl, "c", "classifier."));
    o.classifier.gamma = static_cast<double>(need(cl, "gamma", "classifier."));
    o.classifier.reject_folds = static_cast<int>(need(cl, "reject_folds", "classifier."));
    o.classifier.standardize_each =
        static_cast<int>(need(cl, "standardize_each", "classifier.")) != 0;
    o.classifier.l1 = static_cast<int>(need(cl, "l1", "classifier.")) != 0;
    o.classifier.reject_quantile = static_cast<double>(need(cl, "reject_quantile", "classifier."));
    m.reject_threshold_ = static_cast<double>(need(cl, "reject_threshold", "classifier."));
    o.classifier.novelty_margin = static_cast<double>(need(cl, "novelty_margin", "classifier."));
    m.novelty_threshold_ = static_cast<double>(need(cl, "novelty_threshold", "classifier."));
    m.temperature_ = static_cast<double>(need(cl, "score_temperature", "classifier."));
    if (const cv::FileNode tr = f["training"]; tr.isMap()) {
      if (!tr["examples"].empty()) tr["examples"] >> m.examples_;
      if (!tr["skipped"].empty()) tr["skipped"] >> m.skipped_;
      if (!tr["augment_mirror"].empty())
        o.augment_mirror = static_cast<int>(tr["augment_mirror"]) != 0;
      if (!tr["crops"].empty()) tr["crops"] >> o.crops;
      if (!tr["crop_fraction"].empty()) tr["crop_fraction"] >> o.crop_fraction;
    }
    if (auto s = o.check(); !s) return tl::unexpected(corrupt(path, s.error().message));
    const cv::FileNode st = need(f.root(), "standardize", "");
    need(st, "mean", "standardize.") >> m.mean_;
    need(st, "inv_std", "standardize.") >> m.inv_std_;
    const int dim = feature_dimension(o.features);
    const int classes = static_cast<int>(m.labels_.size());
    if (classes < 2) return tl::unexpected(corrupt(path, "fewer than two labels"));
    auto shape_ok = [](const cv::Mat& a, int rows, int cols, int type) {
      return a.rows == rows && a.cols == cols && a.type() == type;
    };
    if (!shape_ok(m.mean_, 1, dim, CV_32F) || !shape_ok(m.inv_std_, 1, dim, CV_32F))
      return tl::unexpected(corrupt(
          path, fmt::format("standardize: expected 1 x {} float rows for these features", dim)));
    const cv::FileNode ce = need(f.root(), "centroids", "");
    need(ce, "means", "centroids.") >> m.centroids_;
    need(ce, "radii", "centroids.") >> m.radii_;
    if (!shape_ok(m.centroids_, classes, dim, CV_32F) || !shape_ok(m.radii_, classes, 1, CV_32F))
      return tl::unexpected(corrupt(path, "centroids: inconsistent sizes"));
    if (is_linear(o.classifier.kind)) {
      const cv::FileNode li = need(f.root(), "linear", "");
      need(li, "weights", "linear.") >> m.weights_;
      need(li, "bias", "linear.") >> m.bias_;
      if (!shape_ok(m.weights_, classes, dim, CV_32F) || !shape_ok(m.bias_, classes, 1, CV_32F))
        return tl::unexpected(corrupt(
            path,
            fmt::format("linear: expected {} x {} weights and {} biases", classes, dim, classes)));
    } else {
      const cv::FileNode r = need(f.root(), "rbf", "");
      need(r, "gamma", "rbf.") >> m.gamma_;
      need(r, "support_vectors", "rbf.") >> m.support_vectors_;
      need(r, "coef", "rbf.") >> m.coef_;
      need(r, "rho", "rbf.") >> m.rho_;
      need(r, "counts", "rbf.") >> m.counts_;
      const int l = m.support_vectors_.rows;
      if (!shape_ok(m.support_vectors_, l, dim, CV_32F) ||
          !shape_ok(m.coef_, std::max(classes - 1, 1), l, CV_64F) ||
          !shape_ok(m.rho_, 1, classes * (classes - 1) / 2, CV_64F) ||
          !shape_ok(m.counts_, 1, classes, CV_32S) || cv::sum(m.counts_)[0] != l || !(m.gamma_ > 0))
        return tl::unexpected(corrupt(path, "rbf: inconsistent sizes"));
    }
  } catch (const cv::Exception& e) {
    return tl::unexpected(corrupt(path, "unreadable YAML, truncated or corrupt: " +
                                            (e.err.empty() ? std::string("parse error") : e.err)));
  } catch (const std::exception& e) {
    return tl::unexpected(corrupt(path, e.what()));
  }
  return m;
}

}  // namespace dreamsense::actions
