// The `dreamsense` tracker: DCF on fHOG + Staple colour model + DSST scale + LMCF-style failure
// detection and re-detection. See the header for the method and its sources.

#include "dreamsense/objects/dcf_tracker.hpp"

#include "dreamsense/objects/fhog.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace dreamsense::objects {
namespace {

// A window of `size` image pixels centred at `centre`, resampled to `out` (replicated borders).
cv::Mat extract_window(const cv::Mat& img, const cv::Point2d& centre, const cv::Size2d& size,
                       const cv::Size& out) {
  const int w = std::max(1, static_cast<int>(std::lround(size.width)));
  const int h = std::max(1, static_cast<int>(std::lround(size.height)));
  const int x0 = static_cast<int>(std::floor(centre.x - 0.5 * w + 0.5));
  const int y0 = static_cast<int>(std::floor(centre.y - 0.5 * h + 0.5));
  const cv::Rect want(x0, y0, w, h);
  cv::Rect in = want & cv::Rect(0, 0, img.cols, img.rows);
  if (in.empty()) {  // entirely outside: the nearest border pixel
    const int cx = std::clamp(x0 + w / 2, 0, img.cols - 1);
    const int cy = std::clamp(y0 + h / 2, 0, img.rows - 1);
    in = cv::Rect(cx, cy, 1, 1);
  }
  cv::Mat patch = img(in);
  const int top = std::max(0, in.y - want.y), left = std::max(0, in.x - want.x);
  const int bottom = std::max(0, want.br().y - in.br().y),
            right = std::max(0, want.br().x - in.br().x);
  if (top || left || bottom || right)
    cv::copyMakeBorder(patch, patch, top, bottom, left, right, cv::BORDER_REPLICATE);
  // Shrinking: halve by 2x2 box averages (OpenCV's SIMD INTER_AREA path) while the window is at
  // least twice the output, then linear interpolation: as free of aliasing as INTER_AREA at an
  // arbitrary factor and several times cheaper.
  while (patch.cols >= 2 * out.width && patch.rows >= 2 * out.height) {
    cv::Mat half;
    cv::resize(
        patch(cv::Rect(patch.cols % 2, patch.rows % 2, patch.cols / 2 * 2, patch.rows / 2 * 2)),
        half, cv::Size(patch.cols / 2, patch.rows / 2), 0, 0, cv::INTER_AREA);
    patch = half;
  }
  cv::Mat resized;
  cv::resize(patch, resized, out, 0, 0, cv::INTER_LINEAR);
  return resized;
}

cv::Mat hann(int n) {
  cv::Mat w(1, n, CV_32F);
  for (int i = 0; i < n; ++i)
    w.at<float>(i) =
        n > 1 ? static_cast<float>(0.5 * (1 - std::cos(2 * CV_PI * i / (n - 1)))) : 1.f;
  return w;
}

// Complex (CV_32FC2) divided element-wise by a real (CV_32F) map + lambda.
void divide_by_real(cv::Mat& c, const cv::Mat& r, float lambda) {
  for (int y = 0; y < c.rows; ++y) {
    cv::Vec2f* p = c.ptr<cv::Vec2f>(y);
    const float* q = r.ptr<float>(y);
    for (int x = 0; x < c.cols; ++x) p[x] *= 1.f / (q[x] + lambda);
  }
}

// |X|^2 summed into `acc` (CV_32F).
void add_power(const cv::Mat& xf, cv::Mat& acc) {
  for (int y = 0; y < xf.rows; ++y) {
    const cv::Vec2f* p = xf.ptr<cv::Vec2f>(y);
    float* a = acc.ptr<float>(y);
    for (int x = 0; x < xf.cols; ++x) a[x] += p[x][0] * p[x][0] + p[x][1] * p[x][1];
  }
}

// Subpixel offset of a peak from a parabola through three values.
double parabola(double left, double centre, double right) {
  const double d = left - 2 * centre + right;
  return std::abs(d) < 1e-12 ? 0.0 : std::clamp(0.5 * (left - right) / d, -0.5, 0.5);
}

}  // namespace

