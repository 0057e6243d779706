// Experiment tool (issue 20): cross-validated heads on the features fer_features dumped, on the
// folds of `eval expression` (subject_folds, 10 folds, seed 12).
//   fer_cv DATASET DIR FEATURES.bin CONFIG...
// CONFIG: key=value pairs separated by ';': feat=p+g+d+l+r (blocks), train=0,1,... (transforms
// used as training samples), test=0,9 (transforms whose probabilities are averaged), l2=0.3,
// bal=0|1.
#include "dreamsense/eval/classification.hpp"
#include "dreamsense/eval/faces/datasets.hpp"
#include "dreamsense/expression/labels.hpp"
#include "dreamsense/vision/linear_classifier.hpp"

#include <opencv2/core.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

using namespace dreamsense;

namespace {

struct Data {
  int n = 0, T = 0, per = 0, extra = 0;
  std::vector<int> label, has;
  std::vector<std::vector<float>> v;
};

std::vector<int> ints(const std::string& s) {
  std::vector<int> out;
  std::stringstream ss(s);
  std::string t;
  while (std::getline(ss, t, ',')) out.push_back(std::stoi(t));
  return out;
}

std::vector<float> row1(const Data& d, int i, int t, const std::string& feat);
// CAT: "a,b" concatenates transforms a and b; transform t = 0 means the list, t = 1 the list
// shifted by the mirror offset MIRROR.
std::vector<int> g_cat, g_cat_m;
int g_mirror = 9;
std::vector<float> row(const Data& d, int i, int t, const std::string& feat) {
  if (g_cat.empty()) return row1(d, i, t, feat);
  std::vector<float> out;
  for (size_t k = 0; k < g_cat.size(); ++k) {
    const int c = g_cat[k];
    const std::vector<float> r =
        row1(d, i, t ? (g_cat_m.empty() ? c + g_mirror : g_cat_m[k]) : c, feat);
    out.insert(out.end(), r.begin(), r.end());
  }
  return out;
}
std::vector<float> row1(const Data& d, int i, int t, const std::string& feat) {
  const std::vector<float>& a = d.v[static_cast<size_t>(i)];
  const float* base = a.data() + static_cast<size_t>(t) * d.per;
  const float* ex = a.data() + static_cast<size_t>(d.T) * d.per;
  std::vector<float> out;
  for (char c : feat) {
    if (c == 'p') out.insert(out.end(), base, base + 263);
    if (c == 'f') out.insert(out.end(), base, base + 256);
    if (c == 'g') out.insert(out.end(), base + 263, base + 263 + 1024);
    if (c == 'd') out.insert(out.end(), base + 1287, base + 1287 + 128);
    if (c == 'l') out.insert(out.end(), ex, ex + 256);
    if (c == 'r') out.insert(out.end(), ex + 256, ex + 384);
  }
  return out;
}

}  // namespace

// Small MLP head: D -> H (ReLU, dropout) -> K, softmax cross-entropy, AdamW, minibatches;
// deterministic (own LCG). Early stopping on a held-out 10 % of the training faces.
struct Mlp {
  cv::Mat w1, b1, w2, b2;                    // H x D, 1 x H, K x H, 1 x K
  cv::Mat forward(const cv::Mat& x) const {  // x: N x D -> scores N x K
    cv::Mat h = x * w1.t();
    for (int r = 0; r < h.rows; ++r) {
      float* p = h.ptr<float>(r);
      const float* b = b1.ptr<float>();
      for (int c = 0; c < h.cols; ++c) p[c] = std::max(0.f, p[c] + b[c]);
    }
    cv::Mat s = h * w2.t();
    for (int r = 0; r < s.rows; ++r) s.row(r) += b2;
    return s;
  }
};

struct Lcg {
  uint64_t s;
  explicit Lcg(uint64_t seed) : s(seed * 6364136223846793005ull + 1442695040888963407ull) {}
  uint32_t next() {
    s = s * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<uint32_t>(s >> 33);
  }
  double uniform() { return next() / 2147483648.0; }
  double normal() {
    const double u1 = std::max(1e-12, uniform()), u2 = uniform();
    return std::sqrt(-2 * std::log(u1)) * std::cos(2 * CV_PI * u2);
  }
};

