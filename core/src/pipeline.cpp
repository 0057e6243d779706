#include "dreamsense/core/pipeline.hpp"

#include "dreamsense/core/log.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <set>
#include <thread>

namespace dreamsense {
namespace {
using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}
std::set<SensorId> ids_of(const std::vector<StreamSpec>& specs) {
  std::set<SensorId> ids;
  for (const auto& s : specs) ids.insert(s.id);
  return ids;
}
}  // namespace

Result<std::vector<std::unique_ptr<Analyzer>>> order_by_contracts(
    std::vector<std::unique_ptr<Analyzer>> analyzers) {
  const size_t n = analyzers.size();
  std::vector<AnalyzerContract> contracts;
  std::map<std::string, size_t> writer;
  for (size_t i = 0; i < n; ++i) {
    contracts.push_back(analyzers[i]->contract());
    for (const auto& k : contracts[i].writes) writer.emplace(k, i);
  }
  std::vector<std::set<size_t>> after(n);  // after[i]: analysers that must run after i
  std::vector<int> pending(n, 0);
  auto edge = [&](size_t first, size_t second) {
    if (first != second && after[first].insert(second).second) pending[second]++;
  };
  for (size_t i = 0; i < n; ++i) {
    for (const auto& k : contracts[i].reads)
      if (auto w = writer.find(k); w != writer.end()) edge(w->second, i);
    for (const auto& k : contracts[i].reads_previous)
      if (auto w = writer.find(k); w != writer.end()) edge(i, w->second);
  }
  std::vector<std::unique_ptr<Analyzer>> out;
  std::vector<bool> done(n, false);
  for (size_t round = 0; round < n; ++round) {
    size_t next = n;
    for (size_t i = 0; i < n && next == n; ++i)
      if (!done[i] && pending[i] == 0) next = i;
    if (next == n) {
      std::string names;
      for (size_t i = 0; i < n; ++i)
        if (!done[i]) names += (names.empty() ? "" : ", ") + std::string(analyzers[i]->name());
      return make_error(ErrorCode::kFailedPrecondition,
                        "pipeline: analysers {} read each other's keys in a cycle", names);
    }
    done[next] = true;
    for (size_t j : after[next]) pending[j]--;
    out.push_back(std::move(analyzers[next]));
  }
  return out;
}

std::map<std::string, std::vector<SensorId>, std::less<>> key_sensors(
    const std::vector<std::unique_ptr<Analyzer>>& analyzers, const SourceInfo& source) {
  std::map<std::string, std::vector<SensorId>, std::less<>> out;
  for (const auto& a : analyzers) {
    const AnalyzerContract c = a->contract();
    std::set<SensorId> sensors(c.required_inputs.begin(), c.required_inputs.end());
    for (const auto& o : c.optional_inputs)
      if (source.find(o) != nullptr) sensors.insert(o);
    for (const auto& k : c.reads)
      if (auto it = out.find(k); it != out.end())
        sensors.insert(it->second.begin(), it->second.end());
    for (const auto& k : c.writes) out[k] = std::vector<SensorId>(sensors.begin(), sensors.end());
  }
  return out;
}

int PipelineOptions::auto_threads(unsigned cores) {
  if (cores < 4) return 1;
  return std::min(static_cast<int>(cores) - 1, kMaxAutoThreads);
}

Status PipelineOptions::check() const {
  if (threads < 0 || threads > kMaxThreads)
    return make_error(ErrorCode::kInvalidArgument,
                      "PipelineOptions: threads must be in [0, {}] (0: auto), got {}", kMaxThreads,
                      threads);
  if (auto s = sync.check(); !s) return s;
  return blackboard.check();
}

Pipeline::Pipeline(PipelineOptions options, SourceInfo info,
                   std::vector<std::unique_ptr<Analyzer>> analyzers)
    : options_(options),
      info_(std::move(info)),
      analyzers_(std::move(analyzers)),
      blackboard_(options_.blackboard) {
  for (const auto& a : analyzers_)
    stats_.analyzers.push_back(AnalyzerStats{std::string(a->name())});
  const size_t n = analyzers_.size();
  stats_.threads = options_.threads > 0
                       ? options_.threads
                       : PipelineOptions::auto_threads(std::thread::hardware_concurrency());
  if (n < 2) stats_.threads = 1;
  if (stats_.threads == 1) return;
  // j (later) waits for i when one of them writes a key the other reads, in this tick or as
  // feedback: then the order between them is what each sees.
  std::vector<AnalyzerContract> contracts;
  for (const auto& a : analyzers_) contracts.push_back(a->contract());
  auto reads_what_writes = [&](const AnalyzerContract& reader, const AnalyzerContract& writer) {
    for (const auto& k : writer.writes)
      if (std::find(reader.reads.begin(), reader.reads.end(), k) != reader.reads.end() ||
          std::find(reader.reads_previous.begin(), reader.reads_previous.end(), k) !=
              reader.reads_previous.end())
        return true;
    return false;
  };
  dependencies_.assign(n, 0);
  unblocks_.resize(n);
  for (size_t j = 0; j < n; ++j)
    for (size_t i = 0; i < j; ++i)
      if (reads_what_writes(contracts[j], contracts[i]) ||
          reads_what_writes(contracts[i], contracts[j])) {
        dependencies_[j]++;
        unblocks_[i].push_back(j);
      }
  waiting_on_.assign(n, 0);
  path_ms_.assign(n, 0);
  for (int t = 1; t < stats_.threads; ++t) workers_.emplace_back([this] { worker_loop(); });
}