Status DcfTrackerOptions::check() const {
  std::string bad;
  auto need = [&bad](bool ok, const char* what) {
    if (!ok) bad += bad.empty() ? what : std::string("; ") + what;
  };
  need(cell_size >= 1 && cell_size <= 16, "cell_size must be in [1, 16]");
  need(padding >= 0.2, "padding must be >= 0.2");
  need(template_side >= 32, "template_side must be >= 32");
  need(output_sigma_factor > 0, "output_sigma_factor must be > 0");
  need(lambda > 0, "lambda must be > 0");
  need(learning_rate > 0 && learning_rate <= 1, "learning_rate must be in (0, 1]");
  need(colour_bins >= 2 && colour_bins <= 64 && (colour_bins & (colour_bins - 1)) == 0,
       "colour_bins must be a power of two in [2, 64]");
  need(colour_learning_rate >= 0 && colour_learning_rate <= 1,
       "colour_learning_rate must be in [0, 1]");
  need(inner_padding >= 0 && inner_padding < 1, "inner_padding must be in [0, 1)");
  need(merge_factor >= 0 && merge_factor <= 1, "merge_factor must be in [0, 1]");
  need(scales >= 1 && scales <= 99, "scales must be in [1, 99]");
  need(scale_step > 1, "scale_step must be > 1");
  need(scale_learning_rate >= 0 && scale_learning_rate <= 1,
       "scale_learning_rate must be in [0, 1]");
  need(scale_model_max_area >= 64, "scale_model_max_area must be >= 64");
  need(peak_ratio >= 0 && apce_ratio >= 0, "peak_ratio and apce_ratio must be >= 0");
  need(lost_after >= 1, "lost_after must be >= 1");
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "dreamsense tracker: {}", bad);
  return ok_status();
}

struct DcfTracker::State {
  cv::Size frame_size;
  int frame_type = -1;
  cv::Point2d pos;
  cv::Size2d base_target;
  double scale = 1, min_scale = 0.1, max_scale = 10;
  cv::Size2d window;  // image px at scale 1
  cv::Size norm;      // resampled window, px (multiple of the cell)
  cv::Size cells;
  cv::Size2d norm_target;
  cv::Mat hann2d, yf;
  std::vector<cv::Mat> num;
  cv::Mat den;
  // Colour model.
  int colour_shift = 3, colour_channels = 3;
  std::vector<float> fg, bg;
  // Scale filter.
  std::vector<double> scale_factors;
  std::vector<float> scale_window;
  cv::Mat ysf;  // 1 x S complex
  cv::Size scale_model;
  cv::Mat sf_num, sf_den;
  // Confidence.
  double sum_peak = 0, sum_apce = 0;
  int n_conf = 0, low_run = 0;
  bool lost = false;
  // Scratch.
  std::vector<cv::Mat> feat, xf;
  cv::Mat feat_storage, scale_rows, scale_cols, scale_patch;
};

DcfTracker::DcfTracker(DcfTrackerOptions options) : o_(options) {}
DcfTracker::~DcfTracker() = default;

namespace {

struct Response {
  cv::Mat map;             // merged response, centred layout (index h/2, w/2 = no displacement)
  cv::Point2d peak_cells;  // displacement of the peak, cells (subpixel)
  double peak = 0, apce = 0;
};

}  // namespace

namespace {
// Everything that needs the state lives in one helper class to keep the header small.
class DcfWork {
 public:
  DcfWork(const DcfTrackerOptions& o, DcfTracker::State& s) : o_(o), s_(s) {}

  void features(const cv::Mat& grey_patch) {
    compute_fhog(grey_patch, o_.cell_size, s_.feat, s_.feat_storage);
    s_.xf.resize(s_.feat.size());
    for (size_t c = 0; c < s_.feat.size(); ++c) {
      cv::multiply(s_.feat[c], s_.hann2d, s_.feat[c]);
      cv::dft(s_.feat[c], s_.xf[c], cv::DFT_COMPLEX_OUTPUT);
    }
  }

  void learn_translation(const cv::Mat& grey_patch, const cv::Mat& colour_patch, double rate,
                         double colour_rate) {
    features(grey_patch);
    const float inv_n = 1.f / static_cast<float>(s_.cells.area());
    cv::Mat den = cv::Mat::zeros(s_.cells, CV_32F);
    if (s_.num.size() != s_.xf.size()) s_.num.assign(s_.xf.size(), cv::Mat());
    for (size_t c = 0; c < s_.xf.size(); ++c) {
      cv::Mat n;
      cv::mulSpectrums(s_.xf[c], s_.yf, n, 0, true);  // X conj(Y)
      n *= inv_n;
      add_power(s_.xf[c], den);
      if (s_.num[c].empty() || rate >= 1)
        s_.num[c] = n;
      else
        cv::addWeighted(s_.num[c], 1 - rate, n, rate, 0, s_.num[c]);
    }
    den *= inv_n;
    if (s_.den.empty() || rate >= 1)
      s_.den = den;
    else
      cv::addWeighted(s_.den, 1 - rate, den, rate, 0, s_.den);
    learn_colour(colour_patch, colour_rate);
  }

