#pragma once
// Sound-direction analyser (DREAM V17 / primitive F16 getSoundDirection): reads the audio chunks
// of one microphone-array stream, runs the DirectionFinder and writes keys::kSoundDirection once
// per tick in which at least one analysis frame completed: the smoothed estimate when the last
// frame was voiced, an absent entry (silence) otherwise. Method and numbers: README.md.
//
// Bad input: chunks whose sample rate or channel count differ from the configured array are an
// error for that tick (clear message, the pipeline keeps running); clipped audio is processed
// with a one-time warning; silence is absence, never an error.

#include "dreamsense/audio/mic_array.hpp"
#include "dreamsense/audio/reference_gate.hpp"
#include "dreamsense/core/analyzer.hpp"
#include "dreamsense/sound_direction/direction_finder.hpp"

#include <memory>

namespace dreamsense::sound_direction {

struct SoundDirectionAnalyzerOptions {
  SensorId audio_sensor = "mic_array";
  MicArrayGeometry geometry = MicArrayGeometry::kinect_v1();
  DirectionFinderOptions finder;
  // The robot's own voice (issue 16): no direction while the reference stream its loudspeaker
  // plays (role robot_audio; empty: none) says the robot is audible (audio/reference_gate.hpp).
  SensorId reference_sensor;
  audio::ReferenceGateOptions robot_gate;
  Status check() const;
};

Result<std::unique_ptr<Analyzer>> make_sound_direction_analyzer(
    const SoundDirectionAnalyzerOptions& options);

}  // namespace dreamsense::sound_direction
