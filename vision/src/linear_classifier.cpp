// dlib provides the optimisers (L-BFGS for the softmax, dual coordinate descent for the SVMs);
// Eigen the matrix products of the softmax objective. Both stay in this file.
#include "dreamsense/vision/linear_classifier.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <dlib/optimization.h>
#include <dlib/svm.h>

namespace dreamsense::vision {
namespace {

using RowMatrixF = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

Status check_training_set(const cv::Mat& samples, const std::vector<int>& labels, int classes) {
  if (samples.type() != CV_32FC1 || samples.rows < 1 || samples.cols < 1)
    return make_error(ErrorCode::kInvalidArgument,
                      "training samples must be a non-empty CV_32F matrix");
  if (labels.size() != static_cast<size_t>(samples.rows))
    return make_error(ErrorCode::kInvalidArgument, "{} labels for {} samples", labels.size(),
                      samples.rows);
  if (classes < 2) return make_error(ErrorCode::kInvalidArgument, "need at least 2 classes");
  std::vector<int> count(static_cast<size_t>(classes), 0);
  for (int y : labels) {
    if (y < 0 || y >= classes)
      return make_error(ErrorCode::kInvalidArgument, "label {} outside [0, {})", y, classes);
    ++count[static_cast<size_t>(y)];
  }
  for (int k = 0; k < classes; ++k)
    if (count[static_cast<size_t>(k)] == 0)
      return make_error(ErrorCode::kInvalidArgument, "class {} has no training sample", k);
  return ok_status();
}

}  // namespace

Standardizer Standardizer::fit(const cv::Mat& x) {
  DS_CHECK_EQ(x.type(), CV_32FC1);
  Standardizer s;
  const int n = x.rows, d = x.cols;
  std::vector<double> sum(static_cast<size_t>(d), 0.0), sq(static_cast<size_t>(d), 0.0);
  for (int i = 0; i < n; ++i) {
    const float* p = x.ptr<float>(i);
    for (int j = 0; j < d; ++j) sum[j] += p[j];
  }
  s.mean.resize(static_cast<size_t>(d));
  for (int j = 0; j < d; ++j) s.mean[j] = static_cast<float>(sum[j] / std::max(n, 1));
  for (int i = 0; i < n; ++i) {
    const float* p = x.ptr<float>(i);
    for (int j = 0; j < d; ++j) {
      const double v = p[j] - s.mean[j];
      sq[j] += v * v;
    }
  }
  s.inv_std.resize(static_cast<size_t>(d));
  for (int j = 0; j < d; ++j) {
    const double sd = std::sqrt(sq[j] / std::max(n, 1));
    s.inv_std[j] = sd > 1e-8 ? static_cast<float>(1.0 / sd) : 1.f;
  }
  return s;
}

void Standardizer::apply(cv::Mat& x) const {
  DS_CHECK_EQ(x.cols, static_cast<int>(mean.size()));
  for (int i = 0; i < x.rows; ++i) {
    float* p = x.ptr<float>(i);
    for (int j = 0; j < x.cols; ++j) p[j] = (p[j] - mean[j]) * inv_std[j];
  }
}

void Standardizer::apply(std::vector<float>& x) const {
  DS_CHECK_EQ(x.size(), mean.size());
  for (size_t j = 0; j < x.size(); ++j) x[j] = (x[j] - mean[j]) * inv_std[j];
}

std::vector<float> LinearClassifier::scores(const std::vector<float>& x) const {
  DS_CHECK_EQ(static_cast<int>(x.size()), dims());
  std::vector<float> s(static_cast<size_t>(classes()));
  for (int k = 0; k < classes(); ++k) {
    const float* w = weights.ptr<float>(k);
    double acc = bias[k];
    for (int j = 0; j < dims(); ++j) acc += static_cast<double>(w[j]) * x[j];
    s[k] = static_cast<float>(acc);
  }
  return s;
}

std::vector<float> softmax(const std::vector<float>& s) {
  std::vector<float> p(s.size());
  if (s.empty()) return p;
  const float m = *std::max_element(s.begin(), s.end());
  double sum = 0;
  for (size_t k = 0; k < s.size(); ++k) sum += p[k] = std::exp(s[k] - m);
  for (float& v : p) v = static_cast<float>(v / sum);
  return p;
}

Status SoftmaxOptions::check() const {
  if (!(l2 >= 0) || max_iterations < 1 || !(tolerance > 0))
    return make_error(ErrorCode::kInvalidArgument,
                      "SoftmaxOptions: l2 >= 0, max_iterations >= 1, tolerance > 0");
  return ok_status();
}

Status SvmOptions::check() const {
  if (!(c > 0) || !(epsilon > 0) || max_iterations < 1)
    return make_error(ErrorCode::kInvalidArgument,
                      "SvmOptions: c > 0, epsilon > 0, max_iterations >= 1");
  return ok_status();
}

Result<LinearClassifier> train_softmax(const cv::Mat& samples, const std::vector<int>& labels,
                                       int classes, const SoftmaxOptions& o) {
  if (auto s = o.check(); !s) return tl::unexpected(s.error());
  if (auto s = check_training_set(samples, labels, classes); !s) return tl::unexpected(s.error());
  const int n = samples.rows, d = samples.cols, k = classes;
  cv::Mat cont = samples.isContinuous() ? samples : samples.clone();
  Eigen::Map<const RowMatrixF> x(cont.ptr<float>(0), n, d);
  // Per-sample weights (class balancing), normalised to sum 1.
  std::vector<double> count(static_cast<size_t>(k), 0.0);
  for (int y : labels) count[y] += 1;
  Eigen::VectorXf w(n);
  double wsum = 0;
  for (int i = 0; i < n; ++i)
    wsum += w[i] = o.balance_classes ? float(n / (k * count[labels[i]])) : 1.f;
  w /= static_cast<float>(wsum);

  using Column = dlib::matrix<double, 0, 1>;
  const long np = static_cast<long>(k) * d + k;
  Column cached_at, cached_grad;
  double cached_value = 0;
  auto evaluate = [&](const Column& theta) {
    if (cached_at.size() == theta.size() && cached_at == theta) return;
    RowMatrixF wk(k, d);
    Eigen::VectorXf b(k);
    for (int c = 0; c < k; ++c) {
      for (int j = 0; j < d; ++j) wk(c, j) = static_cast<float>(theta(c * d + j));
      b[c] = static_cast<float>(theta(static_cast<long>(k) * d + c));
    }
    RowMatrixF z = x * wk.transpose();  // n x k
    double loss = 0;
    for (int i = 0; i < n; ++i) {
      for (int c = 0; c < k; ++c) z(i, c) += b[c];
      float m = z(i, 0);
      for (int c = 1; c < k; ++c) m = std::max(m, z(i, c));
      double sum = 0;
      for (int c = 0; c < k; ++c) sum += std::exp(static_cast<double>(z(i, c) - m));
      const double lse = m + std::log(sum);
      loss -= w[i] * (z(i, labels[i]) - lse);
      for (int c = 0; c < k; ++c)
        z(i, c) =
            static_cast<float>(w[i] * (std::exp(z(i, c) - lse) - (c == labels[i] ? 1.0 : 0.0)));
    }
    const RowMatrixF gw = z.transpose() * x;  // k x d
    cached_grad.set_size(np);
    double reg = 0;
    for (int c = 0; c < k; ++c) {
      for (int j = 0; j < d; ++j) {
        const double v = theta(c * d + j);
        reg += v * v;
        cached_grad(c * d + j) = gw(c, j) + o.l2 * v;
      }
      double gb = 0;
      for (int i = 0; i < n; ++i) gb += z(i, c);
      cached_grad(static_cast<long>(k) * d + c) = gb;
    }
    cached_value = loss + 0.5 * o.l2 * reg;
    cached_at = theta;
  };
  Column theta(np);
  theta = 0;
  dlib::find_min(
      dlib::lbfgs_search_strategy(10),
      dlib::objective_delta_stop_strategy(o.tolerance,
                                          static_cast<unsigned long>(o.max_iterations)),
      [&](const Column& t) {
        evaluate(t);
        return cached_value;
      },
      [&](const Column& t) {
        evaluate(t);
        return cached_grad;
      },
      theta, -1e300);
  LinearClassifier out;
  out.weights.create(k, d, CV_32F);
  out.bias.resize(static_cast<size_t>(k));
  for (int c = 0; c < k; ++c) {
    for (int j = 0; j < d; ++j) out.weights.at<float>(c, j) = static_cast<float>(theta(c * d + j));
    out.bias[c] = static_cast<float>(theta(static_cast<long>(k) * d + c));
  }
  return out;
}

Result<LinearClassifier> train_one_vs_rest_svm(const cv::Mat& samples,
                                               const std::vector<int>& labels, int classes,
                                               const SvmOptions& o) {
  if (auto s = o.check(); !s) return tl::unexpected(s.error());
  if (auto s = check_training_set(samples, labels, classes); !s) return tl::unexpected(s.error());
  using Sample = dlib::matrix<double, 0, 1>;
  using Kernel = dlib::linear_kernel<Sample>;
  const int n = samples.rows, d = samples.cols;
  std::vector<Sample> xs(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    xs[i].set_size(d);
    const float* p = samples.ptr<float>(i);
    for (int j = 0; j < d; ++j) xs[i](j) = p[j];
  }
  LinearClassifier out;
  out.weights.create(classes, d, CV_32F);
  out.bias.resize(static_cast<size_t>(classes));
  std::vector<double> ys(static_cast<size_t>(n));
  for (int c = 0; c < classes; ++c) {
    for (int i = 0; i < n; ++i) ys[i] = labels[i] == c ? +1.0 : -1.0;
    dlib::svm_c_linear_dcd_trainer<Kernel> trainer;
    trainer.set_c(o.c);
    trainer.set_epsilon(o.epsilon);
    trainer.set_max_iterations(static_cast<unsigned long>(o.max_iterations));
    trainer.include_bias(true);
    const dlib::decision_function<Kernel> df = trainer.train(xs, ys);
    // Linear: one basis vector w with alpha 1; f(x) = w.x - b.
    Sample wv = df.alpha(0) * df.basis_vectors(0);
    for (long j = 1; j < df.basis_vectors.size(); ++j) wv += df.alpha(j) * df.basis_vectors(j);
    for (int j = 0; j < d; ++j) out.weights.at<float>(c, j) = static_cast<float>(wv(j));
    out.bias[c] = static_cast<float>(-df.b);
  }
  return out;
}

void write_linear(cv::FileStorage& fs, const std::string& name, const LinearClassifier& c) {
  fs << name << "{";
  fs << "weights" << c.weights;
  fs << "bias" << cv::Mat(c.bias, true).reshape(1, 1);
  fs << "}";
}

Result<LinearClassifier> read_linear(const cv::FileNode& node, const std::string& what) {
  if (node.empty() || !node.isMap())
    return make_error(ErrorCode::kCorruptData, "{}: missing classifier", what);
  LinearClassifier c;
  cv::Mat bias;
  try {
    node["weights"] >> c.weights;
    node["bias"] >> bias;
  } catch (const cv::Exception& e) {
    return make_error(ErrorCode::kCorruptData, "{}: unreadable classifier", what);
  }
  if (c.weights.type() != CV_32FC1 || c.weights.empty() || bias.type() != CV_32FC1 ||
      static_cast<int>(bias.total()) != c.weights.rows)
    return make_error(ErrorCode::kCorruptData, "{}: classifier weights/bias of wrong shape", what);
  c.bias.assign(bias.ptr<float>(0), bias.ptr<float>(0) + bias.total());
  return c;
}

void write_standardizer(cv::FileStorage& fs, const std::string& name, const Standardizer& s) {
  fs << name << "{";
  fs << "mean" << cv::Mat(s.mean, true).reshape(1, 1);
  fs << "inv_std" << cv::Mat(s.inv_std, true).reshape(1, 1);
  fs << "}";
}

Result<Standardizer> read_standardizer(const cv::FileNode& node, const std::string& what) {
  if (node.empty() || !node.isMap())
    return make_error(ErrorCode::kCorruptData, "{}: missing standardizer", what);
  cv::Mat mean, inv;
  try {
    node["mean"] >> mean;
    node["inv_std"] >> inv;
  } catch (const cv::Exception&) {
    return make_error(ErrorCode::kCorruptData, "{}: unreadable standardizer", what);
  }
  if (mean.type() != CV_32FC1 || inv.type() != CV_32FC1 || mean.total() != inv.total() ||
      mean.empty())
    return make_error(ErrorCode::kCorruptData, "{}: standardizer of wrong shape", what);
  Standardizer s;
  s.mean.assign(mean.ptr<float>(0), mean.ptr<float>(0) + mean.total());
  s.inv_std.assign(inv.ptr<float>(0), inv.ptr<float>(0) + inv.total());
  return s;
}

}  // namespace dreamsense::vision
