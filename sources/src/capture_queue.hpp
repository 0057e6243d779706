#pragma once
// The hand-over between a live device's capture thread and the pipeline's next(): a bounded
// queue that drops the oldest frame when the consumer falls behind (live data must stay current;
// the drop is counted by the caller), and the end of capture (stopped, or an error that next()
// reports once before end-of-stream). Used by CameraSource and AlsaAudioSource.

#include "dreamsense/core/sensor_frame.hpp"
#include "dreamsense/core/status.hpp"

#include <condition_variable>
#include <deque>
#include <mutex>
#include <optional>
#include <string>

namespace dreamsense::sources::detail {

class CaptureQueue {
 public:
  explicit CaptureQueue(size_t capacity) : capacity_(capacity) {}

  // Capture thread: appends a frame; returns how many old frames were dropped to make room.
  size_t push(FramePtr frame) {
    size_t dropped = 0;
    {
      std::lock_guard lock(mutex_);
      queue_.push_back(std::move(frame));
      for (; queue_.size() > capacity_; ++dropped) queue_.pop_front();
    }
    cv_.notify_all();
    return dropped;
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
  // (once), then kEndOfStream "<what>: capture stopped".
  Result<FramePtr> pop(const std::string& what) {
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
    return make_error(ErrorCode::kEndOfStream, "{}: capture stopped", what);
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
