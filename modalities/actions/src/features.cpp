#include "dreamsense/actions/features.hpp"

#include <cmath>

namespace dreamsense::actions {

std::string_view to_string(FeatureMethod m) {
  return m == FeatureMethod::kRelativePositions ? "relative_positions" : "pyramid";
}

Result<FeatureMethod> feature_method_from_string(std::string_view s) {
  if (s == "relative_positions") return FeatureMethod::kRelativePositions;
  if (s == "pyramid") return FeatureMethod::kPyramid;
  return make_error(ErrorCode::kInvalidArgument,
                    "unknown feature method '{}' (relative_positions, pyramid)", s);
}

std::string_view to_string(JointSet s) { return s == JointSet::kAll ? "all" : "upper_body"; }

Result<JointSet> joint_set_from_string(std::string_view s) {
  if (s == "all") return JointSet::kAll;
  if (s == "upper_body") return JointSet::kUpperBody;
  return make_error(ErrorCode::kInvalidArgument, "unknown joint set '{}' (all, upper_body)", s);
}

std::vector<int> joint_indices(JointSet s) {
  // Core's JointId order puts the ten DREAM joints first, then spine and hip centre.
  const int n = s == JointSet::kAll ? kJointCount : static_cast<int>(JointId::kHipCenter) + 1;
  std::vector<int> out(static_cast<size_t>(n));
  for (int j = 0; j < n; ++j) out[static_cast<size_t>(j)] = j;
  return out;
}

Status FeatureOptions::check() const {
  if (samples < 4 || samples > 512)
    return make_error(ErrorCode::kInvalidArgument, "features: samples must be in [4, 512]");
  if (rjp_frames < 1 || rjp_frames > 64)
    return make_error(ErrorCode::kInvalidArgument, "features: rjp_frames must be in [1, 64]");
  if (pyramid_levels < 1 || pyramid_levels > 5)
    return make_error(ErrorCode::kInvalidArgument, "features: pyramid_levels must be in [1, 5]");
  if (fourier < 0 || fourier >= samples / 2)
    return make_error(ErrorCode::kInvalidArgument, "features: fourier must be in [0, samples / 2)");
  return ok_status();
}

int feature_dimension(const FeatureOptions& o) {
  const int j = static_cast<int>(joint_indices(o.joints).size());
  if (o.method == FeatureMethod::kRelativePositions) return o.rjp_frames * (j * (j - 1) / 2) * 3;
  const int cells = (1 << o.pyramid_levels) - 1;
  const int pairs = o.distances ? j * (j - 1) / 2 : 0;
  return cells * 3 * j * (o.velocities ? 2 : 1) + o.fourier * 3 * j + cells * 2 * pairs;
}

std::vector<float> extract_features(const NormalizedWindow& w, const FeatureOptions& o) {
  if (!w.usable || w.frames == 0) return {};
  const std::vector<int> joints = joint_indices(o.joints);
  const int nj = static_cast<int>(joints.size());
  std::vector<float> out;
  out.reserve(static_cast<size_t>(feature_dimension(o)));
  if (o.method == FeatureMethod::kRelativePositions) {
    // Instants (the seed), or cell means of the densely resampled window (rjp_average).
    const int per_cell = o.rjp_average ? std::max(o.samples / o.rjp_frames, 1) : 1;
    const std::vector<cv::Vec3f> r = resample_positions(w, o.rjp_frames * per_cell);
    for (int k = 0; k < o.rjp_frames; ++k) {
      const size_t first = out.size();
      for (int i = 0; i < per_cell; ++i) {
        const cv::Vec3f* frame = &r[static_cast<size_t>(k * per_cell + i) * kJointCount];
        size_t at = first;
        for (int a = 0; a < nj; ++a)
          for (int b = a + 1; b < nj; ++b) {
            const cv::Vec3f d =
                (frame[joints[static_cast<size_t>(a)]] - frame[joints[static_cast<size_t>(b)]]) /
                static_cast<float>(per_cell);
            if (i == 0) {
              out.insert(out.end(), {d[0], d[1], d[2]});
            } else {
              for (int c = 0; c < 3; ++c) out[at + static_cast<size_t>(c)] += d[c];
            }
            at += 3;
          }
      }
    }
    return out;
  }
  const int s = o.samples;
  const std::vector<cv::Vec3f> r = resample_positions(w, s);
  // Series per coordinate: x[c][t], c = joint * 3 + axis.
  const int nc = nj * 3;
  std::vector<float> x(static_cast<size_t>(nc * s)), v(static_cast<size_t>(nc * s));
  const int root = static_cast<int>(JointId::kHipCenter);
  for (int t = 0; t < s; ++t) {
    const cv::Vec3f* frame = &r[static_cast<size_t>(t) * kJointCount];
    for (int a = 0; a < nj; ++a) {
      const int j = joints[static_cast<size_t>(a)];
      const cv::Vec3f p = o.pose_relative && j != root ? frame[j] - frame[root] : frame[j];
      for (int k = 0; k < 3; ++k) x[static_cast<size_t>((a * 3 + k) * s + t)] = p[k];
    }
  }
  // Velocity per window duration (central differences), so a window's speed is comparable
  // across window lengths and frame rates.
  const float per_window = static_cast<float>(s - 1);
  for (int c = 0; c < nc; ++c)
    for (int t = 0; t < s; ++t) {
      const int t0 = std::max(t - 1, 0), t1 = std::min(t + 1, s - 1);
      v[static_cast<size_t>(c * s + t)] =
          (x[static_cast<size_t>(c * s + t1)] - x[static_cast<size_t>(c * s + t0)]) * per_window /
          static_cast<float>(t1 - t0);
    }
  for (int level = 0; level < o.pyramid_levels; ++level) {
    const int cells = 1 << level;
    for (int cell = 0; cell < cells; ++cell) {
      const int b = cell * s / cells, e = (cell + 1) * s / cells;
      for (const std::vector<float>* series : {&x, &v}) {
        if (series == &v && !o.velocities) continue;
        for (int c = 0; c < nc; ++c) {
          double sum = 0;
          for (int t = b; t < e; ++t) sum += (*series)[static_cast<size_t>(c * s + t)];
          out.push_back(static_cast<float>(sum / std::max(e - b, 1)));
        }
      }
    }
  }
  if (o.fourier > 0) {
    std::vector<double> cosine(static_cast<size_t>(o.fourier * s)), sine(cosine.size());
    for (int f = 1; f <= o.fourier; ++f)
      for (int t = 0; t < s; ++t) {
        const double a = 2 * CV_PI * f * t / s;
        cosine[static_cast<size_t>((f - 1) * s + t)] = std::cos(a);
        sine[static_cast<size_t>((f - 1) * s + t)] = std::sin(a);
      }
    for (int c = 0; c < nc; ++c) {
      const float* series = &x[static_cast<size_t>(c * s)];
      for (int f = 0; f < o.fourier; ++f) {
        double re = 0, im = 0;
        const double* cs = &cosine[static_cast<size_t>(f * s)];
        const double* sn = &sine[static_cast<size_t>(f * s)];
        for (int t = 0; t < s; ++t) {
          re += series[t] * cs[t];
          im -= series[t] * sn[t];
        }
        out.push_back(static_cast<float>(std::hypot(re, im) / s));
      }
    }
  }
  if (o.distances) {
    // d[p][t]: the distance of joint pair p at instant t (the resampled window, not the
    // pose-relative series: a distance needs no origin).
    const int np = nj * (nj - 1) / 2;
    std::vector<float> d(static_cast<size_t>(np * s));
    for (int t = 0; t < s; ++t) {
      const cv::Vec3f* frame = &r[static_cast<size_t>(t) * kJointCount];
      int p = 0;
      for (int a = 0; a < nj; ++a)
        for (int b = a + 1; b < nj; ++b, ++p)
          d[static_cast<size_t>(p * s + t)] = static_cast<float>(cv::norm(
              frame[joints[static_cast<size_t>(a)]] - frame[joints[static_cast<size_t>(b)]]));
    }
    for (int level = 0; level < o.pyramid_levels; ++level) {
      const int cells = 1 << level;
      for (int cell = 0; cell < cells; ++cell) {
        const int b = cell * s / cells, e = (cell + 1) * s / cells, n = std::max(e - b, 1);
        for (int p = 0; p < np; ++p) {
          double sum = 0, sq = 0;
          for (int t = b; t < e; ++t) {
            const double v = d[static_cast<size_t>(p * s + t)];
            sum += v;
            sq += v * v;
          }
          const double m = sum / n;
          out.push_back(static_cast<float>(m));
          out.push_back(static_cast<float>(std::sqrt(std::max(sq / n - m * m, 0.0))));
        }
      }
    }
  }
  return out;
}

}  // namespace dreamsense::actions
