#pragma once
// The hand-over between a live device's capture thread and the pipeline's next(): a bounded
// queue that drops the oldest frame when the consumer falls behind (live data must stay current;
// the drop is counted by the caller), and the end of capture (stopped, or an error that next()
// reports once before end-of-stream). Used by CameraSource, AlsaAudioSource and LiveCapture
// (which merges all devices into one queue).

#include "dreamsense/core/sensor_frame.hpp"
#include "dreamsense/core/status.hpp"

#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace dreamsense::sources::detail {

class CaptureQueue {
 public:
  explicit CaptureQueue(size_t capacity) : capacity_(capacity) {}

  // Capture thread: appends a frame; returns how many old frames were dropped to make room,
  // each also handed to `on_drop` (after the queue's lock is released) for per-sensor counts.
  size_t push(FramePtr frame, const std::function<void(const FramePtr&)>& on_drop = {}) {
    std::vector<FramePtr> dropped;
    {
      std::lock_guard lock(mutex_);
      queue_.push_back(std::move(frame));
      for (; queue_.size() > capacity_; queue_.pop_front()) dropped.push_back(queue_.front());
    }
    cv_.notify_all();
    if (on_drop)
      for (const auto& f : dropped) on_drop(f);
    return dropped.size();
  }

  // Capture thread: no more frames; `error` says why when capture did not simply stop.
  void finish(std::optional<Error> error) {
    {
      std::lock_guard lock(mutex_);
      done_ = true;
      error_ = std::move(error);
    }
    cv_.notify_all();
  }

  // Consumer: the oldest frame, waiting for one. After finish() and the last frame: the error
  // (once), then kEndOfStream with `end_message`.
  Result<FramePtr> pop(const std::string& end_message) {
    std::unique_lock lock(mutex_);
    cv_.wait(lock, [&] { return !queue_.empty() || done_; });
    if (!queue_.empty()) {
      FramePtr f = std::move(queue_.front());
      queue_.pop_front();
      return f;
    }
    if (error_ && !error_reported_) {
      error_reported_ = true;
      return tl::unexpected(*error_);
    }
    return make_error(ErrorCode::kEndOfStream, "{}", end_message);
  }

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<FramePtr> queue_;
  size_t capacity_;
  bool done_ = false;
  std::optional<Error> error_;
  bool error_reported_ = false;
};

}  // namespace dreamsense::sources::detail
