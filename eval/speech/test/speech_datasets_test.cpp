// Layout loaders of `eval speech` (fsdd, speech-commands), including bad input.
#include "dreamsense/eval/speech_datasets.hpp"

#include "dreamsense/eval/speech_eval.hpp"

#include <gtest/gtest.h>
#include <sndfile.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace dreamsense::speech {
namespace {

namespace fs = std::filesystem;

class TempDir {
 public:
  TempDir() {
    path_ = fs::temp_directory_path() /
            ("ds_speech_datasets_" + std::to_string(getpid()) + "_" + std::to_string(counter_++));
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
  static inline int counter_ = 0;
};

// A short tone, `channels` interleaved copies.
void write_wav(const fs::path& p, int rate, int channels = 1, double seconds = 0.25) {
  fs::create_directories(p.parent_path());
  SF_INFO info{};
  info.samplerate = rate;
  info.channels = channels;
  info.format = SF_FORMAT_WAV | SF_FORMAT_PCM_16;
  SNDFILE* sf = sf_open(p.string().c_str(), SFM_WRITE, &info);
  ASSERT_NE(sf, nullptr) << p;
  const auto n = static_cast<size_t>(seconds * rate);
  std::vector<int16_t> s(n * static_cast<size_t>(channels));
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < channels; ++c)
      s[i * static_cast<size_t>(channels) + static_cast<size_t>(c)] =
          static_cast<int16_t>(8000 * std::sin(2 * M_PI * 300 * static_cast<double>(i) / rate));
  sf_write_short(sf, s.data(), static_cast<sf_count_t>(s.size()));
  sf_close(sf);
}

void make_commands_layout(const fs::path& d, int per_class = 1) {
  for (const char* w : kCommandWords)
    for (int i = 0; i < per_class; ++i) write_wav(d / w / (std::to_string(i) + ".wav"), 16000);
  for (const char* w : {kUnknownLabel, kSilenceLabel})
    for (int i = 0; i < per_class; ++i) write_wav(d / w / (std::to_string(i) + ".wav"), 16000);
}

TEST(FsddLoader, ListsRecordingsSortedAndSelects) {
  TempDir t;
  const fs::path rec = t.path() / "recordings";
  for (const char* name : {"3_theo_1.wav", "0_theo_0.wav", "9_lucas_12.wav", "3_theo_0.wav"})
    write_wav(rec / name, 8000);
  { std::ofstream(rec / "README.md") << "not audio"; }
  auto all = load_fsdd(t.path());
  ASSERT_TRUE(all) << all.error().to_string();
  ASSERT_EQ(all->size(), 4u);
  EXPECT_EQ((*all)[0].speaker, "lucas");
  EXPECT_EQ((*all)[0].label, "9");
  EXPECT_EQ((*all)[0].index, 12);
  EXPECT_EQ((*all)[1].path.filename(), "0_theo_0.wav");
  EXPECT_EQ((*all)[3].path.filename(), "3_theo_1.wav");

  // The folder holding the WAVs directly works too; speaker and index selection.
  FsddSelection sel;
  sel.speakers = {"theo"};
  sel.first_index = 0;
  sel.last_index = 0;
  auto some = load_fsdd(rec, sel);
  ASSERT_TRUE(some) << some.error().to_string();
  ASSERT_EQ(some->size(), 2u);
  for (const auto& it : *some) {
    EXPECT_EQ(it.speaker, "theo");
    EXPECT_EQ(it.index, 0);
  }

  auto audio = read_mono_wav((*all)[0].path, 8000, "fsdd");
  ASSERT_TRUE(audio) << audio.error().to_string();
  EXPECT_EQ(audio->rate_hz, 8000);
  EXPECT_EQ(audio->samples.size(), 2000u);
}

TEST(FsddLoader, BadInputGivesClearMessages) {
  TempDir t;
  auto missing = load_fsdd(t.path() / "nope");
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().code, ErrorCode::kNotFound);
  EXPECT_NE(missing.error().message.find("not a folder"), std::string::npos);

  auto empty = load_fsdd(t.path());
  ASSERT_FALSE(empty);
  EXPECT_NE(empty.error().message.find("DIGIT_SPEAKER_INDEX.wav"), std::string::npos)
      << empty.error().message;

  write_wav(t.path() / "1_ann_0.wav", 8000);
  FsddSelection sel;
  sel.speakers = {"bob"};
  auto unknown = load_fsdd(t.path(), sel);
  ASSERT_FALSE(unknown);
  EXPECT_NE(unknown.error().message.find("speaker bob"), std::string::npos);
  EXPECT_NE(unknown.error().message.find("ann"), std::string::npos) << "lists who is there";