  int colour_bin(const uchar* p) const {
    if (s_.colour_channels == 1) return p[0] >> s_.colour_shift;
    const int b = o_.colour_bins;
    return ((p[0] >> s_.colour_shift) * b + (p[1] >> s_.colour_shift)) * b +
           (p[2] >> s_.colour_shift);
  }

  cv::Rect target_rect(double shrink) const {
    const double pad = shrink * 0.5 * (s_.norm_target.width + s_.norm_target.height) * 0.5;
    const double w = std::max(2.0, s_.norm_target.width - 2 * pad);
    const double h = std::max(2.0, s_.norm_target.height - 2 * pad);
    return cv::Rect(static_cast<int>(std::lround(0.5 * (s_.norm.width - w))),
                    static_cast<int>(std::lround(0.5 * (s_.norm.height - h))),
                    static_cast<int>(std::lround(w)), static_cast<int>(std::lround(h))) &
           cv::Rect(0, 0, s_.norm.width, s_.norm.height);
  }

  void learn_colour(const cv::Mat& patch, double rate) {
    if (o_.merge_factor <= 0) return;
    const size_t bins = s_.fg.size();
    std::vector<float> fg(bins, 0.f), bg(bins, 0.f);
    const cv::Rect inner = target_rect(o_.inner_padding);
    const cv::Rect target = target_rect(0);
    float nf = 0, nb = 0;
    const int ch = patch.channels();
    for (int y = 0; y < patch.rows; ++y) {
      const uchar* p = patch.ptr<uchar>(y);
      for (int x = 0; x < patch.cols; ++x, p += ch) {
        const cv::Point q(x, y);
        if (inner.contains(q)) {
          fg[static_cast<size_t>(colour_bin(p))] += 1, nf += 1;
        } else if (!target.contains(q)) {
          bg[static_cast<size_t>(colour_bin(p))] += 1, nb += 1;
        }
      }
    }
    if (nf <= 0 || nb <= 0) return;
    for (size_t i = 0; i < bins; ++i) {
      fg[i] /= nf;
      bg[i] /= nb;
    }
    if (rate >= 1) {
      s_.fg = fg;
      s_.bg = bg;
      return;
    }
    const float r = static_cast<float>(rate);
    for (size_t i = 0; i < bins; ++i) {
      s_.fg[i] = (1 - r) * s_.fg[i] + r * fg[i];
      s_.bg[i] = (1 - r) * s_.bg[i] + r * bg[i];
    }
  }

  // Mean foreground likelihood over the target box for every displacement of the cell grid
  // (centred layout), Staple's colour response.
  cv::Mat colour_response(const cv::Mat& patch) const {
    cv::Mat like(patch.size(), CV_32F);
    const int ch = patch.channels();
    for (int y = 0; y < patch.rows; ++y) {
      const uchar* p = patch.ptr<uchar>(y);
      float* l = like.ptr<float>(y);
      for (int x = 0; x < patch.cols; ++x, p += ch) {
        const size_t b = static_cast<size_t>(colour_bin(p));
        const float f = s_.fg[b], g = s_.bg[b];
        l[x] = f + g > 0 ? f / (f + g) : 0.f;
      }
    }
    cv::Mat integral;
    cv::integral(like, integral, CV_64F);
    const int tw = std::max(1, static_cast<int>(std::lround(s_.norm_target.width)));
    const int th = std::max(1, static_cast<int>(std::lround(s_.norm_target.height)));
    const double area = static_cast<double>(tw) * th;
    cv::Mat out(s_.cells, CV_32F);
    const int hc = s_.cells.height, wc = s_.cells.width;
    for (int i = 0; i < hc; ++i)
      for (int j = 0; j < wc; ++j) {
        const double cx = 0.5 * s_.norm.width + (j - wc / 2) * o_.cell_size;
        const double cy = 0.5 * s_.norm.height + (i - hc / 2) * o_.cell_size;
        const int x0 = std::clamp(static_cast<int>(std::lround(cx - 0.5 * tw)), 0, patch.cols);
        const int y0 = std::clamp(static_cast<int>(std::lround(cy - 0.5 * th)), 0, patch.rows);
        const int x1 = std::clamp(static_cast<int>(std::lround(cx + 0.5 * tw)), 0, patch.cols);
        const int y1 = std::clamp(static_cast<int>(std::lround(cy + 0.5 * th)), 0, patch.rows);
        const double sum = integral.at<double>(y1, x1) - integral.at<double>(y0, x1) -
                           integral.at<double>(y1, x0) + integral.at<double>(y0, x0);
        out.at<float>(i, j) = static_cast<float>(sum / area);
      }
    return out;
  }

