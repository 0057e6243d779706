#pragma once
// `dreamsense check`: validates a session without analysing it, and writes a repaired copy.
// Everything a stream's records go through is SessionReader's (the damage policy of
// docs/session_format.md "Damaged recordings"); this adds what an analysis does not need to know:
// a per-stream table (records, gaps, every damaged record), the calibration files, the audio's
// length against the session clock, and the repair.

#include "dreamsense/core/status.hpp"
#include "dreamsense/sources/session.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace dreamsense::sources {

struct SessionCheckOptions {
  // A step between two delivered stamps longer than this many times the stream's median step is a
  // gap (dropped frames, or damaged records skipped). Must be > 1.
  double gap_factor = 1.5;
  // Audio that starts after, or ends before, the other streams by more than this is missing data.
  Duration audio_tolerance = Duration::from_seconds(1.0);
  int decode_threads = 1;             // SessionReaderOptions::decode_threads
  bool follow_links_outside = false;  // SessionReaderOptions::follow_links_outside
  Status check() const;
};

// One step between delivered records longer than gap_factor median steps.
struct StampGap {
  int64_t after_ns = 0;   // stamp of the record before the gap
  int64_t length_ns = 0;  // to the next record
};

struct StreamCheck {
  SensorId stream;
  std::string kind, encoding, file, index;  // index: empty for skeleton and audio
  // The stream cannot be read at all (missing or unreadable file, WAV rate/channels not as
  // declared, ...): the reader's one-line error. Nothing else below is filled then.
  std::optional<std::string> error;
  uint64_t delivered = 0;  // records an analysis gets (frames; audio: chunks of 40 ms)
  std::optional<int64_t> first_ns, last_ns;
  int64_t median_step_ns = 0;
  uint64_t gap_count = 0;
  int64_t gap_total_ns = 0;
  std::vector<StampGap> gaps;  // the first 20
  StreamDamage damage;         // every damaged record listed (damage.first)
  std::string calibration;     // the declared file, may be empty
  std::optional<std::string> calibration_error;
  // Audio: length (samples / rate) and how much of the other streams' span it misses.
  std::optional<double> audio_seconds;
  int64_t audio_missing_start_ns = 0, audio_missing_end_ns = 0;
  std::vector<std::string> problems;  // one line each; empty when the stream is sound
  // Worth saying but not damage, one line each: a stream with no records (a body tracker that
  // never saw anyone, a device that delivered nothing) is intact, only empty.
  std::vector<std::string> notes;
  std::vector<int64_t> delivered_stamps;  // for repair (not in the JSON)
  bool sound() const { return problems.empty(); }
};

struct SessionCheck {
  std::filesystem::path dir;
  bool manifest_ok = false;
  bool complete = false;                      // session.yaml's complete flag
  std::vector<std::string> session_problems;  // manifest, complete flag, clock
  std::vector<StreamCheck> streams;           // manifest order
  size_t markers = 0;  // operator markers in markers.jsonl (a bad file: a session problem)
  bool sound() const;
  // The `--json` document: {session, sound, complete, problems, markers, streams: [...]}.
  nlohmann::json to_json() const;
  // The human table (one row per stream) and, below it, every problem (damaged records: the
  // first `listed` of each stream).
  std::string table(size_t listed = 10) const;
};

// Reads every record of every stream (decoding every frame) and checks the calibration files.
// Never fails on a damaged session: what is wrong is in the result. Errors: bad options only.
Result<SessionCheck> check_session(const std::filesystem::path& session_dir,
                                   const SessionCheckOptions& options = {});

struct SessionRepairOptions {
  bool force = false;  // replace the contents of a non-empty output folder
  SessionCheckOptions check;
};

struct StreamRepair {
  SensorId stream;
  uint64_t kept = 0;       // records written
  uint64_t dropped = 0;    // damaged records left out
  uint64_t torn_cut = 0;   // torn-tail records cut
  uint64_t recovered = 0;  // frames after the end of a short index, indexed again
  bool removed = false;    // the stream could not be read and is not in the copy
  bool calibration_removed = false;
};

struct SessionRepair {
  SessionCheck before;  // the original
  SessionCheck after;   // the copy
  std::vector<StreamRepair> streams;
  bool complete = false;  // what the copy's session.yaml says
  std::vector<std::string> notes;
  nlohmann::json to_json() const;
};

// Writes a repaired copy of `session_dir` into `out_dir` (a new or empty folder; a non-empty one
// only with `force`): every record the reader accepts, copied byte for byte, with rebuilt indices
// (torn tails cut, damaged records dropped, frames after the end of a short index indexed again
// with stamps continued at the stream's median step), WAVs rewritten to the samples they hold, and
// every other file of the session copied. session.yaml says `complete: true` only when nothing
// was lost beyond damaged records: no stream or calibration left out, no session-level problem,
// and the copy checks sound. The copy is staged and published at the end: on failure nothing is
// left in out_dir.
Result<SessionRepair> repair_session(const std::filesystem::path& session_dir,
                                     const std::filesystem::path& out_dir,
                                     const SessionRepairOptions& options = {});

}  // namespace dreamsense::sources
