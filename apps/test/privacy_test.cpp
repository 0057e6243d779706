// Privacy of participants' names (issue 22 item 8, issue 18 item 6; spec/system.md "Privacy"):
// a copy of the 4-second demo whose voice enrolment folders, face gallery and session.yaml
// (name, metadata) hold distinctive people's names and a date is analysed through the executable
// (-v: every log line). By default no name or date may appear in any output file nor on stdout or
// stderr; with --include-names they appear where expected. The DDS messages (the exact text
// `live --publish dds` sends) are checked in-process through Fast DDS. --blur-faces changes the
// report's key frames only around the faces.

#include "dreamsense/export/primitive_json.hpp"
#include "dreamsense/publish/dds_publisher.hpp"
#include "dreamsense/runner/analysis.hpp"
#include "dreamsense/sources/session.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <sys/wait.h>
#include <unistd.h>

namespace {
namespace fs = std::filesystem;
using nlohmann::json;

// The people of the test session. Folder and gallery names use '_' (as a folder would);
// the metadata uses the plain names.
constexpr const char* kChildFolder = "Zebulon_Quimby";         // enroll/child renamed
constexpr const char* kTherapistFolder = "Philippa_Wexford";   // enroll/therapist renamed
constexpr const char* kGalleryName = "Marigold_Featherstone";  // the gallery's person 0
constexpr const char* kSessionName = "Zebulon Quimby with Ottoline Brackenbury";
// What must never appear by default: every part of every name, and the dates.
const std::vector<std::string> kSecrets = {
    "Zebulon",  "Quimby",      "Philippa",   "Wexford",    "Marigold",           "Featherstone",
    "Ottoline", "Brackenbury", "2019-07-23", "2026-02-17", "Tuesday 17 February"};

struct RunResult {
  int exit_code = -1;
  std::string out, err;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

RunResult run(const std::string& args) {
  const std::string tag = std::to_string(::getpid());
  const fs::path out_file = fs::temp_directory_path() / ("ds_privacy_out_" + tag);
  const fs::path err_file = fs::temp_directory_path() / ("ds_privacy_err_" + tag);
  const std::string cmd = std::string(DREAMSENSE_EXE) + " " + args + " > " + out_file.string() +
                          " 2> " + err_file.string();
  const int status = std::system(cmd.c_str());
  RunResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(out_file);
  r.err = slurp(err_file);
  fs::remove(out_file);
  fs::remove(err_file);
  return r;
}

std::vector<json> read_jsonl(const fs::path& p) {
  std::vector<json> out;
  std::ifstream in(p);
  for (std::string line; std::getline(in, line);)
    if (!line.empty()) out.push_back(json::parse(line));
  return out;
}

// "where: secret" for every secret found in `text`.
std::vector<std::string> leaks(const std::string& where, const std::string& text) {
  std::vector<std::string> found;
  for (const auto& s : kSecrets)
    if (text.find(s) != std::string::npos) found.push_back(where + ": " + s);
  return found;
}

// Every file under `dir` (recursively), searched as bytes.
std::vector<std::string> leaks_in_folder(const fs::path& dir) {
  std::vector<std::string> found;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    auto l = leaks(fs::relative(e.path(), dir).string(), slurp(e.path()));
    found.insert(found.end(), l.begin(), l.end());
  }
  return found;
}

std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += x + "\n";
  return s;
}

