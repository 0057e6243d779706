#pragma once
// `dreamsense train voices` and `dreamsense eval voices`: speaker identification on a dataset
// with one label per recording, JSON of spec/cli.md (task "voices").
//
// Layouts (--dataset NAME DIR):
//  - fsdd: Free Spoken Digit Dataset, DIR/{digit}_{speaker}_{index}.wav (or DIR/recordings/...);
//    each speaker's recordings in order of (index, digit), so the first 10 are the ten digits
//    of take 0.
//  - folders: DIR/<speaker>/*.wav (any audio libsndfile reads, or 16 kHz s16le .raw), each
//    speaker's recordings in file-name order.
// Enrolment is deterministic: the first N recordings of each speaker; the rest are tests.

#include "dreamsense/eval/report.hpp"
#include "dreamsense/voice_id/voice_model.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace dreamsense::voice_id {

struct VoiceDataset {
  std::string name;  // fsdd | folders
  std::filesystem::path dir;
  // Recordings per speaker, in protocol order.
  std::map<std::string, std::vector<LabelledAudio>> speakers;
  size_t recordings() const;
};

// Loads a dataset layout; `only` (optional) keeps those speakers (error if one is absent).
Result<VoiceDataset> load_voice_dataset(const std::string& name, const std::filesystem::path& dir,
                                        const std::vector<std::string>& only = {});

struct VoiceTrainRunOptions {
  std::string dataset = "folders";
  std::filesystem::path dir;
  std::vector<std::string> speakers;  // empty: all of the dataset
  int enroll = 0;                     // first N recordings per speaker; 0: all of them
  // Background (UBM) audio: every audio file under this folder. Empty: the enrolment
  // recordings of all speakers pooled (no outside data needed; the UBM then describes exactly
  // the population the open-set threshold separates).
  std::filesystem::path background;
  VoiceTrainOptions train;
  Status check() const;
};

Result<VoiceModel> run_voice_train(const VoiceTrainRunOptions& options,
                                   const std::function<void(double)>& progress = {});

struct VoiceEvalOptions {
  std::string dataset = "fsdd";
  std::filesystem::path dir;
  std::vector<std::string> speakers;  // empty: all
  std::vector<std::string> unknown;   // held out of enrolment; all their recordings are tests
  // The first N recordings of each speaker enrol (with `model`: are skipped, as the model was
  // presumably enrolled on them; 0 = test on everything); the rest are tests.
  int enroll = 10;
  // A model from `train voices`: no enrolment here; dataset speakers the model does not know
  // count as unknown speakers.
  std::filesystem::path model;
  std::filesystem::path background;  // as VoiceTrainRunOptions::background
  VoiceTrainOptions train;
  Status check() const;
};

// Metrics: accuracy (closed set: the best-scoring enrolled speaker is the truth, over the known
// speakers' test recordings), open_set_accuracy (also above the threshold), false_reject_rate
// (known test recordings called unknown), unknown_reject_rate (the unknown speakers' recordings
// called unknown; only with unknown speakers). per_class: recall per speaker; confusion (rows =
// truth, closed-set answers); timing: ms_per_utterance_median, train_s.
Result<eval::EvalReport> run_voice_eval(const VoiceEvalOptions& options,
                                        const std::function<void(double)>& progress = {});

}  // namespace dreamsense::voice_id
