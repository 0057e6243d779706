#pragma once
// Dense wrappers around liblinear (linear SVM, one-vs-rest) and libsvm (RBF SVM, one-vs-one):
// they train, and we keep the learnt numbers in our own model file and evaluate the decision
// functions ourselves (no library state at prediction time); and our shrinkage LDA (Eigen).
// Internal to the actions library.

#include <opencv2/core.hpp>

#include <vector>

namespace dreamsense::actions::detail {

// Rows of `x` (CV_32F, N x D) are examples; y[i] in [0, classes).
struct LinearSvm {
  cv::Mat weights;  // classes x D, CV_32F
  cv::Mat bias;     // classes x 1, CV_32F
};
// L2-regularised L2-loss SVM (dual), one-vs-rest, bias term.
LinearSvm train_linear_svm(const cv::Mat& x, const std::vector<int>& y, int classes, double c,
                           bool l1 = false);
void linear_decision(const LinearSvm& m, const float* x, double* out);

// Linear discriminant analysis with Ledoit-Wolf shrinkage (Ledoit & Wolf 2004): per class, the
// shrunk covariance of that class's own standardised examples, scaled back and averaged with the
// class priors (the recipe of scikit-learn's LinearDiscriminantAnalysis(solver="lsqr",
// shrinkage="auto")); discriminants w_k = S^-1 mu_k, b_k = -mu_k'w_k / 2 + log prior_k, in the
// same weights/bias form as the linear SVM. `shrinkage` (optional) receives each class's
// intensity (0 = sample covariance, 1 = scaled identity). A class without examples gets zero
// weights and a very negative bias.
LinearSvm train_shrinkage_lda(const cv::Mat& x, const std::vector<int>& y, int classes,
                              std::vector<double>* shrinkage = nullptr);
// The Ledoit-Wolf shrinkage intensity of centred rows z (n x p), and mu = trace(z'z / n) / p.
double ledoit_wolf_shrinkage(const cv::Mat& z, double* mu = nullptr);

struct RbfSvm {
  double gamma = 0;
  cv::Mat support_vectors;  // nSV x D, CV_32F, grouped by class (class 0 first)
  cv::Mat coef;             // (classes - 1) x nSV, CV_64F (libsvm's sv_coef)
  cv::Mat rho;              // 1 x classes*(classes-1)/2, CV_64F, pairs (0,1), (0,2), ... (1,2)...
  cv::Mat counts;           // 1 x classes, CV_32S: support vectors per class
};
// C-SVC with an RBF kernel (libsvm), one-vs-one.
RbfSvm train_rbf_svm(const cv::Mat& x, const std::vector<int>& y, int classes, double c,
                     double gamma);
// Per class: the mean of its pairwise decision values (oriented towards it), and the
// one-vs-one votes.
void rbf_decision(const RbfSvm& m, const float* x, double* out, int* votes);

}  // namespace dreamsense::actions::detail