  Response respond(const cv::Mat& grey_patch, const cv::Mat& colour_patch) {
    features(grey_patch);
    cv::Mat acc = cv::Mat::zeros(s_.cells, CV_32FC2), t;
    for (size_t c = 0; c < s_.xf.size(); ++c) {
      cv::mulSpectrums(s_.xf[c], s_.num[c], t, 0, true);  // Z conj(A)
      acc += t;
    }
    divide_by_real(acc, s_.den, static_cast<float>(o_.lambda));
    cv::Mat circ;
    cv::idft(acc, circ, cv::DFT_SCALE | cv::DFT_REAL_OUTPUT);
    // fftshift: centred(i, j) = circ((i - h/2) mod h, (j - w/2) mod w).
    const int hc = s_.cells.height, wc = s_.cells.width;
    Response r;
    r.map.create(s_.cells, CV_32F);
    for (int i = 0; i < hc; ++i)
      for (int j = 0; j < wc; ++j)
        r.map.at<float>(i, j) = circ.at<float>((i - hc / 2 + hc) % hc, (j - wc / 2 + wc) % wc);
    if (o_.merge_factor > 0) {
      const float a = static_cast<float>(o_.merge_factor);
      r.map = (1 - a) * r.map + a * colour_response(colour_patch);
    }
    // Peak within the displacements that do not wrap around.
    double mn, mx;
    cv::Point at;
    const cv::Rect inner(1, 1, wc - 2, hc - 2);
    cv::minMaxLoc(r.map(inner), &mn, &mx, nullptr, &at);
    at += inner.tl();
    cv::minMaxLoc(r.map, &mn, nullptr);
    r.peak = mx;
    const cv::Scalar m = cv::mean((r.map - mn).mul(r.map - mn));
    r.apce = m[0] > 0 ? (mx - mn) * (mx - mn) / m[0] : 0;
    const double sx =
        parabola(r.map.at<float>(at.y, at.x - 1), mx, r.map.at<float>(at.y, at.x + 1));
    const double sy =
        parabola(r.map.at<float>(at.y - 1, at.x), mx, r.map.at<float>(at.y + 1, at.x));
    r.peak_cells = cv::Point2d(at.x - wc / 2 + sx, at.y - hc / 2 + sy);
    return r;
  }

  cv::Size2d window_px() const { return s_.window * s_.scale; }

  // The search window at `centre` (current scale) in the frame's colours, and its grey version.
  void window_at(const cv::Mat& frame, const cv::Point2d& centre, cv::Mat& colour,
                 cv::Mat& grey) const {
    colour = extract_window(frame, centre, window_px(), s_.norm);
    if (colour.channels() == 3)
      cv::cvtColor(colour, grey, cv::COLOR_BGR2GRAY);
    else
      grey = colour;
  }

  // Image px per cell at the current scale.
  cv::Point2d cell_to_image(const cv::Point2d& d) const {
    return {d.x * o_.cell_size * window_px().width / s_.norm.width,
            d.y * o_.cell_size * window_px().height / s_.norm.height};
  }