void softmax_rows(cv::Mat& s) {
  for (int r = 0; r < s.rows; ++r) {
    float* p = s.ptr<float>(r);
    float m = p[0];
    for (int c = 1; c < s.cols; ++c) m = std::max(m, p[c]);
    double z = 0;
    for (int c = 0; c < s.cols; ++c) z += (p[c] = std::exp(p[c] - m));
    for (int c = 0; c < s.cols; ++c) p[c] = static_cast<float>(p[c] / z);
  }
}

struct MlpOptions {
  int hidden = 256, epochs = 60, batch = 64;
  double lr = 1e-3, wd = 1e-4, dropout = 0.5;
  uint64_t seed = 1;
};

// x: N x D standardised, y; group[i] = face index (validation split by face).
Mlp train_mlp(const cv::Mat& x, const std::vector<int>& y, const std::vector<int>& group, int K,
              const MlpOptions& o) {
  const int N = x.rows, D = x.cols, H = o.hidden;
  Lcg rng(o.seed);
  Mlp m;
  m.w1.create(H, D, CV_32F);
  m.w2.create(K, H, CV_32F);
  for (int i = 0; i < H * D; ++i)
    m.w1.ptr<float>()[i] = static_cast<float>(rng.normal() * std::sqrt(2.0 / D));
  for (int i = 0; i < K * H; ++i)
    m.w2.ptr<float>()[i] = static_cast<float>(rng.normal() * std::sqrt(1.0 / H));
  m.b1 = cv::Mat::zeros(1, H, CV_32F);
  m.b2 = cv::Mat::zeros(1, K, CV_32F);
  // validation faces: group % 10 == 3 (deterministic)
  std::vector<int> tr, va;
  for (int i = 0; i < N; ++i) ((group[i] * 2654435761u) % 10 == 3 ? va : tr).push_back(i);
  cv::Mat xv(static_cast<int>(va.size()), D, CV_32F);
  for (size_t k = 0; k < va.size(); ++k) x.row(va[k]).copyTo(xv.row(static_cast<int>(k)));
  std::vector<cv::Mat*> params{&m.w1, &m.b1, &m.w2, &m.b2};
  std::vector<cv::Mat> mom, vel;
  for (auto* p : params) {
    mom.push_back(cv::Mat::zeros(p->size(), CV_32F));
    vel.push_back(cv::Mat::zeros(p->size(), CV_32F));
  }
  Mlp best = m;
  double best_acc = -1;
  int step = 0;
  for (int e = 0; e < o.epochs; ++e) {
    std::vector<int> order = tr;
    for (size_t i = order.size(); i > 1; --i) std::swap(order[i - 1], order[rng.next() % i]);
    for (size_t b0 = 0; b0 < order.size(); b0 += o.batch) {
      const int B = static_cast<int>(std::min(order.size(), b0 + o.batch) - b0);
      cv::Mat xb(B, D, CV_32F);
      for (int k = 0; k < B; ++k) x.row(order[b0 + k]).copyTo(xb.row(k));
      cv::Mat h = xb * m.w1.t();
      cv::Mat mask(B, H, CV_32F);
      for (int r = 0; r < B; ++r) {
        float* p = h.ptr<float>(r);
        float* q = mask.ptr<float>(r);
        for (int c = 0; c < H; ++c) {
          p[c] = std::max(0.f, p[c] + m.b1.at<float>(c));
          q[c] = rng.uniform() < o.dropout ? 0.f : static_cast<float>(1.0 / (1 - o.dropout));
          p[c] *= q[c];
        }
      }
      cv::Mat s = h * m.w2.t();
      for (int r = 0; r < B; ++r) s.row(r) += m.b2;
      softmax_rows(s);
      for (int r = 0; r < B; ++r) s.at<float>(r, y[order[b0 + r]]) -= 1.f;
      s *= 1.0 / B;  // dL/ds
      cv::Mat gw2 = s.t() * h, gb2;
      cv::reduce(s, gb2, 0, cv::REDUCE_SUM);
      cv::Mat dh = s * m.w2;
      for (int r = 0; r < B; ++r) {
        float* p = dh.ptr<float>(r);
        const float* hh = h.ptr<float>(r);
        const float* q = mask.ptr<float>(r);
        for (int c = 0; c < H; ++c) p[c] = hh[c] > 0 ? p[c] * q[c] : 0.f;
      }
      cv::Mat gw1 = dh.t() * xb, gb1;
      cv::reduce(dh, gb1, 0, cv::REDUCE_SUM);
      std::vector<cv::Mat> grads{gw1, gb1, gw2, gb2};
      ++step;
      const double b1c = 1 - std::pow(0.9, step), b2c = 1 - std::pow(0.999, step);
      for (size_t k = 0; k < params.size(); ++k) {
        cv::Mat& p = *params[k];
        mom[k] = 0.9 * mom[k] + 0.1 * grads[k];
        cv::Mat g2;
        cv::multiply(grads[k], grads[k], g2);
        vel[k] = 0.999 * vel[k] + 0.001 * g2;
        cv::Mat den;
        cv::sqrt(vel[k] / b2c, den);
        den += 1e-8;
        cv::Mat upd;
        cv::divide(mom[k] / b1c, den, upd);
        p -= o.lr * upd;
        if (k == 0 || k == 2) p -= o.lr * o.wd * p;
      }
    }
    if (!va.empty()) {
      const cv::Mat s = m.forward(xv);
      int ok = 0;
      for (int r = 0; r < s.rows; ++r) {
        cv::Point mx;
        cv::minMaxLoc(s.row(r), nullptr, nullptr, nullptr, &mx);
        ok += mx.x == y[va[r]];
      }
      const double acc = ok / static_cast<double>(s.rows);
      if (acc > best_acc) {
        best_acc = acc;
        best = Mlp{m.w1.clone(), m.b1.clone(), m.w2.clone(), m.b2.clone()};
      }
    }
  }
  return va.empty() ? m : best;
}

