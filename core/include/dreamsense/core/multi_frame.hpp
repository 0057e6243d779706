#pragma once
// The synchronised set of sensor frames for one tick of the pipeline clock.

#include "dreamsense/core/sensor_frame.hpp"

#include <map>
#include <vector>

namespace dreamsense {

struct MultiFrame {
  Timestamp stamp;    // the tick time
  uint64_t tick = 0;  // tick index since the start of the run
  // Frame streams (cameras, depth, skeleton): the frame matched to this tick, if any.
  std::map<SensorId, FramePtr> frames;
  // Continuous streams (audio): every chunk whose first sample falls in (previous tick, tick].
  std::map<SensorId, std::vector<FramePtr>> chunks;

  FramePtr frame(const SensorId& id) const {
    auto it = frames.find(id);
    return it == frames.end() ? nullptr : it->second;
  }
  const std::vector<FramePtr>& chunks_of(const SensorId& id) const;
  bool has(const SensorId& id) const { return frames.count(id) > 0 || chunks.count(id) > 0; }
};

}  // namespace dreamsense
