#pragma once
// Skeletons from an external body tracker, live, over UDP (docs/recording.md "Skeletons from a
// body tracker"): every datagram is one frame as a line of a session's skeleton stream
// (sources/skeleton_json.hpp: {"bodies": [{"id": 1, "joints": {"head": [x, y, z, c], ...}}]},
// metres in the tracker's sensor frame). Any tracker (OpenNI2/NiTE, a Kinect SDK bridge, a
// camera pose estimator) can feed getBody, getBodyPose, identifyTrajectory, ... this way.
//
// Stamps are the arrival time on the capture clock (steady clock since clock_origin), like the
// cameras' frames; a stamp_ns the sender puts in is ignored (its clock is not ours). A datagram
// that does not parse costs that frame: it is counted (bad_datagrams) and logged (the first few),
// never an error of the stream. Binds 127.0.0.1 by default (network exposure is opt-in).

#include "dreamsense/core/source.hpp"
#include "dreamsense/core/status.hpp"

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

namespace dreamsense::sources {

struct UdpSkeletonSourceOptions {
  SensorId sensor = "front.skeleton";
  std::string host = "127.0.0.1";  // address to listen on
  int port = 0;                    // 0: any free port (see port())
  double rate_hz = 30;             // the tracker's nominal rate (for the manifest)
  std::chrono::steady_clock::time_point clock_origin = std::chrono::steady_clock::now();
  Status check() const;
};

struct UdpSkeletonStats {
  uint64_t frames = 0;
  uint64_t bad_datagrams = 0;
};

class UdpSkeletonSource : public Source {
 public:
  // Binds the socket (an error naming host:port when it cannot).
  static Result<std::unique_ptr<UdpSkeletonSource>> open(const UdpSkeletonSourceOptions& options);
  ~UdpSkeletonSource() override;
  UdpSkeletonSource(const UdpSkeletonSource&) = delete;
  UdpSkeletonSource& operator=(const UdpSkeletonSource&) = delete;
  // Blocks until a valid datagram arrives; after stop(): kEndOfStream.
  Result<FramePtr> next() override;
  SourceInfo info() const override;
  void stop();       // thread-safe
  int port() const;  // the bound port
  UdpSkeletonStats stats() const;

 private:
  struct Impl;
  explicit UdpSkeletonSource(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace dreamsense::sources
