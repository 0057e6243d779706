#include "synthetic_eyes.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

namespace dreamsense::eye_centers {
namespace {

// Uniform and normal variates from raw mt19937_64 outputs (the standard fixes the engine's
// sequence, not the distributions'), so a seed gives the same set on every platform.
class Rng {
 public:
  explicit Rng(uint64_t seed) : e_(seed) {}
  double uniform() { return static_cast<double>(e_() >> 11) * 0x1.0p-53; }
  double uniform(double a, double b) { return a + (b - a) * uniform(); }
  double normal() {
    const double u1 = std::max(uniform(), 1e-300), u2 = uniform();
    return std::sqrt(-2 * std::log(u1)) * std::cos(2 * std::numbers::pi * u2);
  }

 private:
  std::mt19937_64 e_;
};

uint64_t splitmix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

// The visible eye opening in the portrait: an almond between the image-left corner a and the
// image-right corner b, the upper lid `up` px and the lower lid `low` px from the corner line at
// its widest (hand-measured on astronaut.png, magnified; the lids just touch the iris).
struct Almond {
  cv::Point2d a, b;
  double up = 4.5, low = 3.0;
  // Eye frame: t in [0, 1] along a->b, h = signed distance from the corner line (+ = down).
  void frame(const cv::Point2d& p, double& t, double& h) const {
    const cv::Point2d d = b - a;
    const double len = std::hypot(d.x, d.y);
    const cv::Point2d u = d * (1 / len), v(-u.y, u.x);
    t = (p - a).dot(u) / len;
    h = (p - a).dot(v);
  }
  static double profile(double t) { return std::pow(std::sin(std::numbers::pi * t), 0.7); }
};
const Almond kRightAlmond{{192.5, 100.5}, {211.5, 102.5}};  // subject's right eye, image left
const Almond kLeftAlmond{{236.0, 103.5}, {256.5, 102.5}};   // subject's left eye, image right

double smoothstep(double e0, double e1, double x) {
  const double t = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
  return t * t * (3 - 2 * t);
}

// Head and shoulders of the portrait, feathered, in portrait pixels.
cv::Mat portrait_mask(cv::Size size) {
  cv::Mat m(size, CV_32F);
  auto inside = [](double x, double y, double cx, double cy, double ax, double ay) {
    const double r = std::hypot((x - cx) / ax, (y - cy) / ay);
    return smoothstep(1.0, 0.9, r);
  };
  for (int y = 0; y < size.height; ++y)
    for (int x = 0; x < size.width; ++x)
      m.at<float>(y, x) = static_cast<float>(
          std::max(inside(x, y, 226, 95, 82, 98), inside(x, y, 215, 420, 215, 270)));
  return m;
}

struct EyeLook {
  double iris_grey, pupil_grey, sclera_grey, pupil_ratio, phase1, phase2;
  double lid_droop;  // the upper lid's height as a fraction of the portrait's (< 1: lowered)
  double lash_grey;
  int spokes1, spokes2;
  bool glint;
};

// Repaints one eye opening of `img` (output pixels). `port_from_out` maps output -> portrait.
void paint_eye(cv::Mat& img, const Almond& almond, const cv::Matx23d& port_from_out,
               const cv::Matx23d& out_from_port, const cv::Point2d& iris_c, double r,
               const cv::Point2d& glint_dir, const EyeLook& look, double lid_grey) {
  auto map = [](const cv::Matx23d& m, const cv::Point2d& p) {
    return cv::Point2d(m(0, 0) * p.x + m(0, 1) * p.y + m(0, 2),
                       m(1, 0) * p.x + m(1, 1) * p.y + m(1, 2));
  };
  const cv::Point2d mid = 0.5 * (almond.a + almond.b);
  double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
  for (const cv::Point2d& p : {almond.a, almond.b, mid + cv::Point2d(0, -almond.up - 1),
                               mid + cv::Point2d(0, almond.low + 1)}) {
    const cv::Point2d q = map(out_from_port, p);
    x0 = std::min(x0, q.x), y0 = std::min(y0, q.y), x1 = std::max(x1, q.x), y1 = std::max(y1, q.y);
  }
  const int ix0 = std::max(0, static_cast<int>(std::floor(x0)) - 2);
  const int iy0 = std::max(0, static_cast<int>(std::floor(y0)) - 2);
  const int ix1 = std::min(img.cols - 1, static_cast<int>(std::ceil(x1)) + 2);
  const int iy1 = std::min(img.rows - 1, static_cast<int>(std::ceil(y1)) + 2);
  const double rp = look.pupil_ratio * r;
  const cv::Point2d glint_c = iris_c + glint_dir * (0.4 * r);
  constexpr int kSub = 4;
  for (int y = iy0; y <= iy1; ++y)
    for (int x = ix0; x <= ix1; ++x) {
      double inside = 0, value = 0;
      for (int sy = 0; sy < kSub; ++sy)
        for (int sx = 0; sx < kSub; ++sx) {
          const cv::Point2d q(x - 0.5 + (sx + 0.5) / kSub, y - 0.5 + (sy + 0.5) / kSub);
          double t, h;
          almond.frame(map(port_from_out, q), t, h);
          if (t <= 0 || t >= 1) continue;
          const double prof = Almond::profile(t);
          if (h <= -almond.up * prof || h >= almond.low * prof) continue;
          // A lowered upper lid covers the top of the opening (skin, lash line at its edge).
          const double lid = -almond.up * look.lid_droop * prof;
          // Shadow of the upper lid (portrait px below the lid edge), darker corners.
          const double below_lid = h - lid;
          const double shade = 1 - 0.3 * std::exp(-below_lid / 1.2);
          const cv::Point2d d = q - iris_c;
          const double rho = std::hypot(d.x, d.y);
          double v;
          if (below_lid <= 0) {
            v = below_lid > -0.8 ? look.lash_grey : lid_grey * (1 - 0.15 * std::exp(below_lid));
          } else if (cv::norm(q - glint_c) < 0.22 * r && look.glint) {
            v = 245;
          } else if (rho < rp) {
            v = look.pupil_grey;
          } else if (rho < r) {
            const double ang = std::atan2(d.y, d.x);
            const double tex = 1 + 0.12 * std::sin(look.spokes1 * ang + look.phase1) +
                               0.08 * (rho / r) * std::sin(look.spokes2 * ang + look.phase2);
            const double limbal = rho > 0.82 * r ? 0.75 : 1.0;
            v = look.iris_grey * tex * limbal * shade;
          } else {
            const double corner = 1 - 0.25 * std::pow(std::abs(2 * t - 1), 3);
            v = look.sclera_grey * corner * shade;
          }
          inside += 1;
          value += v;
        }
      if (inside == 0) continue;
      const double cov = inside / (kSub * kSub);
      float& px = img.at<float>(y, x);
      px = static_cast<float>(cov * (value / inside) + (1 - cov) * px);
    }
}

}  // namespace

Status SyntheticEyeSetOptions::check() const {
  auto bad = [](const char* what) {
    return make_error(ErrorCode::kInvalidArgument, "SyntheticEyeSetOptions: {}", what);
  };
  if (count < 1 || count > 100000) return bad("count must be in [1, 100000]");
  if (image_size.width < 64 || image_size.height < 64) return bad("image_size too small");
  if (!(min_interocular_px >= 20) || !(max_interocular_px >= min_interocular_px) ||
      max_interocular_px > 0.6 * image_size.width)
    return bad("need 20 <= min_interocular_px <= max_interocular_px <= 0.6 image width");
  if (!(max_roll_deg >= 0) || !(max_roll_deg <= 30)) return bad("max_roll_deg in [0, 30]");
  if (!(max_gaze_x >= 0) || !(max_gaze_x <= 0.3) || !(max_gaze_y >= 0) || !(max_gaze_y <= 0.15))
    return bad("max_gaze_x in [0, 0.3], max_gaze_y in [0, 0.15]");
  if (!(min_lid_droop >= 0.3) || !(min_lid_droop <= 1.05))
    return bad("min_lid_droop in [0.3, 1.05]");
  if (!(max_side_light >= 0) || !(max_side_light <= 0.8)) return bad("max_side_light in [0, 0.8]");
  if (!(min_blur_sigma >= 0) || !(max_blur_sigma >= min_blur_sigma) || !(min_noise_sd >= 0) ||
      !(max_noise_sd >= min_noise_sd) || !(min_gain > 0) || !(max_gain >= min_gain) ||
      !(max_offset >= 0))
    return bad("blur, noise, gain and offset ranges must be ordered and non-negative");
  return ok_status();
}

Result<SyntheticEyeRenderer> SyntheticEyeRenderer::create(const SyntheticEyeSetOptions& o) {
  if (auto s = o.check(); !s) return tl::unexpected(s.error());
  cv::Mat colour = cv::imread(o.portrait.string(), cv::IMREAD_COLOR);
  if (colour.empty())
    return make_error(ErrorCode::kNotFound,
                      "{}: cannot read the portrait (Debian package python3-skimage)",
                      o.portrait.string());
  cv::Mat grey;
  cv::cvtColor(colour, grey, cv::COLOR_BGR2GRAY);
  grey.convertTo(grey, CV_32F);
  cv::Mat mask = portrait_mask(grey.size());
  return SyntheticEyeRenderer(o, grey, mask);
}

SyntheticEyeImage SyntheticEyeRenderer::render(int index) const {
  const SyntheticEyeSetOptions& o = options_;
  Rng rng(splitmix64(o.seed * 0x100000001B3ULL + static_cast<uint64_t>(index)));
  const cv::Size size = o.image_size;

  // Geometry: scale from the inter-ocular distance, roll about the eye midpoint, placement.
  const cv::Point2d pr = o.portrait_right_eye_px, pl = o.portrait_left_eye_px;
  const cv::Point2d pm = 0.5 * (pr + pl);
  const double iod = rng.uniform(o.min_interocular_px, o.max_interocular_px);
  const double s = iod / cv::norm(pl - pr);
  const double roll = rng.uniform(-o.max_roll_deg, o.max_roll_deg) * std::numbers::pi / 180;
  const double mx = rng.uniform(0.35, 0.65) * size.width;
  const double my_hi = std::max(0.33 * size.height, size.height - 6 - 80 * s);
  const double my = rng.uniform(0.33 * size.height, std::min(0.5 * size.height, my_hi));
  const double c = std::cos(roll) * s, sn = std::sin(roll) * s;
  const cv::Matx23d out_from_port(c, -sn, mx - (c * pm.x - sn * pm.y), sn, c,
                                  my - (sn * pm.x + c * pm.y));
  cv::Matx23d port_from_out;
  cv::invertAffineTransform(out_from_port, port_from_out);

  // Background: grey level, gradient, blurred rectangles, low-frequency texture.
  cv::Mat bg(size, CV_32F);
  const double base = rng.uniform(50, 200), gx = rng.uniform(-0.2, 0.2),
               gy = rng.uniform(-0.2, 0.2);
  for (int y = 0; y < size.height; ++y)
    for (int x = 0; x < size.width; ++x)
      bg.at<float>(y, x) =
          static_cast<float>(base + gx * (x - size.width / 2.0) + gy * (y - size.height / 2.0));
  const int rects = 3 + static_cast<int>(rng.uniform() * 5);
  for (int i = 0; i < rects; ++i) {
    const cv::Point p0(static_cast<int>(rng.uniform(-50, size.width)),
                       static_cast<int>(rng.uniform(-50, size.height)));
    const cv::Size rs(static_cast<int>(rng.uniform(20, 160)),
                      static_cast<int>(rng.uniform(20, 160)));
    cv::rectangle(bg, cv::Rect(p0, rs), cv::Scalar(rng.uniform(30, 230)), cv::FILLED);
  }
  cv::Mat lowfreq(7, 9, CV_32F);
  for (int y = 0; y < lowfreq.rows; ++y)
    for (int x = 0; x < lowfreq.cols; ++x)
      lowfreq.at<float>(y, x) = static_cast<float>(rng.normal() * 12);
  cv::resize(lowfreq, lowfreq, size, 0, 0, cv::INTER_CUBIC);
  cv::GaussianBlur(bg, bg, cv::Size(), 2.0);
  bg += lowfreq;

  cv::Mat face, alpha;
  cv::warpAffine(portrait_, face, cv::Mat(out_from_port), size, cv::INTER_LINEAR,
                 cv::BORDER_CONSTANT, cv::Scalar(0));
  cv::warpAffine(mask_, alpha, cv::Mat(out_from_port), size, cv::INTER_LINEAR, cv::BORDER_CONSTANT,
                 cv::Scalar(0));
  cv::Mat img = alpha.mul(face) + (1 - alpha).mul(bg);

  // Eyes: same gaze offset for both (conjugate gaze), along the rolled eye axes.
  const cv::Point2d u(std::cos(roll), std::sin(roll)), v(-u.y, u.x);
  const double eye_w =
      0.5 * (cv::norm(kRightAlmond.b - kRightAlmond.a) + cv::norm(kLeftAlmond.b - kLeftAlmond.a)) *
      s;
  const cv::Point2d gaze = u * (rng.uniform(-o.max_gaze_x, o.max_gaze_x) * eye_w) +
                           v * (rng.uniform(-o.max_gaze_y, o.max_gaze_y) * eye_w);
  const double r = rng.uniform(0.088, 0.105) * iod;
  EyeLook look;
  look.iris_grey = rng.uniform(45, 120);
  look.pupil_grey = rng.uniform(8, 25);
  look.sclera_grey = rng.uniform(170, 230);
  look.pupil_ratio = rng.uniform(0.3, 0.5);
  look.phase1 = rng.uniform(0, 6.3);
  look.phase2 = rng.uniform(0, 6.3);
  look.spokes1 = 5 + static_cast<int>(rng.uniform() * 8);
  look.spokes2 = 11 + static_cast<int>(rng.uniform() * 10);
  look.glint = rng.uniform() < 0.8;
  look.lid_droop = rng.uniform(o.min_lid_droop, 1.05);
  look.lash_grey = rng.uniform(40, 90);
  const double ga = rng.uniform(0, 2 * std::numbers::pi);
  const cv::Point2d glint_dir(std::cos(ga), std::sin(ga));
  auto map = [&](const cv::Point2d& p) {
    return cv::Point2d(out_from_port(0, 0) * p.x + out_from_port(0, 1) * p.y + out_from_port(0, 2),
                       out_from_port(1, 0) * p.x + out_from_port(1, 1) * p.y + out_from_port(1, 2));
  };
  SyntheticEyeImage im;
  im.eyes.right_px = map(pr) + gaze;
  im.eyes.left_px = map(pl) + gaze;
  im.iris_radius_px = r;
  // Skin just above each eye in the portrait, for lowered lids.
  const double right_lid = cv::mean(portrait_(cv::Rect(197, 90, 12, 4)))[0];
  const double left_lid = cv::mean(portrait_(cv::Rect(240, 92, 12, 4)))[0];
  paint_eye(img, kRightAlmond, port_from_out, out_from_port, im.eyes.right_px, r, glint_dir, look,
            right_lid);
  paint_eye(img, kLeftAlmond, port_from_out, out_from_port, im.eyes.left_px, r, glint_dir, look,
            left_lid);

  // Side lighting: a ramp across the face (one eye darker than the other).
  const double ramp = rng.uniform(-o.max_side_light, o.max_side_light);
  for (int y = 0; y < img.rows; ++y)
    for (int x = 0; x < img.cols; ++x) {
      const double along = ((x - mx) * u.x + (y - my) * u.y) / iod;
      img.at<float>(y, x) *= static_cast<float>(std::clamp(1 + ramp * along, 0.3, 1.7));
    }

  // Photometry: gain/offset, optics blur, sensor noise, 8-bit quantisation.
  const double gain = rng.uniform(o.min_gain, o.max_gain);
  const double offset = rng.uniform(-o.max_offset, o.max_offset);
  img = img * gain + offset;
  const double blur = rng.uniform(o.min_blur_sigma, o.max_blur_sigma);
  if (blur > 0.05) cv::GaussianBlur(img, img, cv::Size(), blur);
  const double noise = rng.uniform(o.min_noise_sd, o.max_noise_sd);
  for (int y = 0; y < img.rows; ++y)
    for (int x = 0; x < img.cols; ++x)
      img.at<float>(y, x) += static_cast<float>(noise * rng.normal());
  img.convertTo(im.grey, CV_8U);  // rounds and saturates
  im.id = fmt::format("BioID_{:04d}", index);
  return im;
}

Status write_synthetic_eye_set(const SyntheticEyeSetOptions& options,
                               const std::filesystem::path& dir,
                               const std::function<void(double)>& progress) {
  auto renderer = SyntheticEyeRenderer::create(options);
  if (!renderer) return tl::unexpected(renderer.error());
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return make_error(ErrorCode::kIoError, "{}: {}", dir.string(), ec.message());
  for (int i = 0; i < options.count; ++i) {
    const SyntheticEyeImage im = renderer->render(i);
    const std::filesystem::path pgm = dir / (im.id + ".pgm");
    if (!cv::imwrite(pgm.string(), im.grey))
      return make_error(ErrorCode::kIoError, "{}: cannot write", pgm.string());
    if (auto s = write_bioid_eye_file(dir / (im.id + ".eye"), im.eyes); !s) return s;
    if (progress) progress(static_cast<double>(i + 1) / options.count);
  }
  return ok_status();
}

}  // namespace dreamsense::eye_centers