Pipeline::~Pipeline() {
  {
    std::lock_guard<std::mutex> lock(tick_mutex_);
    stopping_ = true;
  }
  tick_cv_.notify_all();
  for (auto& w : workers_) w.join();
}

Result<std::unique_ptr<Pipeline>> Pipeline::build(
    PipelineOptions options, SourceInfo source_info,
    std::vector<std::unique_ptr<Analyzer>> analyzers) {
  if (auto s = options.check(); !s) return tl::unexpected(s.error());
  std::set<std::string> names, written;
  for (const auto& a : analyzers) {
    if (!a) return make_error(ErrorCode::kInvalidArgument, "pipeline: null analyser");
    const std::string name(a->name());
    if (!names.insert(name).second)
      return make_error(ErrorCode::kFailedPrecondition, "pipeline: two analysers named '{}'", name);
    const AnalyzerContract c = a->contract();
    for (const auto& in : c.required_inputs)
      if (source_info.find(in) == nullptr)
        return make_error(
            ErrorCode::kFailedPrecondition,
            "pipeline: analyser '{}' needs sensor '{}', which the source does not have", name, in);
    for (const auto& key : c.reads)
      if (written.count(key) == 0)
        return make_error(ErrorCode::kFailedPrecondition,
                          "pipeline: analyser '{}' reads '{}', which no earlier analyser writes",
                          name, key);
    for (const auto& key : c.writes)
      if (!written.insert(key).second)
        return make_error(ErrorCode::kFailedPrecondition,
                          "pipeline: blackboard key '{}' has two writers (second: '{}')", key,
                          name);
  }
  return std::unique_ptr<Pipeline>(
      new Pipeline(options, std::move(source_info), std::move(analyzers)));
}

Status Pipeline::replace_analyzers(std::vector<std::unique_ptr<Analyzer>> replacements) {
  auto same = [](const AnalyzerContract& a, const AnalyzerContract& b) {
    return a.required_inputs == b.required_inputs && a.optional_inputs == b.optional_inputs &&
           a.reads == b.reads && a.writes == b.writes && a.reads_previous == b.reads_previous;
  };
  std::vector<size_t> at;
  for (const auto& r : replacements) {
    if (!r) return make_error(ErrorCode::kInvalidArgument, "pipeline: null replacement analyser");
    const auto it = std::find_if(analyzers_.begin(), analyzers_.end(),
                                 [&](const auto& a) { return a->name() == r->name(); });
    if (it == analyzers_.end())
      return make_error(ErrorCode::kNotFound, "pipeline: no analyser '{}' to replace", r->name());
    if (!same((*it)->contract(), r->contract()))
      return make_error(ErrorCode::kFailedPrecondition,
                        "pipeline: the replacement of '{}' has another contract", r->name());
    at.push_back(static_cast<size_t>(it - analyzers_.begin()));
  }
  for (size_t k = 0; k < replacements.size(); ++k) analyzers_[at[k]] = std::move(replacements[k]);
  return ok_status();
}

void Pipeline::finish_stats(const Synchronizer& sync, Timestamp first, Timestamp last) {
  stats_.sync = sync.stats();
  if (first.is_set())
    stats_.media_seconds = (last - first).seconds() + options_.sync.tick_period.seconds();
}

std::vector<StreamSpec> Pipeline::stream_specs() const {
  std::set<SensorId> used;
  for (const auto& a : analyzers_) {
    const AnalyzerContract c = a->contract();
    used.insert(c.required_inputs.begin(), c.required_inputs.end());
    for (const auto& o : c.optional_inputs)
      if (info_.find(o) != nullptr) used.insert(o);
  }
  std::vector<StreamSpec> specs;
  for (const auto& s : info_.sensors) {
    if (!used.empty() && used.count(s.id) == 0) continue;
    specs.push_back(StreamSpec{
        s.id, s.kind == SensorKind::kAudio ? StreamMode::kContinuous : StreamMode::kFrame});
  }
  return specs;
}

