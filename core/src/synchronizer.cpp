#include "dreamsense/core/synchronizer.hpp"

#include <algorithm>

namespace dreamsense {

const char* to_string(SyncPolicy policy) {
  return policy == SyncPolicy::kSettled ? "settled" : "latest_within_tolerance";
}

Status SynchronizerOptions::check() const {
  std::string bad;
  if (tick_period.ns() <= 0) bad += " tick_period must be > 0;";
  if (tolerance.ns() < 0) bad += " tolerance must be >= 0;";
  // tolerance may exceed half a period: a frame may then serve two ticks (sample and hold).
  if (max_in_flight < 1) bad += " max_in_flight must be >= 1;";
  if (max_buffered_per_stream < 2) bad += " max_buffered_per_stream must be >= 2;";
  if (!bad.empty()) return make_error(ErrorCode::kInvalidArgument, "SynchronizerOptions:" + bad);
  return ok_status();
}

uint64_t SyncStats::dropped_frames() const {
  uint64_t n = 0;
  for (const auto& [id, s] : streams) n += s.dropped;
  return n;
}

Synchronizer::Synchronizer(SynchronizerOptions options, std::vector<StreamSpec> streams)
    : options_(std::move(options)), start_(options_.start) {
  for (auto& spec : streams) {
    SensorId id = spec.id;
    stats_.streams[id] = {};
    streams_.emplace(id, Stream{std::move(spec), {}, Timestamp::unset(), false, nullptr});
  }
}

Timestamp Synchronizer::tick_time(uint64_t k) const {
  return start_ + options_.tick_period * static_cast<int64_t>(k);
}

Status Synchronizer::push(FramePtr frame) {
  if (!frame) return make_error(ErrorCode::kInvalidArgument, "Synchronizer::push: null frame");
  auto it = streams_.find(frame->sensor);
  if (it == streams_.end())
    return make_error(ErrorCode::kInvalidArgument, "Synchronizer: unknown sensor '{}'",
                      frame->sensor);
  Stream& s = it->second;
  if (s.ended)
    return make_error(ErrorCode::kFailedPrecondition, "Synchronizer: '{}' pushed after its end",
                      frame->sensor);
  if (s.last_stamp.is_set() && frame->stamp <= s.last_stamp)
    return make_error(ErrorCode::kCorruptData,
                      "{}: frame stamp {} ns is not after the previous frame's {} ns",
                      frame->sensor, frame->stamp.ns(), s.last_stamp.ns());
  if (!start_.is_set()) start_ = frame->stamp;
  if (options_.policy == SyncPolicy::kSettled && next_tick_ > 0) {
    // A frame that belongs before an emitted tick would make the replay order-dependent.
    const Timestamp last_emitted = tick_time(next_tick_ - 1);
    const Timestamp limit =
        s.spec.mode == StreamMode::kFrame ? last_emitted - options_.tolerance : last_emitted;
    if (frame->stamp < limit)
      return make_error(ErrorCode::kCorruptData,
                        "{}: frame at {} arrived after tick {} was settled (stamps out of order "
                        "across streams by more than the tolerance)",
                        frame->sensor, frame->stamp.to_string(), last_emitted.to_string());
  }
  s.last_stamp = frame->stamp;
  stats_.streams[s.spec.id].received++;
  s.buffer.push_back(Buffered{std::move(frame)});
  if (options_.policy == SyncPolicy::kLatestWithinTolerance) {
    while (s.buffer.size() > options_.max_buffered_per_stream) {
      Buffered b = s.buffer.front();
      s.buffer.pop_front();
      if (!b.delivered) stats_.streams[s.spec.id].dropped++;
    }
  }
  return ok_status();
}

void Synchronizer::end_stream(const SensorId& id) {
  auto it = streams_.find(id);
  if (it != streams_.end()) it->second.ended = true;
}

void Synchronizer::end_all() {
  for (auto& [id, s] : streams_) s.ended = true;
}

void Synchronizer::release(Stream& s, const Buffered& b) {
  if (b.delivered) return;
  auto& st = stats_.streams[s.spec.id];
  if (b.wanted)
    st.dropped++;
  else
    st.unmatched++;
}

void Synchronizer::evict_before(Stream& s, Timestamp t) {
  while (!s.buffer.empty() && s.buffer.front().frame->stamp < t) {
    release(s, s.buffer.front());
    s.buffer.pop_front();
  }
}

int Synchronizer::best_match(const Stream& s, Timestamp t, Timestamp not_after, bool newest) const {
  int best = -1;
  Duration best_dist;
  for (size_t i = 0; i < s.buffer.size(); ++i) {
    const Timestamp st = s.buffer[i].frame->stamp;
    if (not_after.is_set() && st > not_after) break;
    const Duration dist = (st - t).abs();
    if (dist > options_.tolerance) continue;
    // Nearest wins; on a tie the earlier frame (deterministic). Live: the newest in tolerance.
    if (best < 0 || newest || dist < best_dist) {
      best = static_cast<int>(i);
      best_dist = dist;
    }
  }
  return best;
}

bool Synchronizer::settled(uint64_t k) const {
  const Timestamp t = tick_time(k);
  for (const auto& [id, s] : streams_) {
    if (s.ended) continue;
    if (!s.last_stamp.is_set()) return false;
    const Timestamp need = s.spec.mode == StreamMode::kFrame ? t + options_.tolerance : t;
    if (s.last_stamp < need) return false;
  }
  return true;
}

bool Synchronizer::nothing_left(Timestamp t) const {
  for (const auto& [id, s] : streams_) {
    if (!s.ended) return false;
    for (const auto& b : s.buffer) {
      if (s.spec.mode == StreamMode::kContinuous && !b.delivered) return false;
      if (s.spec.mode == StreamMode::kFrame && b.frame->stamp >= t - options_.tolerance)
        return false;
    }
  }
  return true;
}

MultiFrame Synchronizer::assemble(uint64_t k, Timestamp not_after, bool newest) {
  MultiFrame mf;
  mf.tick = k;
  mf.stamp = tick_time(k);
  for (auto& [id, s] : streams_) {
    auto& st = stats_.streams[id];
    if (s.spec.mode == StreamMode::kFrame) {
      evict_before(s, mf.stamp - options_.tolerance);
      const int i = best_match(s, mf.stamp, not_after, newest);
      if (i < 0) continue;
      Buffered& b = s.buffer[static_cast<size_t>(i)];
      if (!b.delivered) st.delivered++;
      b.delivered = true;
      mf.frames[id] = b.frame;
      if (newest) {
        // Live: everything older than the chosen frame can never be delivered now.
        for (int j = 0; j < i; ++j) release(s, s.buffer[static_cast<size_t>(j)]);
        s.buffer.erase(s.buffer.begin(), s.buffer.begin() + i);
      }
    } else {
      std::vector<FramePtr> chunks;
      while (!s.buffer.empty()) {
        const Buffered& b = s.buffer.front();
        if (b.frame->stamp > mf.stamp) break;
        if (not_after.is_set() && b.frame->stamp > not_after) break;
        chunks.push_back(b.frame);
        st.delivered++;
        s.buffer.pop_front();
      }
      if (!chunks.empty()) mf.chunks[id] = std::move(chunks);
    }
  }
  return mf;
}

void Synchronizer::mark_wanted(uint64_t k, Timestamp not_after) {
  const Timestamp t = tick_time(k);
  for (auto& [id, s] : streams_) {
    if (s.spec.mode != StreamMode::kFrame) continue;
    const int i = best_match(s, t, not_after, true);
    if (i >= 0) s.buffer[static_cast<size_t>(i)].wanted = true;
  }
}

std::vector<MultiFrame> Synchronizer::poll_settled() {
  std::vector<MultiFrame> out;
  if (!start_.is_set()) {
    finished_ = std::all_of(streams_.begin(), streams_.end(),
                            [](const auto& kv) { return kv.second.ended; });
    return out;
  }
  while (!finished_) {
    const Timestamp t = tick_time(next_tick_);
    if (!settled(next_tick_)) break;
    if (nothing_left(t)) {
      finished_ = true;
      for (auto& [id, s] : streams_) {
        for (const auto& b : s.buffer) release(s, b);
        s.buffer.clear();
      }
      break;
    }
    out.push_back(assemble(next_tick_, Timestamp::unset(), false));
    stats_.ticks_emitted++;
    next_tick_++;
  }
  return out;
}

std::vector<MultiFrame> Synchronizer::poll_live(Timestamp now) {
  std::vector<MultiFrame> out;
  if (!start_.is_set() || !now.is_set() || now < start_) return out;
  const uint64_t k_now = static_cast<uint64_t>((now - start_) / options_.tick_period);
  if (k_now < next_tick_) return out;
  // Ticks the pipeline was too late for are dropped; the frames they wanted count as dropped
  // unless a later tick delivers them.
  for (uint64_t k = next_tick_; k < k_now; ++k) {
    if (k_now - k <= options_.max_buffered_per_stream) mark_wanted(k, now);
    stats_.ticks_dropped++;
  }
  next_tick_ = k_now + 1;
  if (in_flight_ >= options_.max_in_flight) {
    mark_wanted(k_now, now);
    stats_.ticks_dropped++;
    return out;
  }
  out.push_back(assemble(k_now, now, true));
  stats_.ticks_emitted++;
  in_flight_++;
  return out;
}

std::vector<MultiFrame> Synchronizer::poll(Timestamp now) {
  return options_.policy == SyncPolicy::kSettled ? poll_settled() : poll_live(now);
}

void Synchronizer::done() {
  if (in_flight_ > 0) in_flight_--;
}

bool Synchronizer::finished() const { return finished_; }

}  // namespace dreamsense
