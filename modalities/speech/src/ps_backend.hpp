#pragma once
// The only code that includes PocketSphinx/sphinxbase headers. Kept apart from OpenCV-using
// code because sphinxbase's prim_type.h and OpenCV's hal/interface.h both typedef int64/uint64
// differently, so the two cannot be included in one translation unit.

#include "dreamsense/core/status.hpp"

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace dreamsense::speech::detail {

struct PsPass {
  std::string hyp;  // grammar words (empty if nothing or if the garbage branch won)
  int32_t score = 0;
  int first = -1, last = -1;  // frames of the grammar words
  bool any_word = false;      // any non-filler word (grammar or garbage)
};

struct PsConfig {
  std::string model_dir, dictionary;
  std::string means_file;  // -mean over the model's own means (empty = the model's)
  int rate_hz = 16000;
  double upper_hz = 0;  // 0 = the model's feat.params
  bool remove_silence = true, remove_noise = true;
  std::string jsgf, source;
  bool reject = true;
  double garbage_phone_weight = 1.0;
  double frequency_warp = 1.0;  // 1 = off
  std::string mfc_log_dir;      // -mfclogdir (empty = off)
};

// What PsDecoder::create does to a grammar before it loads a model: JSGF text -> sphinxbase FSG
// text (sphinxbase's compiler; errors name `source`), re-read, plus the garbage loop over
// `garbage_phones` when not empty. Without a model (tests, fuzz/fuzz_jsgf.cpp).
Result<std::string> compile_jsgf(const std::string& jsgf, const std::string& source,
                                 const std::vector<std::string>& garbage_phones);

class PsDecoder {
 public:
  static Result<std::unique_ptr<PsDecoder>> create(const PsConfig& config);
  ~PsDecoder();
  // Decodes the whole utterance with the grammar (+ garbage branch if reject) or with the
  // garbage branch alone.
  Result<PsPass> run(bool garbage_only, std::span<const int16_t> samples);

 private:
  PsDecoder() = default;
  void* ps_ = nullptr;  // ps_decoder_t
};

}  // namespace dreamsense::speech::detail