void Pipeline::run_analyzer(size_t i, const MultiFrame& frame) {
  Analyzer& a = *analyzers_[i];
  AnalyzerStats& st = stats_.analyzers[i];
  BlackboardWriter writer{std::string(a.name())};
  const auto t0 = Clock::now();
  try {
    Status s = a.process(frame, blackboard_.snapshot(), writer);
    if (!s) {
      st.errors++;
      if (st.errors <= 5)
        log::warn("{} at {}: {}", a.name(), frame.stamp.to_string(), s.error().message);
      return;
    }
    blackboard_.commit(writer, frame.stamp);
  } catch (const CheckFailure& e) {
    // A broken precondition inside an analyser: log, reset it, keep the pipeline running.
    st.errors++;
    if (st.errors <= 5)
      log::error("{} at {}: {}; resetting it", a.name(), frame.stamp.to_string(), e.what());
    a.reset();
  }
  st.calls++;
  st.latency_ms.push_back(ms_since(t0));
  st.latency_total_ms += st.latency_ms.back();
}

std::optional<size_t> Pipeline::take_ready() {
  if (tick_frame_ == nullptr || tick_exception_ || ready_.empty()) return std::nullopt;
  auto best = ready_.begin();
  for (auto it = ready_.begin(); it != ready_.end(); ++it)
    if (path_ms_[*it] > path_ms_[*best] || (path_ms_[*it] == path_ms_[*best] && *it < *best))
      best = it;
  const size_t i = *best;
  ready_.erase(best);
  return i;
}

// Runs analyser i of the current tick outside the lock, then releases what waited for it.
// Called with `lock` held; returns with it held.
void Pipeline::run_one(size_t i, std::unique_lock<std::mutex>& lock) {
  const MultiFrame& frame = *tick_frame_;
  running_++;
  lock.unlock();
  std::exception_ptr error;
  try {
    run_analyzer(i, frame);
  } catch (...) {
    error = std::current_exception();
  }
  lock.lock();
  running_--;
  finished_++;
  if (error && !tick_exception_) tick_exception_ = error;
  for (size_t j : unblocks_[i])
    if (--waiting_on_[j] == 0) ready_.push_back(j);
  tick_cv_.notify_all();
}

void Pipeline::worker_loop() {
  std::unique_lock<std::mutex> lock(tick_mutex_);
  while (true) {
    tick_cv_.wait(lock, [this] {
      return stopping_ || (tick_frame_ != nullptr && !tick_exception_ && !ready_.empty());
    });
    if (stopping_) return;
    if (auto i = take_ready()) run_one(*i, lock);
  }
}

void Pipeline::run_analyzers_in_parallel(const MultiFrame& frame) {
  const size_t n = analyzers_.size();
  // Longest path to the end of the tick through each analyser, by mean latency so far: the
  // analyser that others wait on longest starts first.
  for (size_t k = n; k-- > 0;) {
    double tail = 0;
    for (size_t j : unblocks_[k]) tail = std::max(tail, path_ms_[j]);
    const AnalyzerStats& st = stats_.analyzers[k];
    path_ms_[k] = tail + (st.calls > 0 ? st.latency_total_ms / static_cast<double>(st.calls) : 0.0);
  }
  std::unique_lock<std::mutex> lock(tick_mutex_);
  tick_frame_ = &frame;
  finished_ = 0;
  tick_exception_ = nullptr;
  ready_.clear();
  for (size_t i = 0; i < n; ++i) {
    waiting_on_[i] = dependencies_[i];
    if (waiting_on_[i] == 0) ready_.push_back(i);
  }
  tick_cv_.notify_all();
  while (finished_ < n && !(tick_exception_ && running_ == 0)) {
    if (auto i = take_ready())
      run_one(*i, lock);
    else
      tick_cv_.wait(lock);
  }
  tick_frame_ = nullptr;
  const std::exception_ptr error = tick_exception_;
  lock.unlock();
  if (error) std::rethrow_exception(error);
}

Status Pipeline::process_tick(const MultiFrame& frame, const TickCallback& on_tick) {
  const auto t_tick = Clock::now();
  if (stats_.threads > 1) {
    run_analyzers_in_parallel(frame);
  } else {
    for (size_t i = 0; i < analyzers_.size(); ++i) run_analyzer(i, frame);
  }
  stats_.ticks++;
  if (on_tick) {
    if (auto s = on_tick(frame, blackboard_.snapshot()); !s) return s;
  }
  stats_.tick_latency_ms.push_back(ms_since(t_tick));
  return ok_status();
}

Status Pipeline::run(Source& source, const TickCallback& on_tick,
                     const ProgressCallback& on_progress) {
  const auto t0 = Clock::now();
  Status s = options_.sync.policy == SyncPolicy::kSettled
                 ? run_settled(source, on_tick, on_progress)
                 : run_live(source, on_tick, on_progress);
  stats_.wall_seconds = ms_since(t0) / 1000.0;
  return s;
}