  // Fourier transforms (along the scale axis) of the scale samples at the current position and
  // scale. The region of the largest scale is resampled once (INTER_AREA) to the scale model's
  // resolution; every scale is then a linear resampling of that small image.
  cv::Mat scale_samples(const cv::Mat& frame) {
    const int S = static_cast<int>(s_.scale_factors.size());
    const double f_max = s_.scale_factors.front();
    const cv::Size2d target = s_.base_target * s_.scale;
    const cv::Size region_px(
        std::max(1, static_cast<int>(std::lround(s_.scale_model.width * f_max))),
        std::max(1, static_cast<int>(std::lround(s_.scale_model.height * f_max))));
    cv::Mat region = extract_window(frame, s_.pos, target * f_max, region_px);
    if (region.channels() == 3) cv::cvtColor(region, region, cv::COLOR_BGR2GRAY);
    const cv::Point2d c(0.5 * region.cols, 0.5 * region.rows);
    const cv::Size cells = fhog_cells(s_.scale_model, 4);
    const int dims = kFhogChannels * cells.area();
    s_.scale_rows.create(S, dims, CV_32F);
    for (int n = 0; n < S; ++n) {
      const double f = s_.scale_factors[static_cast<size_t>(n)];
      // Sub-pixel resampling: at this resolution an integer crop would quantise the scales.
      const double k = f / f_max * region.cols / (s_.scale_model.width * f_max) * f_max;
      const double ky = f / f_max * region.rows / (s_.scale_model.height * f_max) * f_max;
      const cv::Matx23d m(k, 0, c.x - 0.5 * s_.scale_model.width * k + 0.5 * k - 0.5,  //
                          0, ky, c.y - 0.5 * s_.scale_model.height * ky + 0.5 * ky - 0.5);
      cv::warpAffine(region, s_.scale_patch, m, s_.scale_model,
                     cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_REPLICATE);
      const cv::Mat& patch = s_.scale_patch;
      float* row = s_.scale_rows.ptr<float>(n);
      compute_fhog(patch, 4, row);
      const float wn = s_.scale_window[static_cast<size_t>(n)];
      for (int d = 0; d < dims; ++d) row[d] *= wn;
    }
    cv::transpose(s_.scale_rows, s_.scale_cols);
    cv::Mat f;
    cv::dft(s_.scale_cols, f, cv::DFT_ROWS | cv::DFT_COMPLEX_OUTPUT);
    return f;
  }

  void learn_scale(const cv::Mat& xsf, double rate) {
    if (s_.scale_factors.size() < 2) return;
    cv::Mat num(xsf.size(), CV_32FC2), den = cv::Mat::zeros(1, xsf.cols, CV_32F);
    const cv::Vec2f* y = s_.ysf.ptr<cv::Vec2f>(0);
    for (int r = 0; r < xsf.rows; ++r) {
      const cv::Vec2f* x = xsf.ptr<cv::Vec2f>(r);
      cv::Vec2f* o = num.ptr<cv::Vec2f>(r);
      float* d = den.ptr<float>(0);
      for (int c = 0; c < xsf.cols; ++c) {
        // Y conj(X)
        o[c] =
            cv::Vec2f(y[c][0] * x[c][0] + y[c][1] * x[c][1], y[c][1] * x[c][0] - y[c][0] * x[c][1]);
        d[c] += x[c][0] * x[c][0] + x[c][1] * x[c][1];
      }
    }
    if (s_.sf_num.empty() || rate >= 1) {
      s_.sf_num = num;
      s_.sf_den = den;
    } else {
      cv::addWeighted(s_.sf_num, 1 - rate, num, rate, 0, s_.sf_num);
      cv::addWeighted(s_.sf_den, 1 - rate, den, rate, 0, s_.sf_den);
    }
  }

  // Returns the index of the best scale (S/2 = unchanged).
  int estimate_scale(const cv::Mat& xsf) {
    if (s_.scale_factors.size() < 2) return 0;
    cv::Mat acc = cv::Mat::zeros(1, xsf.cols, CV_32FC2);
    cv::Vec2f* a = acc.ptr<cv::Vec2f>(0);
    for (int r = 0; r < xsf.rows; ++r) {
      const cv::Vec2f* x = xsf.ptr<cv::Vec2f>(r);
      const cv::Vec2f* n = s_.sf_num.ptr<cv::Vec2f>(r);
      for (int c = 0; c < xsf.cols; ++c)
        a[c] +=
            cv::Vec2f(n[c][0] * x[c][0] - n[c][1] * x[c][1], n[c][0] * x[c][1] + n[c][1] * x[c][0]);
    }
    divide_by_real(acc, s_.sf_den, static_cast<float>(o_.lambda));
    cv::Mat resp;
    cv::idft(acc, resp, cv::DFT_SCALE | cv::DFT_REAL_OUTPUT | cv::DFT_ROWS);
    cv::Point at;
    cv::minMaxLoc(resp, nullptr, nullptr, nullptr, &at);
    s_.scale = std::clamp(s_.scale * s_.scale_factors[static_cast<size_t>(at.x)], s_.min_scale,
                          s_.max_scale);
    return at.x;
  }