int main(int argc, char** argv) {
  if (argc < 5) {
    std::fprintf(stderr, "usage: fer_cv DATASET DIR FEATURES.bin CONFIG...\n");
    return 2;
  }
  auto items = eval::faces::read_expression_dataset(argv[1], argv[2]);
  if (!items) return 1;
  std::vector<std::string> files;
  {
    std::stringstream fs(argv[3]);
    std::string f;
    while (std::getline(fs, f, ',')) files.push_back(f);
  }
  Data d;
  if (files.size() > 1) {  // several dumps: only the 263 pooled + logits of every transform
    for (size_t fi = 0; fi < files.size(); ++fi) {
      std::ifstream in(files[fi], std::ios::binary);
      int h[4];
      in.read(reinterpret_cast<char*>(h), sizeof h);
      const size_t len = static_cast<size_t>(h[1] * h[2] + h[3]);
      if (fi == 0) {
        d.n = h[0];
        d.v.resize(static_cast<size_t>(d.n));
      }
      d.T += h[1];
      std::vector<float> v(len);
      for (int i = 0; i < d.n; ++i) {
        int lh[2];
        in.read(reinterpret_cast<char*>(lh), 8);
        if (fi == 0) {
          d.label.push_back(lh[0]);
          d.has.push_back(lh[1]);
        }
        in.read(reinterpret_cast<char*>(v.data()), static_cast<std::streamsize>(len * 4));
        for (int t = 0; t < h[1]; ++t)
          d.v[static_cast<size_t>(i)].insert(d.v[static_cast<size_t>(i)].end(),
                                             v.begin() + static_cast<long>(t) * h[2],
                                             v.begin() + static_cast<long>(t) * h[2] + 263);
      }
      if (!in) return 1;
    }
    d.per = 263;
    d.extra = 0;
  } else {
    std::ifstream in(argv[3], std::ios::binary);
    int header[4];
    in.read(reinterpret_cast<char*>(header), sizeof header);
    d.n = header[0], d.T = header[1], d.per = header[2], d.extra = header[3];
    const size_t len = static_cast<size_t>(d.T * d.per + d.extra);
    if (const char* lim = std::getenv("FER_CV_PARTIAL")) {  // a dump still being written
      in.seekg(0, std::ios::end);
      const long long size = in.tellg();
      in.seekg(16);
      d.n =
          std::min<int>(d.n, static_cast<int>((size - 16) / (8 + static_cast<long long>(len) * 4)));
      items->resize(static_cast<size_t>(d.n));
      (void)lim;
    }
    for (int i = 0; i < d.n; ++i) {
      int lh[2];
      in.read(reinterpret_cast<char*>(lh), 8);
      d.label.push_back(lh[0]);
      d.has.push_back(lh[1]);
      std::vector<float> v(len);
      in.read(reinterpret_cast<char*>(v.data()), static_cast<std::streamsize>(len * 4));
      d.v.push_back(std::move(v));
    }
    if (!in || d.n != static_cast<int>(items->size())) {
      std::fprintf(stderr, "bad features file\n");
      return 1;
    }
  }
  std::vector<std::string> subjects;
  for (const auto& it : *items) subjects.push_back(it.subject);
  auto folds = eval::subject_folds(subjects, 10, 12);
  std::set<int> present(d.label.begin(), d.label.end());
  const std::vector<int> classes(present.begin(), present.end());
  const int K = static_cast<int>(classes.size());
  auto cls = [&](int label) {
    return static_cast<int>(std::find(classes.begin(), classes.end(), label) - classes.begin());
  };

  for (int a = 4; a < argc; ++a) {
    std::map<std::string, std::string> cfg{
        {"feat", "p"}, {"train", "0"}, {"test", "0"}, {"l2", "0.3"}, {"bal", "0"}};
    std::stringstream ss(argv[a]);
    std::string kv;
    while (std::getline(ss, kv, ';')) {
      const size_t eq = kv.find('=');
      cfg[kv.substr(0, eq)] = kv.substr(eq + 1);
    }
    const auto t0 = std::chrono::steady_clock::now();
    g_cat.clear();
    g_cat_m.clear();
    if (cfg.count("cat")) {
      for (int v : ints(cfg["cat"])) g_cat.push_back(v);
    }
    if (cfg.count("catm")) g_cat_m = ints(cfg["catm"]);
    if (cfg.count("mirror")) g_mirror = std::stoi(cfg["mirror"]);
    std::vector<int> src_correct(3, 0), src_n(3, 0);
    if (cfg.count("seed")) folds = eval::subject_folds(subjects, 10, std::stoull(cfg["seed"]));
    const std::vector<int> train_t = ints(cfg["train"]), test_t = ints(cfg["test"]);
    vision::SoftmaxOptions so;
    so.l2 = std::stod(cfg["l2"]);
    so.balance_classes = cfg["bal"] == "1";
    std::vector<std::vector<int>> confusion(static_cast<size_t>(K), std::vector<int>(K, 0));
    int correct = 0;
    for (const auto& fold : folds) {
      const std::set<std::string> test_subjects(fold.begin(), fold.end());
      cv::Mat x;
      std::vector<int> y, group;
      std::vector<int> test;
      for (int i = 0; i < d.n; ++i) {
        if (test_subjects.count(subjects[static_cast<size_t>(i)])) {
          test.push_back(i);
          continue;
        }
        if (!d.has[static_cast<size_t>(i)]) continue;
        for (int t : train_t) {
          const std::vector<float> r = row(d, i, t, cfg["feat"]);
          x.push_back(cv::Mat(1, static_cast<int>(r.size()), CV_32F, const_cast<float*>(r.data())));
          y.push_back(cls(d.label[static_cast<size_t>(i)]));
          group.push_back(i);
        }
      }
      const vision::Standardizer st = vision::Standardizer::fit(x);
      st.apply(x);
      const bool use_mlp = cfg["head"] == "mlp";
      std::vector<Mlp> mlps;
      vision::LinearClassifier lin;
      if (use_mlp) {
        MlpOptions mo;
        if (cfg.count("hidden")) mo.hidden = std::stoi(cfg["hidden"]);
        if (cfg.count("epochs")) mo.epochs = std::stoi(cfg["epochs"]);
        if (cfg.count("lr")) mo.lr = std::stod(cfg["lr"]);
        if (cfg.count("wd")) mo.wd = std::stod(cfg["wd"]);
        if (cfg.count("dropout")) mo.dropout = std::stod(cfg["dropout"]);
        const int ens = cfg.count("ens") ? std::stoi(cfg["ens"]) : 1;
        for (int e = 0; e < ens; ++e) {
          mo.seed = 1 + e;
          mlps.push_back(train_mlp(x, y, group, K, mo));
        }
      } else {
        auto c = vision::train_softmax(x, y, K, so);
        if (!c) return 1;
        lin = *c;
      }
      std::vector<float> raw;
      auto probs = [&](const std::vector<float>& r) {
        if (cfg["head"] == "raw") {  // the package's own classifier: logits = r[256..263)
          // face-api order neutral, happy, sad, angry, fearful, disgusted, surprised
          const char* names[7] = {"neutral", "happy",   "sadness", "anger",
                                  "fear",    "disgust", "surprise"};
          std::vector<float> p(static_cast<size_t>(K), 0.f);
          for (int k = 0; k < 7; ++k) {
            int label = 0;
            while (std::string(expression::kExpressionLabels[label]) != names[k]) ++label;
            p[static_cast<size_t>(cls(label))] = raw[static_cast<size_t>(256 + k)];
          }
          return vision::softmax(p);
        }
        if (!use_mlp && cfg.count("mixraw")) {  // head + the package's classifier, mixed
          const double w = std::stod(cfg["mixraw"]);
          std::vector<float> p = vision::softmax(lin.scores(r));
          const char* names[7] = {"neutral", "happy",   "sadness", "anger",
                                  "fear",    "disgust", "surprise"};
          std::vector<float> q(static_cast<size_t>(K), 0.f);
          for (int k = 0; k < 7; ++k) {
            int label = 0;
            while (std::string(expression::kExpressionLabels[label]) != names[k]) ++label;
            q[static_cast<size_t>(cls(label))] = raw[static_cast<size_t>(256 + k)];
          }
          q = vision::softmax(q);
          for (int k = 0; k < K; ++k) p[k] = static_cast<float>((1 - w) * p[k] + w * q[k]);
          return p;
        }
        if (!use_mlp) return vision::softmax(lin.scores(r));
        std::vector<float> p(static_cast<size_t>(K), 0.f);
        const cv::Mat xr(1, static_cast<int>(r.size()), CV_32F, const_cast<float*>(r.data()));
        for (const Mlp& mm : mlps) {
          cv::Mat s = mm.forward(xr);
          softmax_rows(s);
          for (int k = 0; k < K; ++k) p[k] += s.at<float>(k) / mlps.size();
        }
        return p;
      };
      for (int i : test) {
        const int truth = cls(d.label[static_cast<size_t>(i)]);
        int pred = -1;
        if (d.has[static_cast<size_t>(i)]) {
          std::vector<float> p(static_cast<size_t>(K), 0.f);
          for (int t : test_t) {
            std::vector<float> r = row(d, i, t, cfg["feat"]);
            raw = r;
            st.apply(r);
            const std::vector<float> q = probs(r);
            for (int k = 0; k < K; ++k) p[k] += q[k];
          }
          pred = static_cast<int>(std::max_element(p.begin(), p.end()) - p.begin());
        }
        if (pred == truth) ++correct;
        if (d.has[static_cast<size_t>(i)] && d.extra == 1) {
          const int src = static_cast<int>(d.v[static_cast<size_t>(i)].back());
          ++src_n[src];
          src_correct[src] += pred == truth;
        }
        if (pred >= 0) ++confusion[truth][pred];
      }
    }
    double bal = 0;
    for (int k = 0; k < K; ++k) {
      int n = 0;
      for (int j = 0; j < K; ++j) n += confusion[k][j];
      bal += n ? confusion[k][k] / static_cast<double>(n) : 0;
    }
    std::printf("%-60s acc %.4f bal %.4f  (%.0f s)\n", argv[a], correct / static_cast<double>(d.n),
                bal / K,
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    if (d.extra == 1)
      std::printf("    by source: landmarks %d/%d, landmarks_from_crop %d/%d, geometry %d/%d\n",
                  src_correct[0], src_n[0], src_correct[1], src_n[1], src_correct[2], src_n[2]);
    std::fflush(stdout);
  }
  return 0;
}