class Privacy : public ::testing::Test {
 protected:
  static fs::path root() {
    static const fs::path r =
        fs::temp_directory_path() / ("ds_privacy_" + std::to_string(::getpid()));
    return r;
  }
  // The demo session (the ctest fixture's, else made here) copied without its analysis, with the
  // names put in: enrolment folders renamed, a face gallery naming its person, session.yaml's
  // name and metadata.
  static const fs::path& session() {
    static const fs::path s = [] {
      fs::remove_all(root());
      fs::create_directories(root());
      fs::path demo = DREAMSENSE_CLI_DEMO_DIR;
      if (!fs::exists(demo / "summary.json")) {
        demo = root() / "demo";
        RunResult r = run("-q demo --out " + demo.string() + " --seed 3 --duration 4");
        EXPECT_EQ(r.exit_code, 0) << r.err;
      }
      demo_dir() = demo;
      const fs::path dst = root() / "session";
      fs::create_directories(dst);
      const auto& outputs = dreamsense::runner::analysis_output_names();
      for (const auto& e : fs::directory_iterator(demo)) {
        const std::string name = e.path().filename().string();
        if (std::find(outputs.begin(), outputs.end(), name) != outputs.end()) continue;
        fs::copy(e.path(), dst / name, fs::copy_options::recursive);
      }
      fs::rename(dst / "enroll" / "child", dst / "enroll" / kChildFolder);
      fs::rename(dst / "enroll" / "therapist", dst / "enroll" / kTherapistFolder);
      std::string gallery =
          slurp(fs::path(DREAMSENSE_SOURCE_DIR) / "data/subjects/demo_child/face_gallery.yaml");
      const auto at = gallery.find("name: demo_child");
      EXPECT_NE(at, std::string::npos) << "the shipped gallery names its person demo_child";
      if (at != std::string::npos)
        gallery.replace(at, std::string("name: demo_child").size(),
                        std::string("name: ") + kGalleryName);
      std::ofstream(dst / "gallery.yaml") << gallery;
      auto m = dreamsense::sources::read_manifest(dst);
      EXPECT_TRUE(m) << m.error().message;
      m->name = kSessionName;
      m->metadata["participant_name"] = "Zebulon Quimby";
      m->metadata["operator"] = "Ottoline Brackenbury";
      m->metadata["date_of_birth"] = "2019-07-23";
      m->metadata["date"] = "Tuesday 17 February 2026";
      m->metadata["recorded"] = "2026-02-17";
      m->metadata["face_gallery"] = "gallery.yaml";
      EXPECT_TRUE(dreamsense::sources::write_manifest(dst, *m));
      return dst;
    }();
    return s;
  }
  // The demo the session was copied from (analysed with the default options).
  static fs::path& demo_dir() {
    static fs::path d;
    return d;
  }
  // `analyze SESSION --out ROOT/name FLAGS` once per test binary (tests share the results).
  static const RunResult& analysed(const std::string& name, const std::string& flags) {
    static std::map<std::string, RunResult> done;
    auto it = done.find(name);
    if (it == done.end())
      it = done.emplace(name, run("-v analyze " + session().string() + " --out " +
                                  (root() / name).string() + " " + flags))
               .first;
    return it->second;
  }
  void SetUp() override { session(); }
  static void TearDownTestSuite() { fs::remove_all(root()); }
};

// The ok answers of one primitive.
std::vector<json> ok_values(const fs::path& analysis, const std::string& primitive) {
  std::vector<json> out;
  for (const auto& r : read_jsonl(analysis / "primitives.jsonl"))
    if (r["primitive"] == primitive && r["status"] == "ok") out.push_back(r["value"]);
  return out;
}