 private:
  const DcfTrackerOptions& o_;
  DcfTracker::State& s_;
};

}  // namespace

Status DcfTracker::init(const cv::Mat& frame, const cv::Rect2d& box) {
  if (auto s = o_.check(); !s) return s;
  if (auto s = check_init_box(frame, box); !s) return s;
  s_ = std::make_unique<State>();
  State& s = *s_;
  s.frame_size = frame.size();
  s.frame_type = frame.type();
  s.pos = box_centre(box);
  s.base_target = cv::Size2d(box.width, box.height);
  s.window = s.base_target * (1 + o_.padding);
  const double k = o_.template_side / std::sqrt(s.window.area());
  const int cell = o_.cell_size;
  // Cell counts with small prime factors only (fast DFTs), at least 8.
  s.cells = cv::Size(
      cv::getOptimalDFTSize(std::max(8, static_cast<int>(std::lround(s.window.width * k / cell)))),
      cv::getOptimalDFTSize(
          std::max(8, static_cast<int>(std::lround(s.window.height * k / cell)))));
  s.norm = s.cells * cell;
  s.norm_target = cv::Size2d(s.base_target.width * s.norm.width / s.window.width,
                             s.base_target.height * s.norm.height / s.window.height);
  // Hann window and the Gaussian label (peak at zero displacement, circular layout).
  s.hann2d = hann(s.cells.height).t() * hann(s.cells.width);
  const double sigma = std::sqrt(s.norm_target.area()) * o_.output_sigma_factor / cell;
  cv::Mat y(s.cells, CV_32F);
  for (int i = 0; i < s.cells.height; ++i)
    for (int j = 0; j < s.cells.width; ++j) {
      const int di = i < (s.cells.height + 1) / 2 ? i : i - s.cells.height;
      const int dj = j < (s.cells.width + 1) / 2 ? j : j - s.cells.width;
      y.at<float>(i, j) =
          static_cast<float>(std::exp(-0.5 * (di * di + dj * dj) / (sigma * sigma)));
    }
  cv::dft(y, s.yf, cv::DFT_COMPLEX_OUTPUT);
  // Colour model.
  s.colour_channels = frame.channels();
  s.colour_shift = 8 - static_cast<int>(std::lround(std::log2(o_.colour_bins)));
  size_t bins = 1;
  for (int c = 0; c < s.colour_channels; ++c) bins *= static_cast<size_t>(o_.colour_bins);
  s.fg.assign(bins, 0.f);
  s.bg.assign(bins, 0.f);
  // Scale filter.
  const int S = o_.scales;
  s.scale_factors.resize(static_cast<size_t>(S));
  s.scale_window.resize(static_cast<size_t>(S));
  cv::Mat ys(1, S, CV_32F);
  const double scale_sigma = std::sqrt(static_cast<double>(S)) * o_.scale_sigma_factor;
  for (int n = 0; n < S; ++n) {
    const int e = n - S / 2;
    s.scale_factors[static_cast<size_t>(n)] = std::pow(o_.scale_step, -e);
    const int ss = n - S / 2;
    ys.at<float>(n) = static_cast<float>(std::exp(-0.5 * ss * ss / (scale_sigma * scale_sigma)));
    s.scale_window[static_cast<size_t>(n)] =
        S > 1 ? static_cast<float>(0.5 * (1 - std::cos(2 * CV_PI * (n + 1) / (S + 1)))) : 1.f;
  }
  cv::dft(ys, s.ysf, cv::DFT_COMPLEX_OUTPUT | cv::DFT_ROWS);
  const double area = s.base_target.area();
  const double f = area > o_.scale_model_max_area ? std::sqrt(o_.scale_model_max_area / area) : 1.0;
  s.scale_model = cv::Size(std::max(8, static_cast<int>(s.base_target.width * f)),
                           std::max(8, static_cast<int>(s.base_target.height * f)));
  s.min_scale = std::min(1.0, 6.0 / std::min(s.base_target.width, s.base_target.height));
  s.max_scale =
      std::max(1.0, std::min(frame.cols / s.base_target.width, frame.rows / s.base_target.height));
  // First frame: the models are the first frame's.
  DcfWork w(o_, s);
  cv::Mat colour, grey;
  w.window_at(frame, s.pos, colour, grey);
  w.learn_translation(grey, colour, 1.0, 1.0);
  w.learn_scale(w.scale_samples(frame), 1.0);
  return ok_status();
}

