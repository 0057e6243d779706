// `dreamsense analyze VIDEO`: a plain video (made here with OpenCV's VideoWriter from the demo's
// rendered middle camera, no download) is analysed as a one-camera session; its CSV tables parse
// back to the values of primitives.jsonl; bad videos are one-line errors.

#include "dreamsense/sources/session.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <sys/wait.h>

#include "cli_support.hpp"

namespace {
namespace fs = std::filesystem;
using dreamsense::cli_support::read_jsonl;
using dreamsense::cli_support::run;
using dreamsense::cli_support::RunResult;
using dreamsense::cli_support::slurp;
using nlohmann::json;

// RFC 4180 reader (quoted cells with doubled quotes, commas and line breaks inside quotes).
std::vector<std::vector<std::string>> read_csv(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  std::vector<std::vector<std::string>> rows(1);
  std::string cell;
  bool quoted = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (quoted) {
      if (c == '"' && i + 1 < text.size() && text[i + 1] == '"') {
        cell += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        cell += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      rows.back().push_back(cell);
      cell.clear();
    } else if (c == '\n') {
      rows.back().push_back(cell);
      cell.clear();
      rows.emplace_back();
    } else {
      cell += c;
    }
  }
  if (rows.back().empty()) rows.pop_back();
  return rows;
}

class VideoCli : public ::testing::Test {
 protected:
  static fs::path root() {
    static const fs::path r =
        fs::temp_directory_path() / ("ds_video_cli_" + std::to_string(::getpid()));
    return r;
  }
  // The demo session (the ctest fixture's, or made here when run by hand).
  static const fs::path& demo() {
    static const fs::path d = dreamsense::cli_support::fixture_demo(root(), /*analysed=*/false);
    return d;
  }
  // The demo's middle camera as an mp4 (MPEG-4 part 2, 640x480, 25 fps), made once.
  static const fs::path& video() {
    static const fs::path v = [] {
      const fs::path out = root() / "child.mp4";
      auto reader = dreamsense::sources::SessionReader::open(
          demo(), dreamsense::sources::SessionReaderOptions{.only = {"camera_middle"}});
      EXPECT_TRUE(reader) << reader.error().message;
      cv::VideoWriter w(out.string(), cv::VideoWriter::fourcc('m', 'p', '4', 'v'), 25,
                        cv::Size(640, 480));
      EXPECT_TRUE(w.isOpened());
      while (true) {
        auto f = (*reader)->next();
        if (!f) break;
        cv::Mat small;
        cv::resize((*f)->as<dreamsense::ColorImage>()->image, small, cv::Size(640, 480), 0, 0,
                   cv::INTER_AREA);
        w.write(small);
      }
      return out;
    }();
    return v;
  }
  static const fs::path& analysis() {
    static const fs::path a = [] {
      const fs::path out = root() / "video_out";
      RunResult r = run("analyze " + video().string() + " --out " + out.string());
      EXPECT_EQ(r.exit_code, 0) << r.err;
      return out;
    }();
    return a;
  }
  void SetUp() override { demo(); }  // before any test writes into root()
  static void TearDownTestSuite() {
    if (std::getenv("DREAMSENSE_KEEP_TEST_OUTPUT") == nullptr) fs::remove_all(root());
  }
};

TEST_F(VideoCli, AnalysesAVideoAsAOneCameraSessionWithApproximateIntrinsics) {
  const fs::path a = analysis();
  for (const char* f : {"primitives.jsonl", "events.log", "dream.json", "report.html",
                        "summary.json", "tables/events.csv", "tables/tables.json"})
    EXPECT_TRUE(fs::exists(a / f)) << f;
  std::ifstream in(a / "summary.json");
  const json summary = json::parse(in);
  EXPECT_EQ(summary["input"]["kind"], "video");
  EXPECT_EQ(summary["input"]["approximate_calibration"], true);
  EXPECT_EQ(summary["input"]["width"], 640);
  EXPECT_NEAR(summary["input"]["fx_px"].get<double>(), 500.0, 1e-9);
  EXPECT_EQ(summary["pipeline"]["approximate_calibration"], json::array({"camera"}));
  EXPECT_GE(summary["ticks"].get<int>(), 99);
  // The single-camera face chain runs; the sensors a video lacks give no analysers.
  const auto analyzers = summary["analyzers"].get<std::vector<std::string>>();
  for (const char* name : {"face_detection", "face_landmarks", "head_pose", "eye_centers", "gaze"})
    EXPECT_NE(std::find(analyzers.begin(), analyzers.end(), name), analyzers.end()) << name;
  EXPECT_TRUE(summary["pipeline"]["not_running"].contains("body"));
  // Stamps come from the container: 25 fps, 40 ms apart, starting at 0.
  const auto records = read_jsonl(a / "primitives.jsonl");
  std::vector<int64_t> stamps;
  int faces_ok = 0, faces = 0;
  for (const auto& r : records)
    if (r["primitive"] == "getFaces") {
      stamps.push_back(r["stamp_ns"].get<int64_t>());
      ++faces;
      faces_ok += r["status"] == "ok";
      if (r["status"] == "ok") {
        EXPECT_EQ(r["source"], "camera");
      }
    }
  ASSERT_GE(stamps.size(), 99u);
  EXPECT_EQ(stamps[0], 0);
  EXPECT_EQ(stamps[1], 40'000'000);
  EXPECT_GE(faces_ok, faces * 9 / 10) << "the demo child faces the middle camera";
  // The report says the intrinsics are approximate.
  std::ifstream html(a / "report.html");
  std::stringstream ss;
  ss << html.rdbuf();
  EXPECT_NE(ss.str().find("approximate"), std::string::npos);
}

TEST_F(VideoCli, CsvTablesParseBackToThePrimitiveValues) {
  const fs::path a = analysis();
  const auto records = read_jsonl(a / "primitives.jsonl");
  std::map<int64_t, json> head;  // getHead records by stamp
  for (const auto& r : records)
    if (r["primitive"] == "getHead") head[r["stamp_ns"].get<int64_t>()] = r;
  const auto rows = read_csv(a / "tables" / "F10_getHead.csv");
  ASSERT_GE(rows.size(), 2u);
  const auto& header = rows[0];
  auto col = [&](const std::string& name) {
    const auto it = std::find(header.begin(), header.end(), name);
    EXPECT_NE(it, header.end()) << name;
    return static_cast<size_t>(it - header.begin());
  };
  const std::vector<std::string> fixed = {"time_s",     "stamp_ns", "status",       "ok",
                                          "confidence", "source",   "data_stamp_ns"};
  ASSERT_GE(header.size(), fixed.size());
  EXPECT_EQ(std::vector<std::string>(header.begin(), header.begin() + 7), fixed);
  const size_t z = col("position_m.z"), ok = col("ok"), stamp = col("stamp_ns");
  EXPECT_EQ(rows.size() - 1, head.size()) << "one row per tick";
  int compared = 0;
  for (size_t i = 1; i < rows.size(); ++i) {
    ASSERT_EQ(rows[i].size(), header.size()) << "row " << i;
    const json& r = head.at(std::stoll(rows[i][stamp]));
    EXPECT_EQ(rows[i][ok], r["status"] == "ok" ? "1" : "0");
    if (r["status"] == "ok") {
      EXPECT_NEAR(std::stod(rows[i][z]), r["value"]["position_m"][2].get<double>(), 1e-9);
      ++compared;
    } else {
      EXPECT_TRUE(rows[i][z].empty());
    }
  }
  EXPECT_GT(compared, 50);
  // Every table of tables.json exists with the header it lists; events.csv parses.
  std::ifstream in(a / "tables" / "tables.json");
  const json index = json::parse(in);
  EXPECT_EQ(index["approximate_calibration"], true);
  for (const auto& [file, t] : index["tables"].items()) {
    const auto table = read_csv(a / "tables" / file);
    ASSERT_FALSE(table.empty()) << file;
    EXPECT_EQ(table[0], t["columns"].get<std::vector<std::string>>()) << file;
    for (const auto& row : table) EXPECT_EQ(row.size(), table[0].size()) << file;
  }
  EXPECT_FALSE(fs::exists(a / "tables" / "F04_getBodyPose.csv")) << "disabled: no table";
  // ticks.csv: the same values side by side, one row per tick.
  const auto wide = read_csv(a / "tables" / "ticks.csv");
  ASSERT_EQ(wide.size(), rows.size());
  const auto wz = std::find(wide[0].begin(), wide[0].end(), "getHead.position_m.z");
  const auto wok = std::find(wide[0].begin(), wide[0].end(), "getFaces.ok");
  ASSERT_NE(wz, wide[0].end());
  ASSERT_NE(wok, wide[0].end());
  for (size_t i = 1; i < wide.size(); ++i) {
    EXPECT_EQ(wide[i][1], rows[i][stamp]);
    EXPECT_EQ(wide[i][static_cast<size_t>(wz - wide[0].begin())], rows[i][z]);
  }
}

// The report opens in a real browser (Debian's chromium, headless, started here; skipped when
// it is not installed): its DOM has the sections, charts and key frames, it loads nothing from
// the network, and the screenshot is a page with content (structure, not pixels).
TEST_F(VideoCli, ReportRendersInAHeadlessBrowser) {
  if (std::system("command -v chromium > /dev/null 2>&1") != 0)
    GTEST_SKIP() << "chromium is not installed (tools/setup.sh installs it)";
  const fs::path a = analysis();
  const fs::path profile = root() / "chromium-profile";
  const std::string browser =
      "timeout 120 chromium --headless --no-sandbox --disable-gpu --hide-scrollbars "
      "--no-first-run --disable-extensions --user-data-dir=" +
      profile.string() + " ";
  const std::string url = "file://" + fs::absolute(a / "report.html").string();
  const fs::path dom_file = root() / "report.dom.html";
  ASSERT_EQ(
      std::system(
          (browser + "--dump-dom " + url + " > " + dom_file.string() + " 2>/dev/null").c_str()),
      0);
  std::ifstream in(dom_file);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string dom = ss.str();
  auto count = [&](const std::string& needle) {
    size_t n = 0;
    for (size_t p = dom.find(needle); p != std::string::npos; p = dom.find(needle, p + 1)) ++n;
    return n;
  };
  for (const char* id :
       {"summary", "gaze", "timeline", "frames", "quality", "availability", "plots", "episodes"})
    EXPECT_EQ(count(std::string("<h2 id=\"") + id + "\""), 1u) << id;
  EXPECT_GE(count("<svg class=\"chart\""), 4u) << "head pose, gaze, positions...";
  EXPECT_EQ(count("<svg class=\"lanes\""), 1u);
  EXPECT_EQ(count("<img "), 5u) << "five key frames";
  EXPECT_EQ(count("src=\"http"), 0u) << "self-contained";
  EXPECT_EQ(count("href=\"http"), 0u);
  EXPECT_NE(dom.find("Approximate camera intrinsics"), std::string::npos);
  EXPECT_NE(dom.find("time (s)"), std::string::npos);
  EXPECT_EQ(count("<tr><td>F"), 25u) << "availability of the 25 primitives";

  const fs::path png = root() / "report.png";
  ASSERT_EQ(std::system((browser + "--window-size=1200,3000 --screenshot=" + png.string() + " " +
                         url + " > /dev/null 2>&1")
                            .c_str()),
            0);
  const cv::Mat shot = cv::imread(png.string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(shot.empty());
  EXPECT_EQ(shot.cols, 1200);
  cv::Scalar mean, stddev;
  cv::meanStdDev(shot, mean, stddev);
  EXPECT_GT(stddev[0], 20.0) << "not a blank page";
  // The approximate-intrinsics banner (#fff4d6) is drawn near the top of the page.
  cv::Mat banner;
  cv::inRange(shot.rowRange(0, 400), cv::Scalar(0xd0, 0xf0, 0xfa), cv::Scalar(0xdc, 0xf8, 0xff),
              banner);
  EXPECT_GT(cv::countNonZero(banner), 10000) << "warning banner rendered";
}

// OpenCV's sample video (Debian opencv-doc, installed by tools/setup.sh): an XviD AVI whose last
// frame has no timestamp; per-tick CSV rows and faces on most ticks.
TEST_F(VideoCli, AnalysesOpenCvsSampleVideo) {
  const fs::path megamind = "/usr/share/doc/opencv-doc/examples/data/Megamind.avi";
  if (!fs::exists(megamind)) GTEST_SKIP() << megamind << " not found (Debian package opencv-doc)";
  const fs::path out = root() / "megamind";
  RunResult r = run("analyze " + megamind.string() + " --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rows = read_csv(out / "tables" / "F07_getFaces.csv");
  ASSERT_EQ(rows.size(), 271u) << "header + 270 frames";
  const size_t ok =
      static_cast<size_t>(std::find(rows[0].begin(), rows[0].end(), "ok") - rows[0].begin());
  int found = 0;
  double last_t = -1;
  for (size_t i = 1; i < rows.size(); ++i) {
    found += rows[i][ok] == "1";
    const double t = std::stod(rows[i][0]);
    EXPECT_GT(t, last_t) << "row " << i;
    last_t = t;
  }
  EXPECT_GE(found, 240) << "one face, almost always visible";
  EXPECT_NEAR(last_t, 269 / 23.976, 0.01) << "container stamps at 23.976 fps";
}

TEST_F(VideoCli, PrintPipelineShowsTheOneCameraGraph) {
  const fs::path err = root() / "pp.txt";
  const std::string cmd = std::string(DREAMSENSE_EXE) + " analyze " + video().string() +
                          " --print-pipeline > " + err.string() + " 2>/dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  std::ifstream in(err);
  std::stringstream ss;
  ss << in.rdbuf();
  EXPECT_NE(ss.str().find("approximate intrinsics"), std::string::npos) << ss.str();
  EXPECT_NE(ss.str().find("face_detection"), std::string::npos) << ss.str();
}

TEST_F(VideoCli, BadVideosAreOneLineErrors) {
  const fs::path dir = root() / "bad";
  fs::create_directories(dir);
  std::ofstream(dir / "empty.mp4").close();
  std::ofstream(dir / "text.mp4") << "this is not a video\n";
  {  // an mp4 cut in half loses its index (moov atom at the end): nothing can be decoded
    std::ifstream src(video(), std::ios::binary);
    std::stringstream ss;
    ss << src.rdbuf();
    const std::string bytes = ss.str();
    std::ofstream(dir / "cut.mp4", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  }
  {  // an AVI whose second half is missing: frames up to the cut decode, then the error
    cv::VideoWriter w((dir / "full.avi").string(), cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25,
                      cv::Size(320, 240));
    ASSERT_TRUE(w.isOpened());
    for (int k = 0; k < 100; ++k) {
      cv::Mat m(240, 320, CV_8UC3, cv::Scalar(k, 2 * k, 255 - k));
      cv::putText(m, std::to_string(k), {50, 120}, cv::FONT_HERSHEY_SIMPLEX, 2, {255, 255, 255}, 3);
      w.write(m);
    }
  }
  {
    std::ifstream src(dir / "full.avi", std::ios::binary);
    std::stringstream ss;
    ss << src.rdbuf();
    const std::string bytes = ss.str();
    std::ofstream(dir / "half.avi", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  }
  RunResult half =
      run("analyze " + (dir / "half.avi").string() + " --out " + (dir / "half.out").string());
  EXPECT_NE(half.exit_code, 0);
  EXPECT_NE(half.err.find("half.avi: corrupt or truncated: frame"), std::string::npos) << half.err;
  EXPECT_EQ(std::count(half.err.begin(), half.err.end(), '\n'), 1) << half.err;
  EXPECT_FALSE(fs::exists(dir / "half.out" / "primitives.jsonl"));
  // The whole AVI (no face in it) is analysed: "nothing detected" is an answer, not an error.
  RunResult full =
      run("analyze " + (dir / "full.avi").string() + " --out " + (dir / "full.out").string());
  ASSERT_EQ(full.exit_code, 0) << full.err;
  int faces = 0;
  for (const auto& r : read_jsonl(dir / "full.out" / "primitives.jsonl"))
    if (r["primitive"] == "getFaces") {
      ++faces;
      EXPECT_EQ(r["status"], "no_data");
    }
  EXPECT_EQ(faces, 100);

  for (const char* name : {"empty.mp4", "text.mp4", "cut.mp4", "missing.mp4"}) {
    const fs::path out = dir / (std::string(name) + ".out");
    RunResult r = run("analyze " + (dir / name).string() + " --out " + out.string());
    EXPECT_NE(r.exit_code, 0) << name;
    EXPECT_NE(r.err.find(name), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(fs::exists(out / "primitives.jsonl")) << name;
  }
  // A folder of videos is batch's job, said in one line.
  RunResult folder = run("analyze " + dir.string() + " --out " + (dir / "folder.out").string());
  EXPECT_NE(folder.exit_code, 0);
  EXPECT_NE(folder.err.find("dreamsense batch"), std::string::npos) << folder.err;
  EXPECT_EQ(std::count(folder.err.begin(), folder.err.end(), '\n'), 1) << folder.err;
  // --calibration must match the video's image size.
  std::ofstream(dir / "cam.yaml") << "%YAML:1.0\n---\nimage_width: 1280\nimage_height: 960\n"
                                     "camera_matrix: !!opencv-matrix\n  rows: 3\n  cols: 3\n"
                                     "  dt: d\n  data: [1000, 0, 640, 0, 1000, 480, 0, 0, 1]\n";
  RunResult r = run("analyze " + video().string() + " --calibration " +
                    (dir / "cam.yaml").string() + " --out " + (dir / "calib.out").string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

}  // namespace
