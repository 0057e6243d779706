// The tracker factory, shared checks and OpenCV's trackers behind the project's interface.

#include "dreamsense/objects/tracker.hpp"

#include "dreamsense/objects/compressive_tracker.hpp"
#include "dreamsense/objects/dcf_tracker.hpp"

#include <opencv2/tracking.hpp>
#include <opencv2/tracking/tracking_legacy.hpp>
#include <opencv2/video/tracking.hpp>

#include <cmath>

namespace dreamsense::objects {
namespace {

// OpenCV 4.6 trackers of the current API (cv::Tracker: KCF, CSRT in contrib `tracking`, MIL in
// `video`) or of the legacy API (cv::legacy: MOSSE and MedianFlow exist only there).
class OpenCvTracker : public Tracker {
 public:
  OpenCvTracker(std::string name, cv::Ptr<cv::Tracker> t) : name_(std::move(name)), t_(t) {}
  OpenCvTracker(std::string name, cv::Ptr<cv::legacy::Tracker> t)
      : name_(std::move(name)), legacy_(t) {}
  std::string_view name() const override { return name_; }

  Status init(const cv::Mat& frame, const cv::Rect2d& box) override {
    if (auto s = check_init_box(frame, box); !s) return s;
    size_ = frame.size();
    type_ = frame.type();
    last_ = box;
    try {
      if (t_) {
        t_->init(frame, cv::Rect(box));
      } else if (!legacy_->init(frame, box)) {
        return make_error(ErrorCode::kInvalidArgument, "{}: OpenCV refused the initial box", name_);
      }
    } catch (const cv::Exception& e) {
      return make_error(ErrorCode::kInvalidArgument, "{}: OpenCV init failed: {}", name_, e.what());
    }
    initialised_ = true;
    return ok_status();
  }

  Result<TrackerUpdate> update(const cv::Mat& frame) override {
    if (!initialised_)
      return make_error(ErrorCode::kFailedPrecondition, "{}: update() before init()", name_);
    if (auto s = check_update_frame(frame, size_, type_); !s) return tl::unexpected(s.error());
    TrackerUpdate u;
    try {
      if (t_) {
        cv::Rect r;
        u.found = t_->update(frame, r);
        if (u.found) last_ = r;
      } else {
        cv::Rect2d r;
        u.found = legacy_->update(frame, r);
        if (u.found) last_ = r;
      }
    } catch (const cv::Exception& e) {
      // OpenCV's trackers throw when the box drifts out of the frame: report the target lost.
      u.found = false;
    }
    u.box = last_;
    u.confidence = u.found ? 1.0 : 0.0;
    return u;
  }

 private:
  std::string name_;
  cv::Ptr<cv::Tracker> t_;
  cv::Ptr<cv::legacy::Tracker> legacy_;
  cv::Size size_;
  int type_ = -1;
  cv::Rect2d last_;
  bool initialised_ = false;
};

}  // namespace

const std::vector<std::string>& tracker_names() {
  static const std::vector<std::string> names = {"ct",  "dreamsense", "kcf",       "csrt",
                                                 "mil", "mosse",      "medianflow"};
  return names;
}

Result<std::unique_ptr<Tracker>> make_tracker(std::string_view name) {
  if (name == "ct") return std::make_unique<CompressiveTracker>();
  if (name == "dreamsense") return std::make_unique<DcfTracker>();
  if (name == "kcf")
    return std::make_unique<OpenCvTracker>("kcf", cv::Ptr<cv::Tracker>(cv::TrackerKCF::create()));
  if (name == "csrt")
    return std::make_unique<OpenCvTracker>("csrt", cv::Ptr<cv::Tracker>(cv::TrackerCSRT::create()));
  if (name == "mil")
    return std::make_unique<OpenCvTracker>("mil", cv::Ptr<cv::Tracker>(cv::TrackerMIL::create()));
  if (name == "mosse")
    return std::make_unique<OpenCvTracker>(
        "mosse", cv::Ptr<cv::legacy::Tracker>(cv::legacy::TrackerMOSSE::create()));
  if (name == "medianflow")
    return std::make_unique<OpenCvTracker>(
        "medianflow", cv::Ptr<cv::legacy::Tracker>(cv::legacy::TrackerMedianFlow::create()));
  std::string known;
  for (const auto& n : tracker_names()) known += (known.empty() ? "" : ", ") + n;
  return make_error(ErrorCode::kInvalidArgument, "unknown tracker '{}' (known: {})", name, known);
}

Status check_init_box(const cv::Mat& frame, const cv::Rect2d& box) {
  if (frame.empty()) return make_error(ErrorCode::kInvalidArgument, "tracker init: empty frame");
  if (frame.depth() != CV_8U || (frame.channels() != 1 && frame.channels() != 3))
    return make_error(ErrorCode::kInvalidArgument,
                      "tracker init: frame must be 8-bit grey or BGR (got type {})", frame.type());
  if (!std::isfinite(box.x) || !std::isfinite(box.y) || !std::isfinite(box.width) ||
      !std::isfinite(box.height))
    return make_error(ErrorCode::kInvalidArgument, "tracker init: box has non-finite values");
  if (box.width < 2 || box.height < 2)
    return make_error(ErrorCode::kInvalidArgument,
                      "tracker init: empty box ({}x{} px; need at least 2x2)", box.width,
                      box.height);
  const cv::Rect2d inside = box & cv::Rect2d(0, 0, frame.cols, frame.rows);
  if (inside.area() < 0.5 * box.area())
    return make_error(ErrorCode::kInvalidArgument,
                      "tracker init: box ({:.1f}, {:.1f}, {:.1f}x{:.1f}) lies mostly outside the "
                      "{}x{} frame",
                      box.x, box.y, box.width, box.height, frame.cols, frame.rows);
  return ok_status();
}

Status check_update_frame(const cv::Mat& frame, const cv::Size& init_size, int init_type) {
  if (frame.empty()) return make_error(ErrorCode::kInvalidArgument, "tracker update: empty frame");
  if (frame.size() != init_size || frame.type() != init_type)
    return make_error(ErrorCode::kInvalidArgument,
                      "tracker update: frame {}x{} type {} differs from the initial {}x{} type {}",
                      frame.cols, frame.rows, frame.type(), init_size.width, init_size.height,
                      init_type);
  return ok_status();
}

double iou(const cv::Rect2d& a, const cv::Rect2d& b) {
  if (a.width <= 0 || a.height <= 0 || b.width <= 0 || b.height <= 0) return 0;
  const double inter = (a & b).area();
  const double uni = a.area() + b.area() - inter;
  return uni > 0 ? inter / uni : 0;
}

}  // namespace dreamsense::objects