Result<TrackerUpdate> DcfTracker::update(const cv::Mat& frame) {
  if (!s_)
    return make_error(ErrorCode::kFailedPrecondition, "dreamsense tracker: update() before init()");
  State& s = *s_;
  if (auto st = check_update_frame(frame, s.frame_size, s.frame_type); !st)
    return tl::unexpected(st.error());
  DcfWork w(o_, s);
  cv::Mat colour, grey;
  auto respond_at = [&](const cv::Point2d& centre) {
    w.window_at(frame, centre, colour, grey);
    return w.respond(grey, colour);
  };
  auto confident = [&](const Response& r) {
    if (s.n_conf == 0) return true;
    return r.peak >= o_.peak_ratio * s.sum_peak && r.apce >= o_.apce_ratio * s.sum_apce;
  };
  Response r = respond_at(s.pos);
  cv::Point2d centre = s.pos;
  if (s.lost && o_.redetect) {
    // Re-detection: the filter on a 3x3 grid of windows around the last position.
    const cv::Size2d win = w.window_px();
    for (int gy = -1; gy <= 1; ++gy)
      for (int gx = -1; gx <= 1; ++gx) {
        if (!gx && !gy) continue;
        const cv::Point2d c(s.pos.x + gx * 0.5 * win.width, s.pos.y + gy * 0.5 * win.height);
        Response q = respond_at(c);
        if (q.peak > r.peak) r = q, centre = c;
      }
  }
  const bool good = confident(r);
  const double mean_peak = s.n_conf ? s.sum_peak : r.peak;
  // Baselines: running averages of the recent confident frames (rate good_rate); low frames pull
  // them down slowly (low_rate), so a lasting change of appearance is eventually learnt.
  {
    const double a = s.n_conf == 0 ? 1.0 : good ? o_.baseline_rate : o_.baseline_low_rate;
    s.sum_peak = (1 - a) * s.sum_peak + a * r.peak;
    s.sum_apce = (1 - a) * s.sum_apce + a * r.apce;
    ++s.n_conf;
  }
  // The target goes where the response peaks (LMCF: only the learning is gated), except while
  // lost: then it stays where it was last seen until a confident peak reappears.
  if (good || !s.lost) {
    s.pos = centre + w.cell_to_image(r.peak_cells);
    s.pos.x = std::clamp(s.pos.x, 0.0, static_cast<double>(frame.cols - 1));
    s.pos.y = std::clamp(s.pos.y, 0.0, static_cast<double>(frame.rows - 1));
  }
  cv::Mat xsf;
  bool rescaled = false;
  if (good) {  // the scale only changes on confident frames (an occluder has its own size)
    xsf = w.scale_samples(frame);
    // The samples are re-taken for learning only when the scale changed (DSST re-samples at
    // the new scale; when it did not change they are the same samples).
    rescaled = w.estimate_scale(xsf) != o_.scales / 2;
  }
  if (good) {
    s.low_run = 0;
    s.lost = false;
    if (rescaled) xsf = w.scale_samples(frame);
    w.window_at(frame, s.pos, colour, grey);
    w.learn_translation(grey, colour, o_.learning_rate, o_.colour_learning_rate);
    w.learn_scale(xsf, o_.scale_learning_rate);
  } else if (++s.low_run >= o_.lost_after) {
    s.lost = true;
  }
  TrackerUpdate u;
  const cv::Size2d t = s.base_target * s.scale;
  u.box = cv::Rect2d(s.pos.x - 0.5 * t.width, s.pos.y - 0.5 * t.height, t.width, t.height);
  u.found = !s.lost;
  u.confidence = std::clamp(mean_peak > 0 ? r.peak / mean_peak : 0.0, 0.0, 1.0);
  return u;
}

}  // namespace dreamsense::objects
