#pragma once
// Session format v1: a folder with session.yaml and one entry per stream. See
// docs/session_format.md.
//
//   session.yaml            manifest (format, format_version, streams, metadata, complete flag)
//   <id>.mjpg + <id>.idx    colour stream "mjpeg": concatenated JPEG frames + index lines
//                           "sequence,stamp_ns,offset,size" (crash-safe: append-only)
//   <id>.avi/.mp4 + <id>.stamps  colour stream "video": any OpenCV-readable container +
//                           one stamp_ns per line (read-only support, e.g. imported recordings)
//   <id>.depth + <id>.idx   depth stream "raw16": concatenated little-endian uint16 frames (mm),
//                           or "png16": concatenated lossless 16-bit grey PNG frames (mm); same
//                           index lines and crash-safety rules as mjpeg
//   <id>.jsonl              skeleton stream: one JSON object per frame
//   <id>.wav                audio stream: multichannel PCM WAV; first-sample stamp in manifest
//   calib/<id>.yaml         CameraModel files (dreamsense/core/camera_model.hpp)
//   truth.jsonl             optional ground truth (docs/truth_format.md)

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/core/sensor_frame.hpp"
#include "dreamsense/core/source.hpp"
#include "dreamsense/core/status.hpp"

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace dreamsense::sources {

inline constexpr int kSessionFormatVersion = 1;
inline constexpr const char* kManifestName = "session.yaml";

struct StreamEntry {
  SensorId id;
  SensorKind kind = SensorKind::kColor;
  std::string encoding;  // colour: "mjpeg" | "video"; depth: "raw16" | "png16";
                         // skeleton: "jsonl"; audio: "wav"
  std::string file;      // data file, relative to the session folder
  std::string index;     // index/stamps file (colour, depth), relative
  double rate_hz = 0;    // nominal
  int width = 0, height = 0;
  int sample_rate = 0, channels = 0;
  int64_t start_ns = 0;     // audio: stamp of the first sample
  std::string calibration;  // relative path of the CameraModel file, may be empty
  std::string frame;        // transform-tree frame name (defaults to id)
  // What the stream is for (docs/session_format.md "Stream roles": child_camera, table_camera,
  // table_depth, body, mic_array, robot_audio, or a user's own). Empty: the id conventions
  // decide (stream_roles).
  std::vector<std::string> roles;
};

struct Participant {
  int id = 0;
  std::optional<std::string> gender;  // "male" | "female"
  std::optional<double> age_months;
};

struct SessionManifest {
  int format_version = kSessionFormatVersion;
  std::string name;
  int64_t clock_origin_unix_ns = 0;  // wall-clock time of session stamp 0 (for exports)
  Participant participant;
  std::string condition;  // "RET" | "SHT" | ""
  std::string task;       // e.g. "TT", "JA", "IM"
  double frame_rate = 25.0;
  bool complete = false;  // set by SessionWriter::close(); false after a crash
  std::vector<StreamEntry> streams;
  std::string truth;                            // "truth.jsonl" when the session has ground truth
  std::map<std::string, std::string> metadata;  // free key/values (e.g. generator, seed)

  const StreamEntry* find(const SensorId& id) const;
};

// Reads and validates session.yaml (unknown version, missing keys, duplicate ids: clear errors).
Result<SessionManifest> read_manifest(const std::filesystem::path& session_dir);
// Atomic: writes a temporary file and renames it.
Status write_manifest(const std::filesystem::path& session_dir, const SessionManifest& manifest);
// The CameraModel of every colour stream that has a calibration file (keyed by stream id); streams
// without one are left out. A calibration file that does not read is an error naming it.
Result<std::map<SensorId, CameraModel>> read_color_calibrations(
    const std::filesystem::path& session_dir, const SessionManifest& manifest);

// The roles of every stream: its declared ones, or, for a stream without any, the defaults of
// today's id conventions: colour "camera*" -> child_camera; colour "top*" -> table_camera; depth
// "top*" -> table_depth; the first skeleton stream -> body; the first audio stream -> mic_array.
// An exclusive role (table_camera, table_depth, body, mic_array, robot_audio) claimed by two
// streams, or a known role on a stream of the wrong kind, is an error naming session.yaml.
Result<std::map<SensorId, std::vector<std::string>>> stream_roles(const SessionManifest& manifest);

// The checks read_manifest applies after parsing (version, required fields, duplicate ids,
// encoding valid for the kind, relative file paths); errors name session.yaml and the key.
Status check_manifest(const SessionManifest& manifest);
// The default data/index file names of a stream ("<id>.mjpg" + "<id>.idx", "<id>.depth" +
// "<id>.idx" for both raw16 and png16, "<id>.jsonl", "<id>.wav"); SessionWriter::create fills
// empty `file`/`index` (and an empty `frame` with the id) with these. The encoding itself is the
// caller's choice and is never changed.
void fill_stream_defaults(StreamEntry& stream);

struct SessionReaderOptions {
  Duration audio_chunk = Duration::from_ms(40);  // audio is delivered in chunks of this length
  // A session that was not closed (crash) is read up to its last complete record, with a warning.
  // When false, an incomplete session is an error.
  bool allow_incomplete = true;
  std::vector<SensorId> only;  // if not empty, read only these streams
  // Read-ahead decoding of the indexed streams (mjpeg, raw16, png16): this many background threads
  // read and decode upcoming frames, in the order next() will return them, while the caller
  // works on the current one (0 to 16; 0 decodes on the caller's thread inside next()). Only speed
  // changes: frames, order, content and errors are identical for every value. 1 is the best default
  // on 2 cores (measurements in docs/session_format.md). "video" streams are always decoded in
  // next().
  int decode_threads = 1;
  // Memory bound of read-ahead: at most this many frames (over all streams) queued, being decoded
  // or decoded and not yet returned by next(). Must be >= 1; unused when decode_threads is 0.
  int read_ahead_frames = 8;
  // Damage policy (docs/session_format.md, "Damaged recordings"): a torn tail is dropped with a
  // warning; a damaged record in the middle is skipped and counted (SessionReader::damage()); a
  // stream with more than this fraction of its records damaged is an error unless allow_damaged.
  double max_damaged_fraction = 0.2;
  bool allow_damaged = false;
  // Session files that are symbolic links to files outside the session folder are refused
  // (a shared session must not make the analysis read /etc/passwd); true follows them.
  bool follow_links_outside = false;
  // Log each stream's first damaged record and torn tail (warnings); off for a second reader of
  // the same session.
  bool log_damage = true;
  // How many damaged records each stream lists in StreamDamage::first (`dreamsense check` lists
  // them all).
  size_t listed_damage = 20;
  // A stream's `calibration` file must exist (open() fails naming it otherwise). `dreamsense
  // check` turns this off to check the stream's data and report the calibration itself.
  bool require_calibration_files = true;
  Status check() const;  // every bad field in one message
};

// One record a stream lost: where (record index in the stream: frame, index line or skeleton
// line number; stamp when known) and why.
struct DamagedRecord {
  uint64_t record = 0;
  std::optional<int64_t> stamp_ns;
  std::string what;
};

// What the damage policy did to one stream.
struct StreamDamage {
  SensorId stream;
  std::string file;
  uint64_t records = 0;      // records the stream holds, damaged ones included
  uint64_t damaged = 0;      // skipped in the middle (unreadable, undecodable, implausible)
  uint64_t torn_tail = 0;    // dropped at the end (a partly written last record)
  uint64_t empty_lines = 0;  // blank lines in a line-based file (skipped, counted)
  // The first damaged records (at most SessionReaderOptions::listed_damage, default kListed).
  std::vector<DamagedRecord> first;
  static constexpr size_t kListed = 20;
  bool any() const { return damaged > 0 || torn_tail > 0 || empty_lines > 0; }
  double damaged_fraction() const {
    return records == 0 ? 0.0 : static_cast<double>(damaged) / static_cast<double>(records);
  }
};

// Where one record the reader kept at open() lies in its stream's data file: a frame of an
// indexed stream (mjpeg, raw16, png16) or a line of a skeleton file (without its newline).
// `dreamsense check --repair` copies records byte for byte from these.
struct RecordLocation {
  uint64_t record = 0;  // frame number in the index (indexed streams) or line number (skeleton)
  uint64_t sequence = 0;
  int64_t stamp_ns = 0;
  uint64_t offset = 0, size = 0;
};

// Replays a session as a Source: frames of all streams merged in stamp order (ties broken by
// stream order in the manifest), so replay is deterministic.
// open() validates everything it can before the first frame: files present and readable, index
// consistent with data size (truncation), WAV rate/channels as declared, stamps increasing.
// Errors name the file and the problem in one line.
// Damage (SessionReaderOptions): a record that cannot be used (torn tail, malformed line, frame
// that does not decode, implausible values) is skipped and counted in damage(), never returned;
// next() fails only when a stream is damaged beyond max_damaged_fraction (unless allow_damaged).
// next() is called by one thread at a time. With read-ahead
// (options.decode_threads > 0) the destructor stops the workers after their current frame.
class SessionReader : public Source {
 public:
  static Result<std::unique_ptr<SessionReader>> open(const std::filesystem::path& session_dir,
                                                     SessionReaderOptions options = {});
  ~SessionReader() override;
  Result<FramePtr> next() override;
  SourceInfo info() const override;
  // True once stream `id` has no frame left (or is not read: options.only).
  bool stream_ended(const SensorId& id) const override;
  const SessionManifest& manifest() const;
  const std::filesystem::path& dir() const;
  // Per stream read (manifest order): what the damage policy skipped so far (complete after the
  // last next()). Streams without damage are included with zero counts.
  std::vector<StreamDamage> damage() const;
  // The records of stream `id` that passed the checks of open(), in stream order (frames that do
  // not decode are still in it: next() finds those); empty for audio and video streams and for a
  // stream that is not read.
  std::vector<RecordLocation> records(const SensorId& id) const;
  // Reads and decodes records(id)[k] as next() would return it, without moving the replay: for a
  // caller that needs a few frames of a long stream (the self-calibration uses every 6th tick).
  // Corrupt data is a kCorruptData error (not counted in damage()).
  Result<FramePtr> decode_record(const SensorId& id, size_t k) const;

 private:
  SessionReader();
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct SessionWriterOptions {
  int jpeg_quality = 92;
  // zlib level (0-9) of "png16" depth streams; lossless at every level. 1 is fast and gets most
  // of the gain (640x480: a smooth/simulated frame ~23x smaller than raw16, a noisy Kinect-like
  // one ~2x, in ~8-20 ms); higher levels cost much more time for a few % of raw16 (measurements in
  // docs/session_format.md). 0 stores the PNG uncompressed.
  int png_compression = 1;
  Duration flush_interval = Duration::from_seconds(1.0);  // of session time
  Status check() const;
};

// Writes a session. The manifest (with its declared streams) is written at create() with
// complete: false; data files are append-only and flushed (fsync) at least every flush_interval
// of session time, so after a kill everything up to the last flushed second reads back.
class SessionWriter {
 public:
  static Result<std::unique_ptr<SessionWriter>> create(const std::filesystem::path& session_dir,
                                                       SessionManifest manifest,
                                                       SessionWriterOptions options = {});
  ~SessionWriter();  // closes if still open (errors are logged)
  // Routes by frame.sensor; the payload must match the declared stream kind and size.
  Status write(const SensorFrame& frame);
  Status flush();
  // Flushes, closes every file and rewrites the manifest with complete: true.
  Status close();
  const std::filesystem::path& dir() const;

 private:
  SessionWriter();
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace dreamsense::sources