  {
    TempDir w;
    write_wav(w.path() / "1_ann_0.wav", 16000);
    auto wrong_rate = load_fsdd(w.path());
    ASSERT_FALSE(wrong_rate);
    EXPECT_EQ(wrong_rate.error().code, ErrorCode::kUnsupported);
    EXPECT_NE(wrong_rate.error().message.find("1_ann_0.wav"), std::string::npos);
    EXPECT_NE(wrong_rate.error().message.find("16000 Hz"), std::string::npos);
    EXPECT_NE(wrong_rate.error().message.find("8000 Hz"), std::string::npos)
        << wrong_rate.error().message;
  }
  {
    TempDir w;
    write_wav(w.path() / "1_ann_0.wav", 8000, 2);
    auto stereo = load_fsdd(w.path());
    ASSERT_FALSE(stereo);
    EXPECT_NE(stereo.error().message.find("2 channels"), std::string::npos)
        << stereo.error().message;
  }
  {
    TempDir w;
    write_wav(w.path() / "one_ann.wav", 8000);
    auto badname = load_fsdd(w.path());
    ASSERT_FALSE(badname);
    EXPECT_NE(badname.error().message.find("one_ann.wav"), std::string::npos);
  }
  {
    TempDir w;
    std::ofstream(w.path() / "1_ann_0.wav") << "RIFF but not really";
    auto corrupt = load_fsdd(w.path());
    ASSERT_FALSE(corrupt);
    EXPECT_EQ(corrupt.error().code, ErrorCode::kCorruptData);
  }
}

TEST(SpeechCommandsLoader, TwelveClassesAndOtherWordsAreUnknown) {
  TempDir t;
  make_commands_layout(t.path(), 2);
  write_wav(t.path() / "marvin" / "a.wav", 16000);              // training-set layout: another word
  write_wav(t.path() / "_background_noise_" / "n.wav", 16000);  // ignored
  auto items = load_speech_commands(t.path());
  ASSERT_TRUE(items) << items.error().to_string();
  EXPECT_EQ(items->size(), 12u * 2 + 1);
  size_t unknown = 0, silence = 0, yes = 0;
  for (const auto& it : *items) {
    unknown += it.label == kUnknownLabel;
    silence += it.label == kSilenceLabel;
    yes += it.label == "yes";
  }
  EXPECT_EQ(unknown, 3u);
  EXPECT_EQ(silence, 2u);
  EXPECT_EQ(yes, 2u);
}

TEST(SpeechCommandsLoader, BadInputGivesClearMessages) {
  TempDir t;
  auto missing = load_speech_commands(t.path() / "nope");
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("not a folder"), std::string::npos);

  make_commands_layout(t.path());
  fs::remove_all(t.path() / "_silence_");
  fs::remove_all(t.path() / "up");
  auto lacking = load_speech_commands(t.path());
  ASSERT_FALSE(lacking);
  EXPECT_EQ(lacking.error().code, ErrorCode::kNotFound);
  EXPECT_NE(lacking.error().message.find("_silence_"), std::string::npos);
  EXPECT_NE(lacking.error().message.find("up"), std::string::npos) << lacking.error().message;

  {
    TempDir w;
    make_commands_layout(w.path());
    write_wav(w.path() / "go" / "narrow.wav", 8000);
    auto rate = load_speech_commands(w.path());
    ASSERT_FALSE(rate);
    EXPECT_EQ(rate.error().code, ErrorCode::kUnsupported);
    EXPECT_NE(rate.error().message.find("narrow.wav"), std::string::npos);
    EXPECT_NE(rate.error().message.find("16000 Hz"), std::string::npos) << rate.error().message;
  }
  {
    TempDir w;
    make_commands_layout(w.path());
    write_wav(w.path() / "_silence_" / "stereo.wav", 16000, 2);
    auto stereo = load_speech_commands(w.path());
    ASSERT_FALSE(stereo);
    EXPECT_NE(stereo.error().message.find("mono"), std::string::npos) << stereo.error().message;
  }
  {
    TempDir w;  // all twelve folders, no audio
    for (const char* c : kCommandWords) fs::create_directories(w.path() / c);
    fs::create_directories(w.path() / kUnknownLabel);
    fs::create_directories(w.path() / kSilenceLabel);
    auto empty = load_speech_commands(w.path());
    ASSERT_FALSE(empty);
    EXPECT_NE(empty.error().message.find("no .wav"), std::string::npos);
  }
}

TEST(UtteranceList, ReadsRelativeAudioCommentsAndRejectMarks) {
  TempDir t;
  write_wav(t.path() / "audio" / "a.wav", 16000);
  write_wav(t.path() / "audio" / "b.wav", 8000);
  std::ofstream(t.path() / "list.txt") << "# enrolment\n"
                                       << "audio/a.wav  ten of  clubs  # first take\n"
                                       << "\n"
                                       << "audio/b.wav -\n";
  auto eval = load_utterance_list(t.path() / "list.txt", true);
  ASSERT_TRUE(eval) << eval.error().to_string();
  ASSERT_EQ(eval->size(), 2u);
  EXPECT_EQ((*eval)[0].audio, t.path() / "audio" / "a.wav");
  EXPECT_EQ((*eval)[0].words, "ten of clubs");
  EXPECT_EQ((*eval)[0].line, 2);
  EXPECT_FALSE((*eval)[0].reject);
  EXPECT_TRUE((*eval)[1].reject);
  EXPECT_EQ((*eval)[1].words, "");
  EXPECT_EQ((*eval)[1].line, 4);
  auto audio = read_utterance_audio((*eval)[1].audio);
  ASSERT_TRUE(audio) << audio.error().to_string();
  EXPECT_EQ(audio->rate_hz, 8000);

  // Training lists need words on every line.
  auto train = load_utterance_list(t.path() / "list.txt", false);
  ASSERT_FALSE(train);
  EXPECT_NE(train.error().message.find("list.txt:4"), std::string::npos) << train.error().message;
}