TEST_F(Privacy, DefaultOutputsAndLogsCarryIdsOnly) {
  const fs::path out = root() / "default";
  const RunResult& r = analysed("default", "--csv --overlay");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::vector<std::string> found = leaks_in_folder(out);
  for (const auto& l : leaks("stdout", r.out)) found.push_back(l);
  for (const auto& l : leaks("stderr", r.err)) found.push_back(l);
  EXPECT_TRUE(found.empty()) << "names or dates in the default outputs:\n" << joined(found);
  EXPECT_TRUE(fs::exists(out / "tables")) << "the CSV tables were searched too";
  EXPECT_TRUE(fs::exists(out / "overlay.mp4")) << "the overlay was searched too";

  // Not vacuous: both identities were answered, by ids.
  const auto voices = ok_values(out, "identifyVoice");
  ASSERT_FALSE(voices.empty()) << "the 4 s demo has one utterance (the child's)";
  for (const auto& v : voices) {
    EXPECT_TRUE(std::regex_match(v["speaker_id"].get<std::string>(), std::regex("speaker_[12]")) ||
                v["speaker_id"] == "unknown")
        << v;
    EXPECT_EQ(v["name"], v["speaker_id"]) << "the name is the id by default";
  }
  // Enrolment order = folder names sorted: Philippa_Wexford = speaker_1, Zebulon_Quimby (the
  // child's folder) = speaker_2.
  EXPECT_EQ(voices.front()["speaker_id"], "speaker_2");
  const auto faces = ok_values(out, "identifyFace");
  if (faces.empty()) GTEST_SKIP() << "identifyFace did not run (face-api.js weights missing?)";
  for (const auto& f : faces) EXPECT_EQ(f["name"], "") << f;
  EXPECT_EQ(faces.front()["id"], 0) << "the gallery's numeric id identifies";
  const json summary = json::parse(slurp(out / "summary.json"));
  EXPECT_EQ(summary["session"], "session") << "the folder's name, not its path";
  EXPECT_EQ(summary["names"], "ids only");
}

TEST_F(Privacy, IncludeNamesWritesThemWhereExpected) {
  const fs::path out = root() / "names";
  const RunResult& r = analysed("names", "--include-names");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto voices = ok_values(out, "identifyVoice");
  ASSERT_FALSE(voices.empty());
  EXPECT_EQ(voices.front()["name"], kChildFolder);
  EXPECT_EQ(voices.front()["speaker_id"], "speaker_2") << "the id does not change with names";
  const auto faces = ok_values(out, "identifyFace");
  if (!faces.empty()) {
    EXPECT_EQ(faces.front()["name"], kGalleryName);
  }
  EXPECT_NE(slurp(out / "report.html").find(kSessionName), std::string::npos);
  EXPECT_NE(slurp(out / "dream.json").find(kSessionName), std::string::npos);
  EXPECT_NE(r.err.find(kTherapistFolder), std::string::npos)
      << "the plan's note names the enrolled speakers:\n"
      << r.err;
  EXPECT_EQ(json::parse(slurp(out / "summary.json"))["names"], "included");
}

// What `live --publish dds` sends: every tick's ok records, as primitives.jsonl lines, through
// Fast DDS. Analysed in-process (no output files) with a subscriber on identifyVoice.
std::vector<std::string> dds_messages(const fs::path& session, bool include_names) {
  using namespace dreamsense;
  publish::DdsPublisherOptions po;
  po.domain_id = 201 + static_cast<int>(::getpid() % 15) * 2 + (include_names ? 1 : 0);
  po.only = {"identifyVoice", "identifyFace"};
  po.json_topics = true;
  auto voice = publish::DdsStringSubscriber::create(po, "identifyVoice");
  if (!voice && voice.error().code == ErrorCode::kUnsupported) return {"unsupported"};
  EXPECT_TRUE(voice) << voice.error().message;
  auto face = publish::DdsStringSubscriber::create(po, "identifyFace");
  EXPECT_TRUE(face) << face.error().message;
  auto pub = publish::DdsPublisher::create(po);
  EXPECT_TRUE(pub) << pub.error().message;
  if (!voice || !face || !pub) return {};
  // Discovery first: a neutral record until the subscriber hears it.
  primitives::PrimitiveRecord probe;
  probe.id = primitives::PrimitiveId::kIdentifyVoice;
  probe.status = primitives::PrimitiveStatus::kOk;
  probe.value = primitives::VoiceValue{"probe", "probe", 1.0, 0, 0, "probe"};
  size_t probes = 0;
  for (int i = 0; i < 50 && (*voice)->wait_for(1, 100).empty(); ++i) {
    EXPECT_TRUE((*pub)->publish({probe}));
    ++probes;
  }
  const size_t heard_before = (*voice)->wait_for(1, 10).size();
  EXPECT_GT(heard_before, 0u) << "DDS discovery failed in 5 s";

  runner::AnalysisOptions o;
  o.session_dir = session;
  o.plan.include_names = include_names;
  size_t sent = 0;
  o.on_records = [&](const std::vector<primitives::PrimitiveRecord>& records) -> Status {
    for (const auto& rec : records)
      sent += rec.ok() && (rec.id == primitives::PrimitiveId::kIdentifyVoice);
    return (*pub)->publish(records);
  };
  auto s = runner::analyze_session(o);
  EXPECT_TRUE(s) << s.error().message;
  EXPECT_GT(sent, 0u) << "no identifyVoice answer to publish";
  std::vector<std::string> got = (*voice)->wait_for(heard_before + sent, 3000);
  EXPECT_GE(got.size(), heard_before + sent) << "identifyVoice messages lost";
  for (const auto& m : (*face)->wait_for(1, 1000)) got.push_back(m);
  return got;
}

