// liblinear's names (problem, parameter, model) stay inside this file.
#include <cstdlib>
#include <linear.h>
#include <memory>

#include "svm_backends.hpp"

namespace dreamsense::actions::detail {
namespace {
void quiet(const char*) {}
}  // namespace

LinearSvm train_linear_svm(const cv::Mat& x, const std::vector<int>& y, int classes, double c,
                           bool l1) {
  CV_Assert(x.type() == CV_32F && x.rows == static_cast<int>(y.size()) && classes >= 2);
  const int n = x.rows, d = x.cols;
  // Dense rows as liblinear nodes: d values, the bias node, the terminator.
  std::vector<feature_node> nodes(static_cast<size_t>(n) * (d + 2));
  std::vector<feature_node*> rows(static_cast<size_t>(n));
  std::vector<double> labels(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    feature_node* r = &nodes[static_cast<size_t>(i) * (d + 2)];
    const float* xi = x.ptr<float>(i);
    for (int k = 0; k < d; ++k) r[k] = {k + 1, xi[k]};
    r[d] = {d + 1, 1.0};
    r[d + 1] = {-1, 0.0};
    rows[static_cast<size_t>(i)] = r;
    labels[static_cast<size_t>(i)] = y[static_cast<size_t>(i)];
  }
  problem prob{};
  prob.l = n;
  prob.n = d + 1;
  prob.y = labels.data();
  prob.x = rows.data();
  prob.bias = 1.0;
  parameter param{};
  param.solver_type = l1 ? L1R_L2LOSS_SVC : L2R_L2LOSS_SVC_DUAL;
  param.eps = l1 ? 0.01 : 0.1;
  param.C = c;
  set_print_string_function(&quiet);
  std::srand(1);  // the dual solver shuffles with rand(): same data, same model
  model* m = train(&prob, &param);
  LinearSvm out;
  out.weights = cv::Mat::zeros(classes, d, CV_32F);
  out.bias = cv::Mat::zeros(classes, 1, CV_32F);
  const int nr = m->nr_class;
  const int columns = nr == 2 ? 1 : nr;
  for (int k = 0; k < nr; ++k) {
    const int cls = m->label[k];
    const int col = nr == 2 ? 0 : k;
    const float sign = (nr == 2 && k == 1) ? -1.f : 1.f;
    for (int f = 0; f < d; ++f)
      out.weights.at<float>(cls, f) = sign * static_cast<float>(m->w[f * columns + col]);
    out.bias.at<float>(cls, 0) = sign * static_cast<float>(m->w[d * columns + col]);
  }
  // A class absent from the training set keeps zero weights and a very negative bias.
  std::vector<bool> seen(static_cast<size_t>(classes), false);
  for (int k = 0; k < nr; ++k) seen[static_cast<size_t>(m->label[k])] = true;
  for (int k = 0; k < classes; ++k)
    if (!seen[static_cast<size_t>(k)]) out.bias.at<float>(k, 0) = -1e3f;
  free_and_destroy_model(&m);
  return out;
}

void linear_decision(const LinearSvm& m, const float* x, double* out) {
  const int d = m.weights.cols;
  for (int k = 0; k < m.weights.rows; ++k) {
    const float* w = m.weights.ptr<float>(k);
    double s = m.bias.at<float>(k, 0);
    for (int f = 0; f < d; ++f) s += static_cast<double>(w[f]) * x[f];
    out[k] = s;
  }
}

}  // namespace dreamsense::actions::detail