Status Pipeline::run_settled(Source& source, const TickCallback& on_tick,
                             const ProgressCallback& on_progress) {
  const auto specs = stream_specs();
  const std::set<SensorId> used = ids_of(specs);
  Synchronizer sync(options_.sync, specs);
  Timestamp first = Timestamp::unset(), last = Timestamp::unset();
  auto drain = [&]() -> Status {
    for (const MultiFrame& mf : sync.poll()) {
      if (!first.is_set()) first = mf.stamp;
      last = mf.stamp;
      if (auto st = process_tick(mf, on_tick); !st) return st;
      if (on_progress) on_progress(mf.stamp);
    }
    return ok_status();
  };
  // Streams the source has not yet said are over (Source::stream_ended).
  std::vector<SensorId> open_streams(used.begin(), used.end());
  auto end_finished_streams = [&] {
    std::erase_if(open_streams, [&](const SensorId& id) {
      if (!source.stream_ended(id)) return false;
      sync.end_stream(id);
      return true;
    });
  };
  while (true) {
    Result<FramePtr> r = source.next();
    if (!r) {
      if (!is_end_of_stream(r.error())) return tl::unexpected(r.error());
      break;
    }
    if (used.count((*r)->sensor) == 0) continue;
    stats_.frames++;
    if (auto st = sync.push(*r); !st) return st;
    end_finished_streams();
    if (auto st = drain(); !st) return st;
  }
  sync.end_all();
  if (auto st = drain(); !st) return st;
  finish_stats(sync, first, last);
  return ok_status();
}

Status Pipeline::run_live(Source& source, const TickCallback& on_tick,
                          const ProgressCallback& on_progress) {
  const auto specs = stream_specs();
  const std::set<SensorId> used = ids_of(specs);
  Synchronizer sync(options_.sync, specs);

  // The reader thread plays the sensors: it releases each frame at its stamp (if pacing).
  std::mutex mutex;
  std::condition_variable cv;
  std::deque<FramePtr> queue;
  bool reader_done = false;
  Status reader_status = ok_status();
  Timestamp media_origin = Timestamp::unset();
  Clock::time_point wall_origin;
  std::atomic<bool> stop{false};
  std::thread reader([&] {
    while (!stop) {
      Result<FramePtr> r = source.next();
      if (!r) {
        std::lock_guard<std::mutex> lock(mutex);
        if (!is_end_of_stream(r.error())) reader_status = tl::unexpected(r.error());
        reader_done = true;
        cv.notify_all();
        return;
      }
      if (stop) return;
      if (used.count((*r)->sensor) == 0) continue;
      {
        std::unique_lock<std::mutex> lock(mutex);
        if (!media_origin.is_set()) {
          media_origin = (*r)->stamp;
          wall_origin = Clock::now();
        }
        if (options_.pace_source) {
          const auto due =
              wall_origin + std::chrono::nanoseconds(((*r)->stamp - media_origin).ns());
          lock.unlock();
          while (!stop && Clock::now() < due)
            std::this_thread::sleep_for(
                std::min<Clock::duration>(due - Clock::now(), std::chrono::milliseconds(20)));
          lock.lock();
        }
        queue.push_back(*r);
      }
      cv.notify_all();
    }
  });

  Status result = ok_status();
  Timestamp first = Timestamp::unset(), last = Timestamp::unset(), newest_seen;
  while (true) {
    std::deque<FramePtr> batch;
    bool done = false;
    {
      std::unique_lock<std::mutex> lock(mutex);
      cv.wait_for(lock, std::chrono::milliseconds(2),
                  [&] { return !queue.empty() || reader_done; });
      batch.swap(queue);
      done = reader_done && batch.empty();
    }
    for (auto& f : batch) {
      stats_.frames++;
      newest_seen = std::max(newest_seen, f->stamp);
      if (auto st = sync.push(f); !st) {
        result = st;
        break;
      }
    }
    if (!result || done) break;
    // Media "now": paced → wall clock mapped onto the session clock; else the newest stamp seen.
    Timestamp now = newest_seen;
    if (options_.pace_source && media_origin.is_set()) {
      std::lock_guard<std::mutex> lock(mutex);
      now = media_origin + Duration::from_ns(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                                 Clock::now() - wall_origin)
                                                 .count());
    }
    for (const MultiFrame& mf : sync.poll(now)) {
      if (!first.is_set()) first = mf.stamp;
      last = mf.stamp;
      result = process_tick(mf, on_tick);
      sync.done();
      if (on_progress) on_progress(mf.stamp);
    }
    if (!result) break;
  }
  stop = true;  // on error the reader exits after its current frame
  reader.join();
  if (result && !reader_status) result = reader_status;
  finish_stats(sync, first, last);
  return result;
}

}  // namespace dreamsense
