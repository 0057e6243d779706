#pragma once
// Groups frames from many sensors into MultiFrames on a fixed-rate pipeline clock.
//
// Two policies:
//  - kSettled (replay, evaluation): tick k (at start + k*period) is emitted only once every
//    stream has either delivered a frame later than tick + tolerance or ended. The result does
//    not depend on arrival timing, so replays are deterministic. Nothing is ever dropped.
//  - kLatestWithinTolerance (live): poll(now) emits the newest tick <= now at once, with the
//    newest frame of each stream within tolerance of it. A flow limiter admits at most
//    max_in_flight ticks that the pipeline has not finished (done()); a tick refused by the
//    limiter is dropped. Every frame that is never delivered is counted as dropped.
// Frames of one stream must arrive in increasing stamp order.

#include "dreamsense/core/multi_frame.hpp"
#include "dreamsense/core/status.hpp"

#include <deque>
#include <map>
#include <vector>

namespace dreamsense {

enum class SyncPolicy { kSettled, kLatestWithinTolerance };
const char* to_string(SyncPolicy policy);

enum class StreamMode {
  kFrame,       // one frame per tick (nearest within tolerance): cameras, depth, skeleton
  kContinuous,  // every chunk is delivered exactly once, with the first tick at or after it: audio
};

struct StreamSpec {
  SensorId id;
  StreamMode mode = StreamMode::kFrame;
};

struct SynchronizerOptions {
  SyncPolicy policy = SyncPolicy::kSettled;
  Duration tick_period = Duration::from_ms(40);  // DREAM ran at 25 Hz
  Duration tolerance = Duration::from_ms(20);    // max |frame stamp - tick| for a match
  // Tick 0 time. Unset: the stamp of the first frame pushed.
  Timestamp start = Timestamp::unset();
  int max_in_flight = 1;                 // live flow limiter
  size_t max_buffered_per_stream = 256;  // live: older frames are dropped (and counted)
  Status check() const;
};

struct StreamStats {
  uint64_t received = 0;
  uint64_t delivered = 0;  // frames that appeared in at least one MultiFrame
  // Never delivered because no tick fell within tolerance while the frame was the best match
  // (rate conversion, e.g. a 30 Hz stream on a 25 Hz clock). Not a loss of the pipeline.
  uint64_t unmatched = 0;
  // Never delivered although a tick wanted it: that tick was refused by the flow limiter or
  // came too late (live), or the buffer overflowed.
  uint64_t dropped = 0;
};

struct SyncStats {
  uint64_t ticks_emitted = 0;
  uint64_t ticks_dropped = 0;  // live: refused by the flow limiter
  std::map<SensorId, StreamStats> streams;
  uint64_t dropped_frames() const;
};

class Synchronizer {
 public:
  Synchronizer(SynchronizerOptions options, std::vector<StreamSpec> streams);

  // Errors: unknown sensor, frame older than the previous frame of its stream, or (settled)
  // older than a tick already emitted.
  Status push(FramePtr frame);
  // Settled: no more frames will come from this stream.
  void end_stream(const SensorId& id);
  void end_all();

  // Settled: every tick that is now settled (now is ignored). Live: at most one MultiFrame,
  // for the newest tick <= now.
  std::vector<MultiFrame> poll(Timestamp now = Timestamp::unset());
  // Live: the pipeline finished one admitted MultiFrame.
  void done();
  // Settled: all streams ended and every tick up to the last frame emitted.
  bool finished() const;

  const SyncStats& stats() const { return stats_; }
  const SynchronizerOptions& options() const { return options_; }

 private:
  struct Buffered {
    FramePtr frame;
    bool delivered = false;
    bool wanted = false;  // best match of a tick that was dropped
  };
  struct Stream {
    StreamSpec spec;
    std::deque<Buffered> buffer;  // not yet released
    Timestamp last_stamp = Timestamp::unset();
    bool ended = false;
    FramePtr last_delivered;  // live: may be reused while within tolerance
  };
  Timestamp tick_time(uint64_t k) const;
  bool settled(uint64_t k) const;
  bool nothing_left(Timestamp t) const;
  // Index in s.buffer of the best frame for tick time t (nearest; live: newest) or -1.
  int best_match(const Stream& s, Timestamp t, Timestamp not_after, bool newest) const;
  MultiFrame assemble(uint64_t k, Timestamp not_after, bool newest);
  void mark_wanted(uint64_t k, Timestamp not_after);
  void evict_before(Stream& s, Timestamp t);
  void release(Stream& s, const Buffered& b);
  std::vector<MultiFrame> poll_settled();
  std::vector<MultiFrame> poll_live(Timestamp now);

  SynchronizerOptions options_;
  std::map<SensorId, Stream> streams_;
  SyncStats stats_;
  Timestamp start_ = Timestamp::unset();
  uint64_t next_tick_ = 0;
  bool finished_ = false;
  int in_flight_ = 0;
};

}  // namespace dreamsense
