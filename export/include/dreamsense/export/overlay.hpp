#pragma once
// overlay.mp4: the analysis drawn on the camera images, one video frame per tick.
//
// Per tick (OverlayWriter::add), on a copy of the shown camera's frame scaled to the output size
// (letterboxed when cameras differ in aspect ratio), it draws what the blackboard holds for that
// tick (entries stamped with another tick are ignored; a missing key is simply not drawn):
//  - every face box of that camera (keys::kFaceDetections) with its score; the selected face
//    (keys::kSelectedCamera) thicker and in another colour;
//  - the shown camera's name and DREAM SelectCameraID (0 middle, 1 left, 2 right, -1 other),
//    and which camera is selected;
//  - the 68 landmarks (keys::kFaceLandmarks) when they belong to that camera;
//  - head axes (keys::kHeadPose): the head frame's x/y/z axes, head_axis_length_m long, projected
//    with the camera model (x red, y green, z blue; z points to the back of the head);
//  - the eye centres (keys::kEyeCenters) of that camera;
//  - the gaze rays (keys::kEyeGaze): origin to origin + gaze_length_m * direction, projected, for
//    the right and left eye (thin) and both eyes (thick);
//  - mutual gaze (keys::kMutualGaze): a green "MUTUAL 1.2 s" box, grey "no mutual gaze", or grey
//    "no gaze" when the key is absent;
//  - the child's skeleton (keys::kChildBody, world joints projected with the camera model);
//  - the sound direction (keys::kSoundDirection, up to 0.5 s old: azimuth, left/right), the
//    current gesture (keys::kChildAction, when one is recognised) and the last utterance as a
//    subtitle for 3 s (keys::kRecognizedSpeech, with the speaker of keys::kSpeakerIdentity);
//  - a legend of the colours (bottom right), a yellow frame around the selected camera's picture;
//  - the tick time (session clock, seconds) and tick index.
// Which camera: options.camera = "selected" follows keys::kSelectedCamera (the picture switches
// camera with it; while no camera is selected the last one shown stays, and before any selection
// camera_middle or else the first colour stream of the tick is shown), or a fixed stream id.
// A tick without a frame of the shown camera repeats the last picture (ticks before the first
// picture repeat the first one), so the video has exactly one frame per tick.
// Head axes and gaze rays need the camera's model (options.cameras); without one they are not
// drawn. Nothing here throws on missing data.
//
// With options.mosaic every colour camera of the first tick that has one is shown, tiled (the
// others keep their last picture while one has no frame), instead of one camera.
// The file is encoded with cv::VideoWriter (FFmpeg backend) as H.264 ('avc1', libx264 through
// Debian's FFmpeg) in .mp4, which browsers play; when that encoder is missing it falls back to
// MPEG-4 Part 2 ('mp4v') with a warning (codec() says which),
// written as "<stem>.partial<ext>" next to the final path (FFmpeg picks the container from the
// extension, so the extension stays last) and renamed by commit(); on failure or without
// commit() nothing is left under the final name.

#include "dreamsense/core/blackboard.hpp"
#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/multi_frame.hpp"
#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace dreamsense::exporters {

struct OverlayOptions {
  std::string camera = "selected";  // "selected" or a colour stream id
  int width_px = 960;               // output width; height from the first picture's aspect (even)
  double fps = 25;                  // the session's frame (tick) rate
  std::string fourcc = "avc1";      // H.264; "mp4v", or "MJPG" with an .avi path, also work
  bool mosaic = false;              // every colour camera tiled instead of one
  bool legend = true;               // colour key, bottom right
  bool skeleton = true;             // the child's skeleton
  bool sound_direction = true;      // azimuth of the last voice
  bool subtitles = true;            // last utterance and speaker, for subtitle_s
  bool gesture = true;              // the recognised gesture
  double subtitle_s = 3.0;
  std::map<SensorId, CameraModel> cameras;  // for head axes and gaze rays (world -> pixels)
  double head_axis_length_m = 0.08;
  double gaze_length_m = 0.3;
  // Privacy (`--blur-faces`, docs/outputs.md "Names and faces"): pixelate every face region of
  // the shown camera (face_regions_px) before anything is drawn on it.
  bool blur_faces = false;
  Status check() const;
};

// The face regions of `camera` for the tick at `tick`, in pixels of an image of `shown` size (the
// camera's frame, possibly scaled): every face box (keys::kFaceDetections), the landmarks' bounding
// box (keys::kFaceLandmarks) and, projected with `model` when given, every face track
// (keys::kFaceTracks: a 0.24 m square around the predicted head centre, so a face the detector
// misses in this frame is still covered). Entries up to 1 s older than the tick are used (a
// region a little stale is better than a face shown); each region is enlarged by 25 % on every
// side (hair, chin) and clipped to the image.
std::vector<cv::Rect> face_regions_px(const SensorId& camera, Timestamp tick,
                                      const BlackboardView& view, const CameraModel* model,
                                      cv::Size shown);
// Pixelates `regions` of `image` in place (at most 8 cells across the larger side, then a
// Gaussian blur over the cells), so that no face can be recognised; pixels outside the regions
// are unchanged.
void blur_regions(cv::Mat& image, const std::vector<cv::Rect>& regions);

// Colours used (BGR), e.g. to find them in a decoded frame.
namespace overlay_colors {
inline const cv::Scalar kFaceBox{255, 200, 0};          // light blue
inline const cv::Scalar kSelectedFaceBox{0, 230, 255};  // yellow
inline const cv::Scalar kLandmark{255, 255, 255};
inline const cv::Scalar kEyeCenter{255, 0, 255};  // magenta
inline const cv::Scalar kGaze{0, 140, 255};       // orange
inline const cv::Scalar kMutual{0, 190, 0};       // green
inline const cv::Scalar kNoMutual{110, 110, 110};
inline const cv::Scalar kSkeleton{255, 120, 200};  // violet
}  // namespace overlay_colors

// Draws the overlay of `camera`'s `image` for one tick into a picture of `out_size` (the image
// scaled to fit, letterboxed). Never fails: missing entries are not drawn.
cv::Mat draw_overlay(const cv::Mat& image, const SensorId& camera, const MultiFrame& tick,
                     const BlackboardView& view, const OverlayOptions& options, cv::Size out_size);

class OverlayWriter {
 public:
  OverlayWriter();
  ~OverlayWriter();  // abandons an uncommitted video
  OverlayWriter(const OverlayWriter&) = delete;
  OverlayWriter& operator=(const OverlayWriter&) = delete;

  // Checks the options and that the folder is writable; the encoder starts at the first picture
  // (its size is needed). An existing file at `path` is removed.
  Status open(const std::filesystem::path& path, const OverlayOptions& options = {});
  // One video frame for this tick (the blackboard after the tick's analysers ran).
  Status add(const MultiFrame& tick, const BlackboardView& view);
  // Finishes the file and renames it to the final path. An error when no picture was ever
  // available (no frame of the shown camera in any tick): then no file is left.
  Status commit();
  void abandon();
  bool is_open() const;
  int64_t frames_written() const;
  cv::Size frame_size() const;  // empty until the first picture
  std::string codec() const;    // the fourcc really used ("avc1", or "mp4v" after a fallback)
  const std::filesystem::path& path() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace dreamsense::exporters
