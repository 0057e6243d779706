#pragma once
// The deterministic demo session (`dreamsense demo [--seed N]`): a synthetic but physically
// consistent recording with exact ground truth (docs/truth_format.md), built only from media
// that Debian packages ship. Scene layout: docs/demo_session.md; method: sim/README.md.
//
// Determinism: the same options give byte-identical data files and truth.jsonl, whatever the
// number of threads (each frame depends only on (seed, stream, frame index)).

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/status.hpp"
#include "dreamsense/sim/demo_scene.hpp"
#include "dreamsense/sim/face_renderer.hpp"

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace dreamsense::sim {

// The demo child's subject id (session metadata `subject`); its calibration ships in
// data/subjects/demo_child (tools/train_demo_subject.sh).
inline constexpr const char* kDemoSubject = "demo_child";

// data/demo/robot in the source tree (compiled in, as the portrait landmarks).
std::filesystem::path default_robot_prompts_dir();

struct DemoOptions {
  std::filesystem::path out_dir;  // required; must not exist, be empty, or hold an old session
  uint64_t seed = 1;
  double duration_s = 20;         // (0, 600]
  double camera_rate_hz = 25;     // camera_left / camera_middle / camera_right (DREAM ~25 Hz)
  double kinect_rate_hz = 30;     // front.color, front.depth, front.skeleton, top.color
  int audio_sample_rate = 16000;  // must equal the clips' rate (16 kHz)
  double audio_chunk_s = 0.1;     // length of the AudioChunk frames written
  double rt60_s = 0.35;           // room reverberation
  double snr_db = 20;             // speech (while active) to pink noise, per channel
  // Child-like voice (issue 16): the child's clips (session and enrolment) played this much
  // faster, like a tape: pitch and every formant x factor, duration / factor (libsoxr
  // resampling of the 16 kHz clip read as 16 kHz x factor). 1 = the recordings as they are
  // (adult talkers); 1.3 puts a man's ~120 Hz f0 near 155 Hz and his formants where a
  // ten-year-old's are (a shorter vocal tract). [0.5, 2].
  double child_voice_shift = 1.0;
  double joint_noise_m = 0.005;    // Gaussian noise on the written skeleton joints (truth: none)
  double image_noise_sigma = 2.0;  // Gaussian noise on colour images (grey levels)
  int jpeg_quality = 90;
  int threads = 2;         // render threads (>= 1); never changes the output
  bool overwrite = false;  // replace an existing session folder (only if it has session.yaml)
  // The child's face: the textured 3-D mesh with moving eyes (default), or the flat photo
  // (painted eyes: the truth eye gaze is then the head gaze).
  enum class FaceModel { kMesh, kPlanar };  // kMesh: session metadata subject = kDemoSubject
  FaceModel face_model = FaceModel::kMesh;
  // Which child (index into demo_children(), demo_children.hpp; mesh face only): portrait, face
  // width, eye height, metadata subject. `dreamsense demo` sets demo_child_for_seed(seed); the
  // library keeps child 0 (the original child; `portrait` / `portrait_landmarks` below apply to
  // it only).
  int child = 0;
  // The child's gestures: by default DREAM's gestures that leave the face in view (wave, fly,
  // hands_on_head, drive_car: F20 is checkable on every demo); kDream: all six (also cover_eyes
  // and drink, hands over the face); kClassic: the original three (the demo before issue 13);
  // custom gestures and a fixed schedule for tests.
  DemoScriptOptions script{.gestures = DemoScriptOptions::GestureSet::kDreamFaceVisible};
  // Media shipped by Debian packages.
  std::filesystem::path portrait =
      "/usr/lib/python3/dist-packages/skimage/data/astronaut.png";  // python3-skimage
  // The portrait's 68 landmarks (in the dreamsense source tree; mesh face only).
  std::filesystem::path portrait_landmarks = default_portrait_landmarks_path();
  std::filesystem::path opencv_samples_dir =
      "/usr/share/doc/opencv-doc/examples/data";  // opencv-doc
  std::filesystem::path pocketsphinx_data_dir =
      "/usr/share/pocketsphinx/test/data";  // pocketsphinx-testdata
  // The robot's own voice (issue 16): prompts played through the robot's loudspeaker (at
  // geometry.robot_head_m) in the gaps between the child's and the therapist's utterances,
  // rendered into the array by the room, with truth records `robot_speech`, and the played
  // signal as the session's reference stream `robot_audio` (role robot_audio). Off: the demo
  // before issue 16 (byte-identical microphone audio).
  bool robot_voice = true;
  // prompts.txt + the prompt files (espeak-ng, tools/make_robot_prompts.sh); in the source tree.
  std::filesystem::path robot_prompts_dir = default_robot_prompts_dir();
  // Only the audio streams (mic_array, robot_audio), the enrolment audio, the grammar and the
  // full truth: the same audio as the full session in a fraction of the time (audio work).
  bool audio_only = false;
  Status check() const;
};

struct DemoSummary {
  std::filesystem::path out_dir;
  std::map<std::string, int64_t> frames;  // per stream id (audio: chunks)
  int utterances = 0;
  int robot_utterances = 0;
  int action_segments = 0;
  int64_t truth_records = 0;
  double generation_s = 0;  // wall-clock time of generate_demo_session
};

// Generates the session folder. `progress` (optional) receives fractions in [0, 1].
// Missing media give one-line errors naming the file and the Debian package to install.
Result<DemoSummary> generate_demo_session(
    const DemoOptions& options, const std::function<void(double fraction)>& progress = nullptr);

// ---- Building blocks (exposed for tests and for `dreamsense eval`) ----

// All demo cameras, in manifest order: camera_left, camera_middle, camera_right, front.color,
// front.depth (same model as front.color: registered depth), top.color.
std::vector<CameraModel> make_demo_cameras(const DemoGeometry& geometry = {});

// The child's body as the session's skeleton stream `stream` writes it at frame `sequence`
// (stamp in ns): the script's joints plus seeded Gaussian noise, legs "inferred" (0.5). Lets
// tools build skeleton streams of any seed without rendering cameras.
SkeletonBody demo_skeleton_body(const DemoScript& script, uint64_t seed, const std::string& stream,
                                uint64_t sequence, int64_t stamp_ns, double joint_noise_m);
// Stamp of frame `index` of a stream at rate_hz (all demo streams start at 0).
int64_t demo_stamp_ns(int64_t index, double rate_hz);

// The face's state at time t: head pose, eyes fixating the script's gaze target, blinks.
FaceState demo_face_state(const DemoScript& script, double t);

// Kinect v1 microphone positions in the array frame (metres), Nx3 rows.
std::vector<cv::Vec3d> demo_mic_positions(const DemoGeometry& geometry = {});

// Azimuth/elevation (degrees) of a world point in the array frame: azimuth 0 = broadside
// (+z), positive towards +x; elevation positive upwards (towards -y).
void array_direction(const DemoGeometry& geometry, const cv::Vec3d& world, double& azimuth_deg,
                     double& elevation_deg);

struct SpeechClipInfo {
  std::string file;     // relative to pocketsphinx_data_dir
  std::string text;     // transcription
  std::string speaker;  // "child" | "therapist"
  double duration_s = 0;
  double speech_start_s = 0, speech_end_s = 0;  // energy gate on the clean clip
};

struct PlannedUtterance {
  size_t clip = 0;              // index into the clip list
  double clip_start_s = 0;      // session time of the clip's first sample
  cv::Vec3d source_m{0, 0, 0};  // world
};

struct RobotPrompt {
  std::string file;  // relative to robot_prompts_dir
  std::string text;
  bool in_grammar = false;
};
struct PlannedRobotUtterance {
  size_t prompt = 0;        // index into the prompt list
  double clip_start_s = 0;  // session time of the prompt's first sample
};
// The robot speaks in the gaps of the human utterances: in each gap (also before the first and
// after the last) that leaves >= margin_s (1.0 s) of silence on both sides, with probability
// 0.7, one prompt, centred; prompts cycle in a seeded order. Depends only on the seed.
std::vector<PlannedRobotUtterance> plan_robot_utterances(
    uint64_t seed, double duration_s, const std::vector<std::pair<double, double>>& busy_s,
    const std::vector<double>& prompt_durations_s, double margin_s = 1.0);

// Non-overlapping placement of 3-5 utterances (fewer if the session is too short), alternating
// speakers; child utterances come from the child's mouth, therapist ones from one side of the
// array at 30-60 degrees azimuth and 1.2-2.0 m.
std::vector<PlannedUtterance> plan_utterances(const DemoScript& script,
                                              const std::vector<SpeechClipInfo>& clips);

}  // namespace dreamsense::sim
