// Acoustic-model adaptation (train speech): the sendump decoder on synthetic and packaged files,
// bad requests that must fail before anything is written, and adaptation to one synthetic
// talker (espeak-ng, fixture) that must improve recognition of that talker's unseen utterances.

#include "dreamsense/speech/acoustic_adaptation.hpp"

#include "dreamsense/eval/speech_eval.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <string>
#include <unistd.h>
#include <vector>

#include "sendump.hpp"  // training library internals (include dir set in CMake)

namespace dreamsense::speech {
namespace {
namespace fs = std::filesystem;

fs::path temp_dir(const std::string& name) {
  const fs::path d =
      fs::temp_directory_path() / ("dreamsense_adapt_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// Writes a sendump in PocketSphinx's layout: header strings, then either the dimensions
// (8 bit) or 16 centroids (4 bit), then the per-(feature, density) rows of senone values.
void write_sendump(const fs::path& p, const std::vector<std::string>& header, bool clustered,
                   int densities, int senones, const std::vector<uint8_t>& centroids,
                   const std::vector<uint8_t>& rows) {
  std::ofstream out(p, std::ios::binary);
  auto put32 = [&](int32_t v) { out.write(reinterpret_cast<const char*>(&v), 4); };
  for (const auto& h : header) {
    put32(static_cast<int32_t>(h.size() + 1));
    out.write(h.c_str(), static_cast<std::streamsize>(h.size() + 1));
  }
  put32(0);
  if (clustered) {
    out.write(reinterpret_cast<const char*>(centroids.data()),
              static_cast<std::streamsize>(centroids.size()));
  } else {
    put32(densities);
    put32(senones);
  }
  out.write(reinterpret_cast<const char*>(rows.data()), static_cast<std::streamsize>(rows.size()));
}

TEST(Sendump, DecodesEightBitWeightsAndNormalises) {
  const fs::path d = temp_dir("sendump8");
  // 1 feature, 2 densities, 3 senones. Value v stands for 1.0001^-(v << 10).
  write_sendump(d / "sendump", {"title", "feature_count 1"}, false, 2, 3, {},
                {0, 7, 0,    // density 0 for senones 0, 1, 2
                 0, 0, 7});  // density 1
  auto m = detail::read_sendump(d / "sendump");
  ASSERT_TRUE(m) << m.error().to_string();
  EXPECT_EQ(m->features, 1);
  EXPECT_EQ(m->densities, 2);
  EXPECT_EQ(m->senones, 3);
  const double q = std::pow(1.0001, -7.0 * 1024);  // relative weight of value 7
  EXPECT_NEAR(m->at(0, 0, 0), 0.5, 1e-6);
  EXPECT_NEAR(m->at(1, 0, 0), q / (1 + q), 1e-6);
  EXPECT_NEAR(m->at(1, 0, 1), 1 / (1 + q), 1e-6);
  EXPECT_NEAR(m->at(2, 0, 1), q / (1 + q), 1e-6);
  fs::remove_all(d);
}

TEST(Sendump, DecodesFourBitClusteredWeights) {
  const fs::path d = temp_dir("sendump4");
  std::vector<uint8_t> centroids(16);
  for (int i = 0; i < 16; ++i) centroids[static_cast<size_t>(i)] = static_cast<uint8_t>(3 * i);
  // 3 senones in 2 bytes per row: senone 0 low nibble, senone 1 high nibble, senone 2 low.
  write_sendump(d / "sendump",
                {"title", "feature_count 1", "mixture_count 2", "model_count 3", "cluster_count 16",
                 "cluster_bits 4"},
                true, 2, 3, centroids,
                {0x50, 0x02,    // density 0: senone 0 code 0, senone 1 code 5, senone 2 code 2
                 0x05, 0x00});  // density 1: senone 0 code 5, senone 1 code 0, senone 2 code 0
  auto m = detail::read_sendump(d / "sendump");
  ASSERT_TRUE(m) << m.error().to_string();
  const double w15 = std::pow(1.0001, -15.0 * 1024), w6 = std::pow(1.0001, -6.0 * 1024);
  EXPECT_NEAR(m->at(0, 0, 0), 1 / (1 + w15), 1e-6);  // codes 0 / 5 -> values 0 / 15
  EXPECT_NEAR(m->at(1, 0, 0), w15 / (1 + w15), 1e-6);
  EXPECT_NEAR(m->at(2, 0, 0), w6 / (w6 + 1), 1e-6);  // code 2 -> value 6 vs value 0
  fs::remove_all(d);
}

TEST(Sendump, RejectsTruncatedAndForeignFiles) {
  const fs::path d = temp_dir("sendump_bad");
  write_sendump(d / "short", {"title", "feature_count 1"}, false, 2, 3, {}, {0, 0, 0});
  auto m = detail::read_sendump(d / "short");
  ASSERT_FALSE(m);
  EXPECT_NE(m.error().message.find("truncated"), std::string::npos) << m.error().message;
  std::ofstream(d / "text") << "this is not a sendump at all\n";
  EXPECT_FALSE(detail::read_sendump(d / "text"));
  EXPECT_FALSE(detail::read_sendump(d / "missing"));
  fs::remove_all(d);
}

TEST(Sendump, ReadsThePackagedModelsAndWritesSphinxTrainFormat) {
  struct Model {
    fs::path sendump;
    int features;
  };
  const std::vector<Model> models = {{kTidigitsModel / "sendump", 4},  // semi-continuous, 4 bit
                                     {"/usr/share/pocketsphinx/model/en-us/en-us/sendump", 3}};
  for (const auto& [path, features] : models) {
    if (!fs::exists(path)) GTEST_SKIP() << path << " not installed";
    auto m = detail::read_sendump(path);
    ASSERT_TRUE(m) << m.error().to_string();
    EXPECT_EQ(m->features, features) << path;
    for (int s = 0; s < m->senones; s += 97) {
      double sum = 0;
      for (int k = 0; k < m->densities; ++k) sum += m->at(s, 0, k);
      EXPECT_NEAR(sum, 1.0, 1e-4) << path << " senone " << s;
    }
    const fs::path d = temp_dir("mixw");
    ASSERT_TRUE(detail::write_mixture_weights(*m, d / "mixture_weights"));
    const std::string header = "s3\nversion 1.0\nendhdr\n";
    EXPECT_EQ(fs::file_size(d / "mixture_weights"),
              header.size() + 4 + 16 + m->weights.size() * sizeof(float));
    fs::remove_all(d);
  }
}

bool have_adaptation_tools() {
  return ::access("/usr/lib/sphinxtrain/bw", X_OK) == 0 &&
         ::access("/usr/lib/sphinxtrain/map_adapt", X_OK) == 0 &&
         ::access("/usr/bin/pocketsphinx_mdef_convert", X_OK) == 0 &&
         fs::exists(kTidigitsModel / "mdef");
}

AcousticAdaptationOptions tidigits_options() {
  SpeechEvalOptions eo;
  auto f = fsdd_recognizer(eo);
  AcousticAdaptationOptions o;
  if (f) o.recognizer = f->options;
  o.min_utterances = 2;
  return o;
}

std::vector<AdaptationUtterance> tone_utterances(int n, const std::string& words) {
  std::vector<AdaptationUtterance> u;
  for (int i = 0; i < n; ++i) {
    AdaptationUtterance a{std::to_string(i), std::vector<int16_t>(8000), 8000, words};
    a.id.insert(0, 1, 'u');  // (not "u" + ...: GCC 12 -Wrestrict false positive)
    for (size_t k = 0; k < a.samples.size(); ++k)
      a.samples[k] = static_cast<int16_t>(3000 * std::sin(0.3 * static_cast<double>(k)));
    u.push_back(std::move(a));
  }
  return u;
}

TEST(AcousticAdaptation, BadRequestsFailBeforeWritingAnything) {
  if (!fs::exists(kTidigitsModel / "mdef")) GTEST_SKIP() << "pocketsphinx-testdata missing";
  const fs::path d = temp_dir("bad");
  const fs::path out = d / "model";
  auto o = tidigits_options();
  auto expect_error = [&](std::vector<AdaptationUtterance> u, const AcousticAdaptationOptions& opt,
                          const std::string& needle) {
    auto r = adapt_acoustic_model(u, opt, out);
    ASSERT_FALSE(r) << needle;
    EXPECT_NE(r.error().message.find(needle), std::string::npos) << r.error().message;
    EXPECT_FALSE(fs::exists(out)) << needle;
  };
  expect_error(tone_utterances(1, "one"), o, "at least 2 utterances");
  expect_error(tone_utterances(3, "one elephant"), o, "elephant");
  auto twice = tone_utterances(3, "one");
  twice[2].id = "u0";
  expect_error(twice, o, "used twice");
  auto bad_id = tone_utterances(3, "one");
  bad_id[1].id = "../escape";
  expect_error(bad_id, o, "../escape");
  auto no_words = tone_utterances(3, "one");
  no_words[0].words = "  ";
  expect_error(no_words, o, "no words");
  auto no_tools = o;
  no_tools.sphinxtrain_dir = d / "nowhere";
  expect_error(tone_utterances(3, "one"), no_tools, "sphinxtrain");
  auto no_model = o;
  no_model.recognizer.model_dir = d / "no_model";
  expect_error(tone_utterances(3, "one"), no_model, "no_model");
  // An existing, non-empty folder is never written into.
  fs::create_directories(out);
  std::ofstream(out / "keep.txt") << "data";
  auto r = adapt_acoustic_model(tone_utterances(3, "one"), o, out);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("not empty"), std::string::npos) << r.error().message;
  EXPECT_TRUE(fs::exists(out / "keep.txt"));
  EXPECT_FALSE(fs::exists(out / "means"));
  fs::remove_all(d);
}

// Accuracy of a model folder on FSDD-layout items (closed digit set, as eval speech).
double digit_accuracy(const fs::path& data, const FsddSelection& sel, const std::string& model) {
  SpeechEvalOptions eo;
  eo.dataset = "fsdd";
  eo.dir = data;
  eo.fsdd = sel;
  eo.fsdd_model = model;
  eo.list_items = false;
  auto r = run_speech_eval(eo);
  EXPECT_TRUE(r) << r.error().to_string();
  return r ? r->to_json()["metrics"]["accuracy"].get<double>() : -1;
}

// One espeak-ng talker (fixture speech_synth_talker): adapting the TIDIGITS model on 10 of their
// takes per digit must raise the accuracy on their other 6 takes per digit.
TEST(AcousticAdaptation, AdaptingToATalkerImprovesTheirUnseenUtterances) {
  const fs::path data = fs::path(DREAMSENSE_BINARY_DIR) / "test_data" / "espeak_talker";
  if (!fs::exists(data / "recordings")) GTEST_SKIP() << "no synthetic talker (espeak-ng missing)";
  if (!have_adaptation_tools()) GTEST_SKIP() << "sphinxtrain / pocketsphinx tools missing";
  FsddSelection train, test;
  train.first_index = 6;
  train.last_index = 15;
  test.first_index = 0;
  test.last_index = 5;
  auto items = load_fsdd(data, train);
  ASSERT_TRUE(items) << items.error().to_string();
  ASSERT_EQ(items->size(), 100u);
  auto o = tidigits_options();
  auto utterances = fsdd_enrolment(*items);
  ASSERT_TRUE(utterances) << utterances.error().to_string();
  const fs::path d = temp_dir("talker");
  auto r = adapt_acoustic_model(*utterances, o, d / "model");
  ASSERT_TRUE(r) << r.error().to_string();
  EXPECT_EQ(r->utterances, 100);
  EXPECT_GE(r->trained_utterances, 95);
  EXPECT_TRUE(fs::exists(d / "model" / kAdaptationFileName));
  EXPECT_FALSE(fs::exists(d / "model" / "work"));
  // Only the means change.
  auto bytes = [](const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  };
  EXPECT_NE(bytes(d / "model" / "means"), bytes(kTidigitsModel / "means"));
  EXPECT_EQ(bytes(d / "model" / "sendump"), bytes(kTidigitsModel / "sendump"));

  const double before = digit_accuracy(data, test, "tidigits");
  const double after = digit_accuracy(data, test, (d / "model").string());
  RecordProperty("accuracy_before", std::to_string(before));
  RecordProperty("accuracy_after", std::to_string(after));
  EXPECT_GE(after, before + 0.05) << "before " << before << " after " << after;
  fs::remove_all(d);
}

}  // namespace
}  // namespace dreamsense::speech