TEST(UtteranceList, BadListsNameFileAndLine) {
  TempDir t;
  write_wav(t.path() / "a.wav", 16000);
  auto error_of = [&](const std::string& text) {
    std::ofstream(t.path() / "l.txt") << text;
    auto r = load_utterance_list(t.path() / "l.txt", true);
    return r ? std::string("no error") : r.error().message;
  };
  EXPECT_NE(error_of("a.wav one\nmissing.wav two\n").find("l.txt:2: audio file"),
            std::string::npos);
  EXPECT_NE(error_of("a.wav\n").find("l.txt:1: expected"), std::string::npos);
  EXPECT_NE(error_of("# only a comment\n").find("no utterances"), std::string::npos);
  EXPECT_FALSE(load_utterance_list(t.path() / "nothing.txt", true));
  EXPECT_FALSE(load_utterance_list(t.path(), true));  // a folder
}

TEST(SpeechEval, UnknownLayoutAndBadOptions) {
  SpeechEvalOptions o;
  o.dataset = "timit";
  auto r = run_speech_eval(o);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().code, ErrorCode::kUnsupported);
  EXPECT_NE(r.error().message.find("speech-commands"), std::string::npos);

  o.dataset = "fsdd";
  o.fsdd_model = "whisper";
  TempDir t;
  write_wav(t.path() / "1_ann_0.wav", 8000);
  o.dir = t.path();
  auto m = run_speech_eval(o);
  ASSERT_FALSE(m);
  EXPECT_NE(m.error().message.find("tidigits, en-us or a TIDIGITS-family model folder"),
            std::string::npos)
      << m.error().message;

  RecognizerOptions ro;
  ro.front_end_rate_hz = 8000;  // needs an upper filter edge below 4 kHz
  EXPECT_FALSE(ro.check());
  ro.front_end_upper_hz = 3800;
  EXPECT_TRUE(ro.check());
  ro.front_end_upper_hz = 4000;
  EXPECT_FALSE(ro.check());
}

}  // namespace
}  // namespace dreamsense::speech

namespace dreamsense::speech {
namespace {

// The shipped speech-commands model: decoys read, means-only folder decoded over its base model
// (a regression: the folder argument aliased options.model_dir and the base's own means were
// read instead).
TEST(SpeechCommandsModel, ShippedFolderIsMeansOnlyOverEnUsWithDecoys) {
  const fs::path dir = commands_model_dir();
  ASSERT_TRUE(fs::exists(dir / "means")) << dir;
  auto decoys = read_decoy_words(dir / "decoys.txt");
  ASSERT_TRUE(decoys) << decoys.error().message;
  // The dataset's whole auxiliary vocabulary (README: the 12 words the development clips never
  // say are listed too), and no command word.
  EXPECT_EQ(decoys->size(), 25u);
  for (const char* never_heard : {"backward", "bed", "bird", "cat", "sheila", "six", "three",
                                  "tree", "two", "visual", "wow", "zero"})
    EXPECT_EQ(std::count(decoys->begin(), decoys->end(), never_heard), 1) << never_heard;
  for (const char* command :
       {"yes", "no", "up", "down", "left", "right", "on", "off", "stop", "go"})
    EXPECT_EQ(std::count(decoys->begin(), decoys->end(), command), 0) << "a command is no decoy";
  RecognizerOptions o;
  if (!fs::exists(o.model_dir / "mdef")) GTEST_SKIP() << "pocketsphinx-en-us not installed";
  o.model_dir = dir;
  auto st = use_acoustic_model(o, o.model_dir);  // the aliasing call of run_speech_eval
  ASSERT_TRUE(st) << st.error().message;
  EXPECT_EQ(o.model_dir, RecognizerOptions{}.model_dir);
  EXPECT_EQ(o.means_file, dir / "means");
}

TEST(SpeechCommandsModel, DecoyFilesAreCheckedAndCommented) {
  TempDir t;
  std::ofstream(t.path() / "d.txt") << "# words\ncat dog # pets\n\nbird\n";
  auto d = read_decoy_words(t.path() / "d.txt");
  ASSERT_TRUE(d) << d.error().message;
  EXPECT_EQ(*d, (std::vector<std::string>{"cat", "dog", "bird"}));
  std::ofstream(t.path() / "empty.txt") << "# nothing\n";
  auto empty = read_decoy_words(t.path() / "empty.txt");
  ASSERT_FALSE(empty);
  EXPECT_NE(empty.error().message.find("empty.txt"), std::string::npos);
  EXPECT_FALSE(read_decoy_words(t.path() / "missing.txt"));
}

}  // namespace
}  // namespace dreamsense::speech
