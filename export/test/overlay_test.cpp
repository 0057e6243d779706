// overlay.mp4: synthetic frames and blackboard entries are drawn, encoded, decoded again and
// checked (frame count, size, colours where the drawing should be), plus the partial-file rule.

#include "dreamsense/export/overlay.hpp"

#include "dreamsense/perception/actions.hpp"
#include "dreamsense/perception/body.hpp"
#include "dreamsense/perception/eye_centers.hpp"
#include "dreamsense/perception/face_detection.hpp"
#include "dreamsense/perception/face_landmarks.hpp"
#include "dreamsense/perception/face_tracks.hpp"
#include "dreamsense/perception/gaze.hpp"
#include "dreamsense/perception/head_pose.hpp"
#include "dreamsense/perception/sound_direction.hpp"
#include "dreamsense/perception/speech.hpp"
#include "dreamsense/perception/voice_id.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <chrono>
#include <fstream>
#include <iterator>
#include <random>
#include <unistd.h>

namespace dreamsense::exporters {
namespace {
namespace fs = std::filesystem;

fs::path temp_dir(const std::string& name) {
  auto d = fs::temp_directory_path() / ("ds_overlay_" + name + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

CameraModel middle_model() {
  CameraModel c;
  c.frame = "camera_middle";
  c.image_size = {1280, 960};
  c.K = cv::Matx33d(1100, 0, 640, 0, 1100, 480, 0, 0, 1);
  return c;  // at the world origin, looking along +z
}

// A textured grey 1280x960 image (so that the encoder has something realistic to do).
cv::Mat scene(int seed, cv::Size size = {1280, 960}, cv::Scalar base = {70, 70, 70}) {
  cv::Mat img(size, CV_8UC3, base);
  std::mt19937 rng(static_cast<unsigned>(seed));
  std::uniform_int_distribution<int> x(0, size.width), y(0, size.height), c(30, 120);
  for (int i = 0; i < 40; ++i)
    cv::circle(img, {x(rng), y(rng)}, 10 + c(rng) / 4, cv::Scalar::all(c(rng)), cv::FILLED);
  return img;
}

MultiFrame tick_with(int i, const std::map<SensorId, cv::Mat>& images) {
  MultiFrame mf;
  mf.tick = static_cast<uint64_t>(i);
  mf.stamp = Timestamp::from_seconds(i / 25.0);
  for (const auto& [id, img] : images)
    mf.frames[id] = make_frame(id, mf.stamp, static_cast<uint64_t>(i), ColorImage{img});
  return mf;
}

const cv::Rect2d kBox(400, 300, 200, 200);  // camera_middle pixels (1280x960)

// Every analyser key for a face 1 m in front of camera_middle, looking at it.
void write_all(Blackboard& bb, Timestamp t, bool mutual, bool selected_middle = true) {
  BlackboardWriter w("test");
  FaceDetections det;
  det.cameras["camera_middle"] = CameraFaces{t, 0, {1280, 960}, {DetectedFace{kBox, 0.93f}}};
  det.cameras["camera_left"] =
      CameraFaces{t, 0, {640, 360}, {DetectedFace{cv::Rect2d(200, 100, 80, 80), 0.6f}}};
  w.set(keys::kFaceDetections, det, t, 0.93f);
  SelectedCamera sel;
  sel.camera = selected_middle ? "camera_middle" : "camera_left";
  sel.face =
      selected_middle ? det.cameras["camera_middle"].faces[0] : det.cameras["camera_left"].faces[0];
  w.set(keys::kSelectedCamera, sel, t, 0.9f);
  FaceLandmarks lm;
  lm.camera = "camera_middle";
  lm.image_size = {1280, 960};
  for (int k = 0; k < kFaceLandmarkCount; ++k)
    lm.points_px.push_back({420 + 2.5 * k, 400 + 40 * std::sin(k * 0.3)});
  w.set(keys::kFaceLandmarks, lm, t, 0.9f);
  HeadPose head;
  head.camera = "camera_middle";
  head.position_world_m = {-0.03, -0.02, 1.0};
  head.world_from_head = rotation_from_ypr_deg(20, 10, 0);
  w.set(keys::kHeadPose, head, t, 0.9f);
  EyeCenters eyes;
  eyes.camera = "camera_middle";
  eyes.right = {true, {470, 380}, 0.9};
  eyes.left = {true, {530, 380}, 0.9};
  w.set(keys::kEyeCenters, eyes, t, 0.9f);
  EyeGaze gaze;
  gaze.camera = "camera_middle";
  gaze.both.valid = true;
  gaze.both.origin_world_m = {-0.03, -0.02, 1.0};
  gaze.both.direction_world = cv::normalize(cv::Vec3d(0.6, 0.3, -1));
  w.set(keys::kEyeGaze, gaze, t, 0.9f);
  MutualGaze mg;
  mg.mutual = mutual;
  mg.held_s = mutual ? 1.2 : 0;
  w.set(keys::kMutualGaze, mg, t, 0.9f);
  bb.commit(w, t);
}

double colour_distance(const cv::Vec3b& a, const cv::Scalar& b) {
  return std::sqrt(std::pow(a[0] - b[0], 2) + std::pow(a[1] - b[1], 2) + std::pow(a[2] - b[2], 2));
}

// Smallest distance to `colour` among the pixels of `img` inside `r`.
double best_match(const cv::Mat& img, cv::Rect r, const cv::Scalar& colour) {
  r &= cv::Rect(0, 0, img.cols, img.rows);
  double best = 1e9;
  for (int y = r.y; y < r.y + r.height; ++y)
    for (int x = r.x; x < r.x + r.width; ++x)
      best = std::min(best, colour_distance(img.at<cv::Vec3b>(y, x), colour));
  return best;
}

std::vector<cv::Mat> read_video(const fs::path& p, double* reported_count = nullptr) {
  cv::VideoCapture cap(p.string(), cv::CAP_FFMPEG);
  EXPECT_TRUE(cap.isOpened()) << p;
  if (reported_count) *reported_count = cap.get(cv::CAP_PROP_FRAME_COUNT);
  std::vector<cv::Mat> frames;
  cv::Mat f;
  while (cap.read(f)) frames.push_back(f.clone());
  return frames;
}

TEST(DrawOverlay, DrawsEachElementWhereExpected) {
  OverlayOptions o;
  o.cameras["camera_middle"] = middle_model();
  Blackboard bb;
  const MultiFrame mf = tick_with(3, {{"camera_middle", scene(1)}});
  write_all(bb, mf.stamp, /*mutual=*/true);
  const cv::Mat pic = draw_overlay(scene(1), "camera_middle", mf, bb.snapshot(), o, {960, 720});
  ASSERT_EQ(pic.size(), cv::Size(960, 720));
  // Selected face box: image (400, 300)-(600, 500) * 0.75 -> right edge x = 450, y 225..375.
  EXPECT_LT(best_match(pic, {448, 300, 5, 5}, overlay_colors::kSelectedFaceBox), 1);
  // Eye centre circle (anti-aliased) around (470, 380) * 0.75 = (352, 285), radius >= 3.
  EXPECT_LT(best_match(pic, {345, 278, 15, 15}, overlay_colors::kEyeCenter), 40);
  // Gaze ray: middle of the projected segment.
  const CameraModel cam = middle_model();
  const cv::Vec3d o3(-0.03, -0.02, 1.0), d = cv::normalize(cv::Vec3d(0.6, 0.3, -1));
  const cv::Point2d mid = (*cam.project(o3) + *cam.project(o3 + d * 0.3)) * 0.5 * 0.75;
  EXPECT_LT(best_match(pic, cv::Rect(cv::Point(mid) - cv::Point(3, 3), cv::Size(7, 7)),
                       overlay_colors::kGaze),
            40);
  // Head x axis (red): middle of the projected 8 cm segment.
  const cv::Vec3d x_end = o3 + rotation_from_ypr_deg(20, 10, 0) * cv::Vec3d(0.08, 0, 0);
  const cv::Point2d x_mid = (*cam.project(o3) + *cam.project(x_end)) * 0.5 * 0.75;
  EXPECT_LT(best_match(pic, cv::Rect(cv::Point(x_mid) - cv::Point(3, 3), cv::Size(7, 7)),
                       cv::Scalar(0, 0, 255)),
            40);
  // Mutual gaze box at the bottom left.
  EXPECT_LT(best_match(pic, {0, 680, 200, 40}, overlay_colors::kMutual), 1);
  // Landmarks are white dots near (420, 400) * 0.75.
  EXPECT_LT(best_match(pic, {310, 295, 10, 10}, overlay_colors::kLandmark), 1);

  // Entries of another tick are not drawn (only the picture, header and "no gaze").
  const MultiFrame later = tick_with(4, {{"camera_middle", scene(1)}});
  const cv::Mat bare = draw_overlay(scene(1), "camera_middle", later, bb.snapshot(), o, {960, 720});
  EXPECT_GT(best_match(bare, {440, 230, 20, 140}, overlay_colors::kSelectedFaceBox), 60);
  EXPECT_GT(best_match(bare, {0, 680, 200, 40}, overlay_colors::kMutual), 60);
}

TEST(DrawOverlay, MissingOrOddDataNeverCrashes) {
  OverlayOptions o;  // no camera models: no axes, no rays
  Blackboard bb;
  const MultiFrame mf = tick_with(1, {{"camera_middle", scene(2)}});
  {
    BlackboardWriter w("odd");
    FaceLandmarks lm;
    lm.camera = "camera_middle";
    lm.points_px.assign(68, {NAN, NAN});  // NaNs
    w.set(keys::kFaceLandmarks, lm, mf.stamp, 0.5f);
    HeadPose head;
    head.position_world_m = {0, 0, -1};  // behind the camera
    w.set(keys::kHeadPose, head, mf.stamp, 0.5f);
    w.set_absent(keys::kFaceDetections, mf.stamp);
    w.set_absent(keys::kMutualGaze, mf.stamp);
    bb.commit(w, mf.stamp);
  }
  for (const cv::Mat& img : {scene(2), cv::Mat(), cv::Mat(480, 640, CV_8UC1, cv::Scalar(9)),
                             cv::Mat(480, 640, CV_16UC1, cv::Scalar(9))}) {
    const cv::Mat pic = draw_overlay(img, "camera_middle", mf, bb.snapshot(), o, {960, 720});
    EXPECT_EQ(pic.size(), cv::Size(960, 720));
  }
  o.cameras["camera_middle"] = middle_model();
  EXPECT_EQ(draw_overlay(scene(2), "camera_middle", mf, bb.snapshot(), o, {960, 720}).type(),
            CV_8UC3);
}

TEST(OverlayWriter, OneFramePerTickBoxVisibleAfterDecoding) {
  const auto dir = temp_dir("video");
  OverlayOptions o;
  o.cameras["camera_middle"] = middle_model();
  OverlayWriter w;
  ASSERT_TRUE(w.open(dir / "overlay.mp4", o));
  Blackboard bb;
  const int ticks = 30;
  for (int i = 0; i < ticks; ++i) {
    // Ticks 10-12 lack the camera frame (repeat the last picture); from 20 on, no analysis.
    std::map<SensorId, cv::Mat> images;
    if (i < 10 || i > 12) images["camera_middle"] = scene(i);
    const MultiFrame mf = tick_with(i, images);
    if (i < 20 && !images.empty()) write_all(bb, mf.stamp, i % 2 == 0);
    ASSERT_TRUE(w.add(mf, bb.snapshot()));
    EXPECT_FALSE(fs::exists(dir / "overlay.mp4")) << "nothing under the final name before commit";
  }
  EXPECT_EQ(w.frames_written(), ticks);
  EXPECT_EQ(w.frame_size(), cv::Size(960, 720));
  ASSERT_TRUE(w.commit());
  EXPECT_TRUE(fs::exists(dir / "overlay.mp4"));
  EXPECT_FALSE(fs::exists(dir / "overlay.partial.mp4"));

  double reported = 0;
  const auto frames = read_video(dir / "overlay.mp4", &reported);
  ASSERT_EQ(static_cast<int>(frames.size()), ticks);
  EXPECT_EQ(static_cast<int>(reported), ticks);
  ASSERT_EQ(frames[0].size(), cv::Size(960, 720));
  // The selected face box's right edge (x = 450, y 225..375, 3 px wide) after H.264 coding.
  const cv::Rect edge(446, 260, 9, 80);
  for (int i : {0, 5, 11, 19})
    EXPECT_LT(best_match(frames[static_cast<size_t>(i)], edge, overlay_colors::kSelectedFaceBox),
              50)
        << "frame " << i;
  // No analysis from tick 20: no box there.
  EXPECT_GT(best_match(frames[25], edge, overlay_colors::kSelectedFaceBox), 80);
  // Ticks 10-12 repeat tick 9's picture.
  EXPECT_LT(cv::norm(frames[11], frames[9], cv::NORM_L1) / frames[9].total(), 3.0);
  fs::remove_all(dir);
}

TEST(OverlayWriter, SwitchesCameraWithTheSelectionAndLetterboxes) {
  const auto dir = temp_dir("switch");
  OverlayWriter w;
  ASSERT_TRUE(w.open(dir / "overlay.mp4"));
  Blackboard bb;
  // camera_middle 4:3 (grey-blue), camera_left 16:9 (reddish): 960x720 output throughout.
  for (int i = 0; i < 20; ++i) {
    const MultiFrame mf =
        tick_with(i, {{"camera_middle", cv::Mat(960, 1280, CV_8UC3, cv::Scalar(150, 90, 60))},
                      {"camera_left", cv::Mat(360, 640, CV_8UC3, cv::Scalar(40, 60, 200))}});
    write_all(bb, mf.stamp, false, /*selected_middle=*/i < 10);
    ASSERT_TRUE(w.add(mf, bb.snapshot()));
  }
  ASSERT_TRUE(w.commit());
  const auto frames = read_video(dir / "overlay.mp4");
  ASSERT_EQ(frames.size(), 20u);
  const cv::Rect centre(300, 500, 20, 20);
  EXPECT_LT(best_match(frames[5], centre, {150, 90, 60}), 25) << "camera_middle shown";
  EXPECT_LT(best_match(frames[15], centre, {40, 60, 200}), 25) << "camera_left shown";
  // 16:9 in 960x720: 540 rows of picture, 90 black rows above and below.
  EXPECT_LT(best_match(frames[15], {400, 40, 20, 20}, {0, 0, 0}), 25);
  EXPECT_GT(best_match(frames[5], {400, 40, 20, 20}, {0, 0, 0}), 80);
  // camera_left's face box (200, 100, 80, 80) in 640x360 -> x 300..420, y 240..360 in the output.
  EXPECT_LT(best_match(frames[15], {296, 280, 9, 40}, overlay_colors::kSelectedFaceBox), 50);
  fs::remove_all(dir);
}

// Skeleton, sound direction, gesture, subtitle and speaker: what issue 21 added to the picture.
void write_body_and_audio(Blackboard& bb, Timestamp t) {
  BlackboardWriter w("test2");
  BodyState body;
  // A vertical spine 1.5 m in front of camera_middle: shoulder centre (0, -0.2), hip (0, 0.3).
  body.body.joint(JointId::kShoulderCenter) = {{0, -0.2, 1.5}, 1.f};
  body.body.joint(JointId::kSpine) = {{0, 0.05, 1.5}, 1.f};
  body.body.joint(JointId::kHipCenter) = {{0, 0.3, 1.5}, 1.f};
  w.set(keys::kChildBody, body, t, 1.f);
  SoundDirection sd;
  sd.azimuth_deg = -23;
  w.set(keys::kSoundDirection, sd, t, 1.f);
  ActionState action;
  action.label = "wave";
  action.ready = true;
  action.scores = {{"wave", 0.8}, {"none", 0.2}};
  w.set(keys::kChildAction, action, t, 1.f);
  RecognizedSpeech speech;
  speech.text = "go forward";
  w.set(keys::kRecognizedSpeech, speech, t, 1.f);
  SpeakerIdentity who;
  who.speaker_id = "child";
  w.set(keys::kSpeakerIdentity, who, t, 1.f);
  bb.commit(w, t);
}

TEST(DrawOverlay, SkeletonSoundGestureSubtitleAndLegend) {
  OverlayOptions o;
  o.cameras["camera_middle"] = middle_model();
  Blackboard bb;
  const MultiFrame mf = tick_with(3, {{"camera_middle", scene(1)}});
  write_body_and_audio(bb, mf.stamp);
  const cv::Mat pic = draw_overlay(scene(1), "camera_middle", mf, bb.snapshot(), o, {960, 720});
  // Spine: x = 640 * 0.75 = 480, from y (480 - 1100 * 0.2 / 1.5) * 0.75 = 250 to 525.
  EXPECT_LT(best_match(pic, {476, 440, 9, 60}, overlay_colors::kSkeleton), 40);
  // Gesture label (violet box) and sound direction label (dark blue box) at the left.
  EXPECT_LT(best_match(pic, {0, 560, 120, 120}, overlay_colors::kSkeleton), 1);
  EXPECT_LT(best_match(pic, {0, 600, 120, 100}, {90, 60, 20}), 1);
  // Subtitle: a black box with white (anti-aliased) text at the bottom centre.
  EXPECT_LT(best_match(pic, {330, 600, 300, 60}, {255, 255, 255}), 20);
  // Legend swatches at the bottom right: the gaze colour and the skeleton colour.
  EXPECT_LT(best_match(pic, {700, 500, 260, 220}, overlay_colors::kGaze), 1);

  // A subtitle stays for subtitle_s; 4 s later it, the gesture and the sound are gone.
  const MultiFrame later = tick_with(3 + 25, {{"camera_middle", scene(1)}});
  const cv::Mat after =
      draw_overlay(scene(1), "camera_middle", later, bb.snapshot(), o, {960, 720});
  EXPECT_LT(best_match(after, {330, 600, 300, 60}, {255, 255, 255}), 20) << "1 s later: kept";
  const cv::Mat gone =
      draw_overlay(scene(1), "camera_middle", tick_with(3 + 100, {}), bb.snapshot(), o, {960, 720});
  EXPECT_GT(best_match(gone, {0, 560, 120, 120}, overlay_colors::kSkeleton), 60);
  EXPECT_GT(best_match(gone, {330, 600, 300, 60}, {255, 255, 255}), 60) << "4 s later: gone";
  EXPECT_GT(best_match(gone, {0, 600, 120, 100}, {90, 60, 20}), 30);  // grey scene: >= 50

  // Everything off: no skeleton, labels, subtitle or legend.
  o.skeleton = o.sound_direction = o.gesture = o.subtitles = o.legend = false;
  const cv::Mat off = draw_overlay(scene(1), "camera_middle", mf, bb.snapshot(), o, {960, 720});
  EXPECT_GT(best_match(off, {476, 440, 9, 60}, overlay_colors::kSkeleton), 60);
  EXPECT_GT(best_match(off, {0, 560, 120, 120}, overlay_colors::kSkeleton), 60);
  EXPECT_GT(best_match(off, {700, 500, 260, 220}, overlay_colors::kGaze), 60);
}

TEST(OverlayWriter, WritesBrowserPlayableH264) {
  const auto dir = temp_dir("h264");
  OverlayWriter w;
  ASSERT_TRUE(w.open(dir / "overlay.mp4"));
  Blackboard bb;
  for (int i = 0; i < 10; ++i)
    ASSERT_TRUE(w.add(tick_with(i, {{"camera_middle", scene(i)}}), bb.snapshot()));
  ASSERT_TRUE(w.commit());
  EXPECT_EQ(w.codec(), "avc1");
  // The MP4's sample description names the codec: 'avc1' (H.264), not 'mp4v' (MPEG-4 Part 2).
  std::ifstream in(dir / "overlay.mp4", std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(bytes.find("avc1"), std::string::npos);
  EXPECT_NE(bytes.find("avcC"), std::string::npos) << "H.264 decoder configuration record";
  EXPECT_EQ(bytes.find("mp4v"), std::string::npos);
  EXPECT_EQ(read_video(dir / "overlay.mp4").size(), 10u);
  fs::remove_all(dir);
}

TEST(OverlayWriter, MosaicShowsEveryCamera) {
  const auto dir = temp_dir("mosaic");
  OverlayOptions o;
  o.mosaic = true;
  o.legend = false;
  OverlayWriter w;
  ASSERT_TRUE(w.open(dir / "overlay.mp4", o));
  Blackboard bb;
  for (int i = 0; i < 10; ++i) {
    std::map<SensorId, cv::Mat> images{
        {"camera_left", cv::Mat(960, 1280, CV_8UC3, cv::Scalar(40, 60, 200))},
        {"camera_middle", cv::Mat(960, 1280, CV_8UC3, cv::Scalar(150, 90, 60))}};
    if (i >= 5) images.erase("camera_left");  // keeps its last picture
    ASSERT_TRUE(w.add(tick_with(i, images), bb.snapshot()));
  }
  ASSERT_TRUE(w.commit());
  const auto frames = read_video(dir / "overlay.mp4");
  ASSERT_EQ(frames.size(), 10u);
  // Two cameras: two tiles side by side (camera_left first), 960 wide, 4:3 tiles of 480x360.
  EXPECT_EQ(frames[0].size(), cv::Size(960, 360));
  for (int i : {2, 8}) {
    EXPECT_LT(best_match(frames[static_cast<size_t>(i)], {200, 250, 20, 20}, {40, 60, 200}), 25);
    EXPECT_LT(best_match(frames[static_cast<size_t>(i)], {680, 250, 20, 20}, {150, 90, 60}), 25);
  }
  fs::remove_all(dir);
}

TEST(OverlayWriter, NothingUnderTheFinalNameUnlessCommitted) {
  const auto dir = temp_dir("partial");
  {
    OverlayWriter w;
    ASSERT_TRUE(w.open(dir / "a.mp4"));
    Blackboard bb;
    for (int i = 0; i < 3; ++i)
      ASSERT_TRUE(w.add(tick_with(i, {{"camera_middle", scene(i)}}), bb.snapshot()));
    EXPECT_TRUE(fs::exists(dir / "a.partial.mp4"));
  }  // destroyed without commit
  EXPECT_FALSE(fs::exists(dir / "a.mp4"));
  EXPECT_FALSE(fs::exists(dir / "a.partial.mp4"));
  {  // no picture at all: commit fails, nothing left
    OverlayWriter w;
    ASSERT_TRUE(w.open(dir / "b.mp4"));
    ASSERT_TRUE(w.add(tick_with(0, {}), Blackboard().snapshot()));
    EXPECT_FALSE(w.commit());
  }
  EXPECT_TRUE(fs::is_empty(dir));
  // Bad options and unwritable places are errors at open().
  OverlayWriter w;
  OverlayOptions bad;
  bad.fps = 0;
  EXPECT_FALSE(w.open(dir / "c.mp4", bad));
  EXPECT_FALSE(w.open("/proc/dreamsense_overlay/c.mp4"));
  EXPECT_FALSE(w.add(tick_with(0, {}), Blackboard().snapshot())) << "add before open";
  fs::remove_all(dir);
}

TEST(OverlayWriter, CostPerFrame) {
  // 1280x960 camera frames -> 960x720 H.264 with every element drawn; frames made beforehand.
  const auto dir = temp_dir("cost");
  OverlayOptions o;
  o.cameras["camera_middle"] = middle_model();
  OverlayWriter w;
  ASSERT_TRUE(w.open(dir / "overlay.mp4", o));
  Blackboard bb;
  std::vector<MultiFrame> ticks;
  for (int i = 0; i < 50; ++i) ticks.push_back(tick_with(i, {{"camera_middle", scene(i)}}));
  double add_ms = 0, draw_ms = 0;
  using clock = std::chrono::steady_clock;
  for (const MultiFrame& mf : ticks) {
    write_all(bb, mf.stamp, true);
    const auto view = bb.snapshot();
    const auto t0 = clock::now();
    const cv::Mat pic = draw_overlay(mf.frame("camera_middle")->as<ColorImage>()->image,
                                     "camera_middle", mf, view, o, {960, 720});
    const auto t1 = clock::now();
    ASSERT_TRUE(w.add(mf, view));
    const auto t2 = clock::now();
    draw_ms += std::chrono::duration<double, std::milli>(t1 - t0).count();
    add_ms += std::chrono::duration<double, std::milli>(t2 - t1).count();
  }
  ASSERT_TRUE(w.commit());
  std::cout << "[overlay 1280x960 -> 960x720] draw " << draw_ms / ticks.size()
            << " ms/frame, add (draw + H.264 encode) " << add_ms / ticks.size() << " ms/frame\n";
  fs::remove_all(dir);
}

// A fine black and white checkerboard (3 px squares): every blurred pixel turns grey.
cv::Mat checkerboard(cv::Size size = {1280, 960}) {
  cv::Mat img(size, CV_8UC3);
  for (int y = 0; y < size.height; ++y)
    for (int x = 0; x < size.width; ++x)
      img.at<cv::Vec3b>(y, x) = cv::Vec3b::all(((x / 3 + y / 3) % 2) ? 230 : 20);
  return img;
}

// --blur-faces (privacy): pixels inside the regions change, pixels outside do not.
TEST(BlurRegions, ChangesTheRegionsOnlyAndRemovesTheirDetail) {
  const cv::Mat original = checkerboard();
  cv::Mat img = original.clone();
  const cv::Rect face(400, 300, 200, 200);
  blur_regions(img, {face, cv::Rect(1200, 900, 500, 500) /* clipped */, cv::Rect(5, 5, 1, 1)});
  cv::Mat diff;
  cv::absdiff(original, img, diff);
  cv::Mat outside = diff.clone();
  outside(face).setTo(cv::Scalar::all(0));
  outside(cv::Rect(1200, 900, 80, 60)).setTo(cv::Scalar::all(0));
  EXPECT_EQ(cv::countNonZero(outside.reshape(1)), 0) << "pixels outside the regions changed";
  // Inside: the circles' edges are gone (little high-frequency energy left).
  auto detail = [](const cv::Mat& m) {
    cv::Mat grey, lap;
    cv::cvtColor(m, grey, cv::COLOR_BGR2GRAY);
    cv::Laplacian(grey, lap, CV_64F);
    cv::Scalar mean, sd;
    cv::meanStdDev(lap, mean, sd);
    return sd[0];
  };
  EXPECT_GT(detail(original(face)), 5.0) << "the test scene has detail there";
  EXPECT_LT(detail(img(face)), 0.3 * detail(original(face)));
  EXPECT_GT(cv::mean(diff(face))[0], 1.0);
}

// Count of pixels that differ between two pictures inside / outside `r`.
std::pair<int, int> changed_inside_outside(const cv::Mat& a, const cv::Mat& b, cv::Rect r) {
  cv::Mat diff, any;
  cv::absdiff(a, b, diff);
  cv::cvtColor(diff, any, cv::COLOR_BGR2GRAY);
  any = any > 0;
  r &= cv::Rect(0, 0, a.cols, a.rows);
  const int inside = cv::countNonZero(any(r));
  return {inside, cv::countNonZero(any) - inside};
}

TEST(DrawOverlay, BlurFacesPixelatesTheFaceBoxAndNothingElse) {
  OverlayOptions o;
  o.cameras["camera_middle"] = middle_model();
  Blackboard bb;
  const MultiFrame mf = tick_with(3, {{"camera_middle", checkerboard()}});
  write_all(bb, mf.stamp, /*mutual=*/true);
  const cv::Mat plain =
      draw_overlay(checkerboard(), "camera_middle", mf, bb.snapshot(), o, {960, 720});
  o.blur_faces = true;
  const cv::Mat blurred =
      draw_overlay(checkerboard(), "camera_middle", mf, bb.snapshot(), o, {960, 720});
  // The face box (400, 300, 200, 200) and the landmarks, shown at 0.75 and grown by 25 % each
  // side: every change lies inside (the drawing on top is the same in both).
  const cv::Rect grown(350 * 3 / 4 - 1, 250 * 3 / 4 - 1, 300 * 3 / 4 + 3, 300 * 3 / 4 + 3);
  const auto [inside, outside] = changed_inside_outside(plain, blurred, grown);
  EXPECT_EQ(outside, 0);
  EXPECT_GT(inside, grown.area() / 4);
  // The regions themselves (in shown pixels).
  const auto regions = face_regions_px("camera_middle", mf.stamp, bb.snapshot(),
                                       &o.cameras["camera_middle"], {1280, 960});
  ASSERT_GE(regions.size(), 2u);  // the box and the landmarks
  EXPECT_EQ(regions[0], cv::Rect(350, 250, 300, 300));
  // Another camera's faces are not this camera's regions.
  EXPECT_EQ(face_regions_px("camera_right", mf.stamp, bb.snapshot(), nullptr, {1280, 960}).size(),
            0u);
}

TEST(DrawOverlay, BlurFacesCoversAFaceTrackTheDetectorMissed) {
  OverlayOptions o;
  o.cameras["camera_middle"] = middle_model();
  o.blur_faces = true;
  Blackboard bb;
  const MultiFrame mf = tick_with(5, {{"camera_middle", checkerboard()}});
  {
    BlackboardWriter w("tracks");
    FaceDetections det;  // this frame: the detector found nothing
    det.cameras["camera_middle"] = CameraFaces{mf.stamp, 0, {1280, 960}, {}};
    w.set(keys::kFaceDetections, det, mf.stamp, 0.f);
    FaceTracks tracks;  // a face 1 m ahead of the camera, last seen 0.2 s ago, still
    tracks.tracks.push_back({7, {0, 0, 1.0}, {0, 0, 0}, mf.stamp - Duration::from_ms(200), 12});
    w.set(keys::kFaceTracks, tracks, mf.stamp, 1.f);
    bb.commit(w, mf.stamp);
  }
  const auto regions = face_regions_px("camera_middle", mf.stamp, bb.snapshot(),
                                       &o.cameras["camera_middle"], {1280, 960});
  ASSERT_EQ(regions.size(), 1u);
  // Centre (640, 480); half side 1100 * 0.12 / 1.0 = 132 px, grown by 25 %: 198 px.
  EXPECT_NEAR(regions[0].x, 640 - 198, 2);
  EXPECT_NEAR(regions[0].width, 2 * 198, 3);
  const cv::Mat plain = [&] {
    OverlayOptions p = o;
    p.blur_faces = false;
    return draw_overlay(checkerboard(), "camera_middle", mf, bb.snapshot(), p, {960, 720});
  }();
  const cv::Mat blurred =
      draw_overlay(checkerboard(), "camera_middle", mf, bb.snapshot(), o, {960, 720});
  const cv::Rect shown(static_cast<int>(regions[0].x * 0.75) - 1,
                       static_cast<int>(regions[0].y * 0.75) - 1,
                       static_cast<int>(regions[0].width * 0.75) + 3,
                       static_cast<int>(regions[0].height * 0.75) + 3);
  const auto [inside, outside] = changed_inside_outside(plain, blurred, shown);
  EXPECT_EQ(outside, 0);
  EXPECT_GT(inside, shown.area() / 4);
  // Without the camera model the track cannot be placed, and nothing else is there to blur.
  EXPECT_TRUE(
      face_regions_px("camera_middle", mf.stamp, bb.snapshot(), nullptr, {1280, 960}).empty());
}

}  // namespace
}  // namespace dreamsense::exporters
