#pragma once
// A Source yields timestamped sensor frames: a recorded session or live devices, same interface.

#include "dreamsense/core/sensor_frame.hpp"
#include "dreamsense/core/status.hpp"

#include <optional>
#include <string>
#include <vector>

namespace dreamsense {

struct SensorDescription {
  SensorId id;
  SensorKind kind = SensorKind::kColor;
  double rate_hz = 0;         // nominal frame rate (audio: chunks per second)
  int width = 0, height = 0;  // images
  int sample_rate = 0;        // audio
  int channels = 0;           // audio
  std::string calibration;    // path of the calibration file, if any
  std::string frame;          // name of the sensor's frame in the transform tree
};

struct SourceInfo {
  std::vector<SensorDescription> sensors;
  Timestamp start = Timestamp::unset();  // first stamp, if known
  Timestamp end = Timestamp::unset();    // last stamp, if known (recordings)
  bool live = false;
  const SensorDescription* find(const SensorId& id) const {
    for (const auto& s : sensors)
      if (s.id == id) return &s;
    return nullptr;
  }
};

class Source {
 public:
  virtual ~Source() = default;
  // The next frame in stamp order across all streams. At the end: an Error with
  // ErrorCode::kEndOfStream. Any other error is real (corrupt or missing data).
  virtual Result<FramePtr> next() = 0;
  virtual SourceInfo info() const = 0;
  // True once next() will return no more frames of stream `id` (a recording's stream that ends
  // before the others, or has none). Settled replay then stops waiting for that stream, instead
  // of holding every later frame of the other streams until the whole source ends (issue 18).
  // The default, false until the end, is always correct.
  virtual bool stream_ended(const SensorId& /*id*/) const { return false; }
};

inline bool is_end_of_stream(const Error& e) { return e.code == ErrorCode::kEndOfStream; }

}  // namespace dreamsense