TEST_F(Privacy, DdsMessagesCarryIdsOnlyUnlessNamesAreIncluded) {
  const auto plain = dds_messages(session(), false);
  if (plain.size() == 1 && plain.front() == "unsupported") GTEST_SKIP() << "built without Fast DDS";
  std::string text;
  for (const auto& m : plain) text += m + "\n";
  EXPECT_NE(text.find("speaker_2"), std::string::npos) << text;
  const auto found = leaks("DDS", text);
  EXPECT_TRUE(found.empty()) << joined(found) << text;

  std::string named;
  for (const auto& m : dds_messages(session(), true)) named += m + "\n";
  EXPECT_NE(named.find(kChildFolder), std::string::npos) << "the check can see a name:\n" << named;
}

// The data: JPEG key frames of report.html, decoded.
std::vector<cv::Mat> key_frames(const fs::path& report) {
  static const std::string kB64 =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const std::string html = slurp(report);
  const std::string tag = "data:image/jpeg;base64,";
  std::vector<cv::Mat> out;
  for (size_t at = html.find(tag); at != std::string::npos; at = html.find(tag, at + 1)) {
    const size_t b = at + tag.size(), e = html.find('"', b);
    std::vector<uchar> bytes;
    int buffer = 0, bits = 0;
    for (size_t i = b; i < e; ++i) {
      const auto v = kB64.find(html[i]);
      if (v == std::string::npos) continue;  // '=' padding
      buffer = (buffer << 6) | static_cast<int>(v);
      bits += 6;
      if (bits >= 8) {
        bits -= 8;
        bytes.push_back(static_cast<uchar>((buffer >> bits) & 0xff));
      }
    }
    out.push_back(cv::imdecode(bytes, cv::IMREAD_COLOR));
  }
  return out;
}

// --blur-faces: the report's key frames change where the face is and stay as they were elsewhere
// (JPEG works on 8x8 blocks: blocks away from the face are encoded from the same pixels).
TEST_F(Privacy, BlurFacesChangesTheKeyFramesAroundTheFaceOnly) {
  // The demo's own analysis (default options; the names put into the copy change no picture).
  const fs::path plain = demo_dir(), blurred = root() / "blurred";
  const RunResult& r = analysed("blurred", "--blur-faces");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto a = key_frames(plain / "report.html"), b = key_frames(blurred / "report.html");
  ASSERT_FALSE(a.empty());
  ASSERT_EQ(a.size(), b.size());
  int changed = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    ASSERT_FALSE(a[i].empty());
    ASSERT_EQ(a[i].size(), b[i].size());
    cv::Mat diff;
    cv::absdiff(a[i], b[i], diff);
    cv::Mat grey;
    cv::extractChannel(diff, grey, 0);
    cv::Mat any = grey > 0;
    for (int c = 1; c < 3; ++c) {
      cv::extractChannel(diff, grey, c);
      any |= grey > 0;
    }
    const double share = cv::countNonZero(any) / static_cast<double>(any.total());
    if (share > 0) ++changed;
    EXPECT_LT(share, 0.25) << "key frame " << i << ": only the face region changes";
  }
  EXPECT_GT(changed, 0) << "no key frame was blurred";
}

}  // namespace
