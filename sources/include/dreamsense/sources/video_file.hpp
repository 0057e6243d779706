#pragma once
// A plain video file (.mp4, .avi, ... anything OpenCV's VideoCapture/FFmpeg opens) as a
// one-camera session made on the fly (docs/video_input.md): no re-encoding, no files written.
//
//   - one colour stream, id "camera", role child_camera, world = that camera's optical frame
//     (with a calibration file: the world of its extrinsics, identity when it has none);
//   - stamps: the container's presentation time of each frame (CAP_PROP_POS_MSEC after the
//     frame is decoded), as int64 ns from the first frame; never the wall clock. Variable frame
//     rates are kept as they are. A frame whose stamp does not increase (FFmpeg gives some frames,
//     often an AVI's last, no time) is placed one nominal period after the previous one, with a
//     warning; more than max(2, 1 % of the frames) such frames is an error naming the frame;
//   - intrinsics: the calibration file given, else the approximate rule used by OpenFace for
//     uncalibrated video: fx = fy = 500 * width / 640, cx = width / 2, cy = height / 2, no
//     distortion (a horizontal field of view of about 65 degrees). Flagged `approximate`.
//   - the sound track is not read (OpenCV's video reader gives no audio on Debian 12).

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/source.hpp"
#include "dreamsense/core/status.hpp"
#include "dreamsense/sources/session.hpp"

#include <filesystem>
#include <memory>
#include <string>

namespace dreamsense::sources {

inline constexpr const char* kVideoStreamId = "camera";

// True for the file extensions `analyze` treats as a video (any case): .mp4 .avi .mov .mkv .m4v
// .webm .mpg .mpeg .wmv .ogv .flv .3gp .ts .mts (the same list as `batch`).
bool has_video_extension(const std::filesystem::path& path);

// The approximate intrinsics of an uncalibrated camera with this image size (rule above).
CameraModel approximate_camera(int width, int height, const std::string& frame);

struct VideoFileOptions {
  // A CameraModel file (dreamsense calibrate intrinsics) replacing the approximate intrinsics;
  // its image size must match the video's.
  std::filesystem::path calibration;
};

// What the video is, read from its container and first frame.
struct VideoFileInfo {
  std::filesystem::path path;  // absolute
  int width = 0, height = 0;
  double nominal_fps = 0;   // the container's frame rate (0 when it does not say)
  int64_t frame_count = 0;  // the container's estimate (0 when it does not say)
  double duration_s = 0;    // frame_count / nominal_fps when both are known
  std::string codec;        // FourCC as text, e.g. "avc1", "MJPG"
  CameraModel camera;       // world = the camera's frame
  bool approximate_calibration = true;
  std::string audio;  // what happens to the sound track (one line)
  // The one-camera session: stream kVideoStreamId (encoding "video", file = the absolute path,
  // calibration = the absolute calibration path or empty), role child_camera, frame_rate =
  // nominal_fps (25 when unknown), metadata: source_video, calibration ("approximate" or the file),
  // robot_head_m = the camera's centre in world (mutual gaze = looking at the camera).
  SessionManifest manifest;
};

// Reads a video's frames in order with their container stamps.
class VideoFileSource : public Source {
 public:
  // Opens and checks the video: OpenCV must open it and decode its first frame, otherwise a
  // one-line error naming the file (missing, empty, not a video, no decodable frame).
  static Result<std::unique_ptr<VideoFileSource>> open(const std::filesystem::path& path,
                                                       const VideoFileOptions& options = {});
  ~VideoFileSource() override;
  // Frames in file order; a frame whose stamp is not after the previous one, or that cannot be
  // decoded before the container's announced end, is an error naming the file and frame.
  Result<FramePtr> next() override;
  SourceInfo info() const override;
  const VideoFileInfo& video() const;
  uint64_t frames_read() const;

 private:
  VideoFileSource();
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace dreamsense::sources
