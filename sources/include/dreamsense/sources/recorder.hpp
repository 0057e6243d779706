#pragma once
// Recording a session from live devices (`dreamsense record --config FILE --out DIR`).
//
// The configuration (YAML, docs/recording.md) names the cameras (OpenCV VideoCapture devices)
// and the microphone array (ALSA), their calibration files and the session's metadata. Every
// source runs its own capture thread; a writer thread per source moves its frames into one
// SessionWriter (crash-safe, flushed every second of session time), so a slow stream never holds
// up another. Stamps are the monotonic clock from the start of the recording (stamp 0); the wall
// clock of stamp 0 goes into the manifest for exports. Dropped frames and audio overruns are
// counted and reported, never hidden.

#include "dreamsense/core/source.hpp"
#include "dreamsense/core/status.hpp"
#include "dreamsense/sources/session.hpp"

#include <nlohmann/json.hpp>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace dreamsense::sources {

struct RecordCameraConfig {
  SensorId id;
  std::string device;  // V4L2 index, /dev/videoN, URL or (for dry runs) a video file
  int width = 0, height = 0;
  double fps = 0;
  std::filesystem::path calibration;  // CameraModel YAML, copied to calib/<id>.yaml; optional
};

struct RecordAudioConfig {
  SensorId id = "mic_array";
  std::string device = "default";  // ALSA PCM name
  int sample_rate = 16000;
  int channels = 4;
  std::filesystem::path calibration;  // microphone geometry YAML, copied to calib/<id>.yaml
};

// The robot's own voice, captured as the analysers' reference (docs/session_format.md, "The
// robot's voice"): an ALSA capture of what the robot plays, e.g. a loopback (snd-aloop) or the
// sound server's monitor of the robot's output. Recorded as a stream with the role robot_audio;
// the microphone array's stream then declares the role mic_array. The analysers measure the
// offset between the two devices themselves (within +-1 s), so their start latencies may differ.
struct RecordRobotAudioConfig {
  SensorId id = "robot_audio";
  std::string device;  // ALSA PCM name; required
  int sample_rate = 16000;
  int channels = 1;
};

// Skeletons from an external body tracker over UDP (udp_skeleton_source.hpp).
struct RecordSkeletonConfig {
  SensorId id = "front.skeleton";  // the body analyser takes the first skeleton stream
  std::string host = "127.0.0.1";  // listen address (config key `udp: "host:port"`)
  int port = 0;
  double rate_hz = 30;
  std::filesystem::path calibration;  // the tracker's sensor pose (CameraModel YAML), optional
};

// A live RGB-D sensor (depth_sensor_source.hpp): streams <id>.depth (raw16) and <id>.color.
struct RecordDepthSensorConfig {
  std::string id = "front";
  std::string driver = "freenect";  // freenect | openni2 | fake
  std::string device;               // freenect: index; openni2: URI or .oni file; "" = first
  double fps = 30;
  bool color = true;
  std::filesystem::path calibration;  // CameraModel YAML of the (registered) sensor, optional
};

struct RecordConfig {
  std::string name;  // session name (default: the output folder's name)
  Participant participant;
  std::string condition;  // "RET" | "SHT" | ""
  std::string task;
  std::map<std::string, std::string> metadata;  // copied into session.yaml
  std::filesystem::path speech_grammar;         // copied to speech.gram (metadata speech_grammar)
  std::filesystem::path voice_enroll;  // folder <speaker>/*.wav, copied to enroll/ (voice_enroll)
  std::vector<RecordCameraConfig> cameras;
  std::vector<RecordSkeletonConfig> skeletons;
  std::vector<RecordDepthSensorConfig> depth_sensors;
  std::optional<RecordAudioConfig> audio;
  std::optional<RecordRobotAudioConfig> robot_audio;  // needs `audio`
  Status check() const;                               // every problem in one message
};

// Reads the YAML configuration; relative paths are taken from the file's folder. Unknown keys
// are errors (a typo must not silently drop a camera).
Result<RecordConfig> read_record_config(const std::filesystem::path& file);

