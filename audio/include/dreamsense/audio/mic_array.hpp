#pragma once
// Microphone array geometry: mic positions in the array frame, sample rate and extrinsics.
//
// Array frame convention (as docs/truth_format.md): x along the array (Kinect: channel 1 at +x),
// y down, z forward (broadside). Azimuth 0 = +z, positive towards +x; elevation positive upwards
// (towards -y). Extrinsics are array_from_world: X_array = R * X_world + t (metres), as
// calib/mic_array.yaml.

#include "dreamsense/core/status.hpp"

#include <opencv2/core.hpp>

#include <filesystem>
#include <vector>

namespace dreamsense::audio {

struct MicArrayGeometry {
  std::vector<cv::Vec3d> mics_m;  // one per channel, channel order, array frame (metres)
  int sample_rate = 16000;        // Hz
  cv::Matx33d array_from_world_R = cv::Matx33d::eye();
  cv::Vec3d array_from_world_t{0, 0, 0};

  // Kinect v1: four mics on the x axis at +113, -36, -76, -113 mm, 16 kHz, identity extrinsics.
  static MicArrayGeometry kinect_v1();
  // Rank of the mic layout: 1 = linear (azimuth only, front/back ambiguous), 2 = planar,
  // 3 = volumetric. Mics closer than 1 mm to the fitted line/plane count as on it.
  int rank() const;
  // Unit vector of a direction given in the array frame, rotated into world.
  cv::Vec3d to_world_direction(const cv::Vec3d& array_dir) const {
    return array_from_world_R.t() * array_dir;
  }
  // At least two distinct mics, sample rate in [8000, 192000], R a rotation; a linear array must
  // lie along the array frame's x axis (the azimuth grid is in the x-z plane).
  Status check() const;
};

// Names the geometry from CLI flags: "kinect1" (the only built-in one for now).
Result<MicArrayGeometry> named_geometry(const std::string& name);

// Reads calib/<stream>.yaml as written by the demo session: sample_rate, mic_positions_m (Nx3),
// array_from_world_R (3x3), array_from_world_t (3x1). Missing extrinsics default to identity.
Result<MicArrayGeometry> read_mic_array(const std::filesystem::path& path);

}  // namespace dreamsense::audio
