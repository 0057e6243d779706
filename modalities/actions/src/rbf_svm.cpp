// libsvm's names stay inside this file.
#include <cmath>
#include <cstring>
#include <libsvm/svm.h>

#include "svm_backends.hpp"

namespace dreamsense::actions::detail {
namespace {
void quiet(const char*) {}
}  // namespace

RbfSvm train_rbf_svm(const cv::Mat& x, const std::vector<int>& y, int classes, double c,
                     double gamma) {
  CV_Assert(x.type() == CV_32F && x.rows == static_cast<int>(y.size()) && classes >= 2);
  const int n = x.rows, d = x.cols;
  // Present the examples grouped by class 0, 1, ... so that libsvm's class order is ours.
  std::vector<int> order;
  for (int k = 0; k < classes; ++k)
    for (int i = 0; i < n; ++i)
      if (y[static_cast<size_t>(i)] == k) order.push_back(i);
  std::vector<svm_node> nodes(static_cast<size_t>(n) * (d + 1));
  std::vector<svm_node*> rows(static_cast<size_t>(n));
  std::vector<double> labels(static_cast<size_t>(n));
  for (int r = 0; r < n; ++r) {
    const int i = order[static_cast<size_t>(r)];
    svm_node* row = &nodes[static_cast<size_t>(r) * (d + 1)];
    const float* xi = x.ptr<float>(i);
    for (int k = 0; k < d; ++k) row[k] = {k + 1, xi[k]};
    row[d] = {-1, 0.0};
    rows[static_cast<size_t>(r)] = row;
    labels[static_cast<size_t>(r)] = y[static_cast<size_t>(i)];
  }
  svm_problem prob{};
  prob.l = n;
  prob.y = labels.data();
  prob.x = rows.data();
  svm_parameter param{};
  param.svm_type = C_SVC;
  param.kernel_type = RBF;
  param.gamma = gamma;
  param.cache_size = 200;
  param.eps = 1e-3;
  param.C = c;
  param.shrinking = 1;
  param.probability = 0;
  svm_set_print_string_function(&quiet);
  svm_model* m = svm_train(&prob, &param);
  RbfSvm out;
  out.gamma = gamma;
  const int nr = m->nr_class;  // classes present, in order of first appearance = ascending
  out.support_vectors = cv::Mat::zeros(m->l, d, CV_32F);
  for (int s = 0; s < m->l; ++s)
    for (const svm_node* p = m->SV[s]; p->index != -1; ++p)
      if (p->index >= 1 && p->index <= d)
        out.support_vectors.at<float>(s, p->index - 1) = static_cast<float>(p->value);
  // Expand to all `classes` (a class absent from training gets no support vectors).
  out.counts = cv::Mat::zeros(1, classes, CV_32S);
  for (int k = 0; k < nr; ++k) out.counts.at<int>(0, m->label[k]) = m->nSV[k];
  out.coef = cv::Mat::zeros(std::max(classes - 1, 1), m->l, CV_64F);
  out.rho = cv::Mat::zeros(1, classes * (classes - 1) / 2, CV_64F);
  // libsvm's coef row r for an SV of class i holds its coefficient in the decision function
  // against the (r < i ? r : r + 1)-th class (indices among the classes present).
  std::vector<int> present(static_cast<size_t>(nr));
  for (int k = 0; k < nr; ++k) present[static_cast<size_t>(k)] = m->label[k];
  auto pair_index = [classes](int a, int b) {  // a < b
    return a * classes - a * (a + 1) / 2 + (b - a - 1);
  };
  int start = 0;
  for (int i = 0; i < nr; ++i) {
    for (int s = start; s < start + m->nSV[i]; ++s)
      for (int r = 0; r < nr - 1; ++r) {
        const int j = r < i ? r : r + 1;  // libsvm class position of the other class
        // Our coef row for SV of class ci against class cj: index of cj among classes != ci.
        const int ci = present[static_cast<size_t>(i)], cj = present[static_cast<size_t>(j)];
        const int row = cj < ci ? cj : cj - 1;
        out.coef.at<double>(row, s) = m->sv_coef[r][s];
      }
    start += m->nSV[i];
  }
  int p = 0;
  for (int i = 0; i < nr; ++i)
    for (int j = i + 1; j < nr; ++j, ++p)
      out.rho.at<double>(0, pair_index(present[static_cast<size_t>(i)],
                                       present[static_cast<size_t>(j)])) = m->rho[p];
  svm_free_and_destroy_model(&m);
  return out;
}

void rbf_decision(const RbfSvm& m, const float* x, double* out, int* votes) {
  const int classes = m.counts.cols;
  const int l = m.support_vectors.rows, d = m.support_vectors.cols;
  std::vector<double> kv(static_cast<size_t>(l));
  for (int s = 0; s < l; ++s) {
    const float* sv = m.support_vectors.ptr<float>(s);
    double dist = 0;
    for (int f = 0; f < d; ++f) {
      const double e = static_cast<double>(sv[f]) - x[f];
      dist += e * e;
    }
    kv[static_cast<size_t>(s)] = std::exp(-m.gamma * dist);
  }
  std::vector<int> start(static_cast<size_t>(classes) + 1, 0);
  for (int k = 0; k < classes; ++k)
    start[static_cast<size_t>(k) + 1] = start[static_cast<size_t>(k)] + m.counts.at<int>(0, k);
  for (int k = 0; k < classes; ++k) {
    out[k] = 0;
    votes[k] = 0;
  }
  for (int i = 0; i < classes; ++i)
    for (int j = i + 1; j < classes; ++j) {
      const int ni = m.counts.at<int>(0, i), nj = m.counts.at<int>(0, j);
      if (ni == 0 || nj == 0) continue;  // a class absent from training never wins
      double sum = 0;
      // Coefficients: SV of class i against j sits in row j - 1; SV of class j against i, row i.
      for (int s = start[static_cast<size_t>(i)]; s < start[static_cast<size_t>(i) + 1]; ++s)
        sum += m.coef.at<double>(j - 1, s) * kv[static_cast<size_t>(s)];
      for (int s = start[static_cast<size_t>(j)]; s < start[static_cast<size_t>(j) + 1]; ++s)
        sum += m.coef.at<double>(i, s) * kv[static_cast<size_t>(s)];
      sum -= m.rho.at<double>(0, i * classes - i * (i + 1) / 2 + (j - i - 1));
      out[i] += sum;
      out[j] -= sum;
      ++votes[sum > 0 ? i : j];
    }
  for (int k = 0; k < classes; ++k) out[k] /= std::max(classes - 1, 1);
}

}  // namespace dreamsense::actions::detail