struct RecordStreamStats {
  uint64_t frames_written = 0;  // recorded (when recording) or delivered
  uint64_t frames_dropped = 0;  // by the source because its consumer fell behind
  uint64_t overruns = 0;        // audio samples lost in the device (ALSA overruns)
  // The device failed during the session (unplugged, driver error): why and when; empty if not.
  // Its stream is offline from then on; the other devices went on.
  std::string lost;
};

struct RecordStats {
  double duration_s = 0;
  std::map<SensorId, RecordStreamStats> streams;
};

// An error naming the streams whose device failed during the session (RecordStreamStats::lost),
// for the command's exit status; ok when none did.
Status lost_devices(const RecordStats& stats);

// What the capture counted, kept beside session.yaml by a recording (`record`, `live --record`),
// so that whoever analyses the session later knows what the terminal said once: a device lost
// at 12 s, frames dropped because the disk fell behind. `check` reports it.
inline constexpr const char* kCaptureReportFile = "capture.json";
// {"duration_s", "streams": {id: {"frames_captured", "frames_dropped", "overruns", "lost"}}}
// ("lost": the reason and time, or null).
nlohmann::json capture_report(const RecordStats& stats);
// The capture report of `session_dir`: nullopt when it has none (not a recording, or recorded
// before 2026-12-01); an error naming the file when it is not such an object.
Result<std::optional<nlohmann::json>> read_capture_report(const std::filesystem::path& session_dir);

// The configured devices as one live Source (frames of all devices in arrival order; each
// stream's stamps increase), optionally recorded on the way through.
//
// manifest() describes the streams. Its file references (calibration, speech grammar, voice
// enrolment) are absolute paths into the configuration's files, so analysers can be set up from
// it without a recording; the recorded session.yaml holds its own copies under relative names.
struct LiveCaptureOptions {
  // When every device has ended by itself (video files run out), keep the stream open (next()
  // waits) until stop(): a run with a fixed duration lasts that long, its sensors offline.
  // false: the stream ends with the last device.
  bool until_stopped = false;
};

class LiveCapture : public Source {
 public:
  // Opens every device (an error before anything is written when one fails). With
  // `record_dir`, creates the session there (it must not already hold one) and writes every
  // delivered frame into it.
  static Result<std::unique_ptr<LiveCapture>> open(
      const RecordConfig& config, const std::optional<std::filesystem::path>& record_dir = {},
      const SessionWriterOptions& writer = {}, const LiveCaptureOptions& options = {});
  ~LiveCapture() override;
  LiveCapture(const LiveCapture&) = delete;
  LiveCapture& operator=(const LiveCapture&) = delete;

  // Blocks until a frame arrives. After stop(): the queued frames, then kEndOfStream. A disk
  // failure is returned once, after the frames before it, and ends the capture. A device that
  // fails (unplugged, driver error) only ends its own streams: logged, counted in finish()'s
  // RecordStreamStats::lost, while the other devices go on (the analysis sees the stream offline).
  Result<FramePtr> next() override;
  SourceInfo info() const override;
  const SessionManifest& manifest() const;
  // The UDP port each skeleton input listens on (port 0 in the configuration: a free one).
  std::map<SensorId, int> skeleton_ports() const;
  // The steady-clock time of stamp 0.
  std::chrono::steady_clock::time_point clock_origin() const;
  void stop();          // thread-safe; ends every device
  bool failed() const;  // the recording failed (next() reports why)
  // Devices still delivering (not ended, not lost, not stopped).
  int devices_running() const;
  // After the end of stream: closes the recording (complete: true) and returns the counts.
  Result<RecordStats> finish();

 private:
  struct Impl;
  explicit LiveCapture(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

struct RecordOptions {
  std::optional<double> duration_s;         // stop after this long; none: until *stop
  const std::atomic<bool>* stop = nullptr;  // set (e.g. by SIGINT) to end the recording
  SessionWriterOptions writer;
  std::function<void(double elapsed_s)> progress;  // called about once a second
};

// Records into `out_dir` (created; must not already hold a session). Returns when the duration
// has passed, *stop was set, or a source failed (the session is then closed with what was
// recorded and the error is returned).
Result<RecordStats> record_session(const RecordConfig& config, const std::filesystem::path& out_dir,
                                   const RecordOptions& options);

}  // namespace dreamsense::sources
