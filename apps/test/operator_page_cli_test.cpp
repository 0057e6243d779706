// The operator page of `live --ui` in a real browser (issue 21 item 1): a live dry run whose
// cameras are video files serves the page; headless Chromium (Debian's `chromium`, skipped when
// absent) loads it, it updates, its mark button (pressed by the page's own script through
// `?test_mark=1`: JS -> POST /api/marker -> the live run) writes a marker that lands in the
// recorded session (markers.jsonl, `check`), the live analysis' events.csv and summary.json, and
// an `analyze` of the recording; the screenshot shows camera pictures and the mutual-gaze
// indicator (checked by structure, not pixels).

#include "dreamsense/sources/session.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <arpa/inet.h>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <netinet/in.h>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <sys/socket.h>
#include <thread>
#include <unistd.h>
#include <vector>

#include "cli_support.hpp"
#include "demo_video.hpp"

namespace {
namespace fs = std::filesystem;
using nlohmann::json;

using dreamsense::cli_support::slurp;
using dreamsense::cli_support::write_video;

bool wait_for(const std::function<bool()>& done, double seconds) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < end) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return done();
}

// GET http://127.0.0.1:port/path: the body ("" when the page does not answer).
std::string http_get(int port, const std::string& path) {
  const int s = ::socket(AF_INET, SOCK_STREAM, 0);
  if (s < 0) return "";
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  std::string response;
  if (::connect(s, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) == 0) {
    const std::string req = "GET " + path + " HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) +
                            "\r\nConnection: close\r\n\r\n";
    if (::send(s, req.data(), req.size(), 0) == static_cast<ssize_t>(req.size())) {
      char buf[4096];
      for (ssize_t n; (n = ::recv(s, buf, sizeof(buf), 0)) > 0;) response.append(buf, n);
    }
  }
  ::close(s);
  const auto body = response.find("\r\n\r\n");
  return body == std::string::npos ? "" : response.substr(body + 4);
}

TEST(OperatorPageBrowser, PageUpdatesAndItsMarkerReachesTheSession) {
  if (std::system("command -v chromium > /dev/null 2>&1") != 0)
    GTEST_SKIP() << "chromium is not installed (tools/setup.sh installs it)";
  const fs::path demo = DREAMSENSE_CLI_DEMO_DIR;
  ASSERT_TRUE(fs::exists(demo / "session.yaml")) << "run the fixture cli_demo_fixture first";
  const fs::path dir = fs::temp_directory_path() / ("ds_opage_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  write_video(demo, "camera_middle", 4, dir / "middle.avi");  // 16 s
  write_video(demo, "camera_left", 4, dir / "left.avi");
  if (HasFatalFailure()) return;
  std::ofstream(dir / "live.yaml")
      << "session: {name: opage, metadata: {subject: demo_child}}\ncameras:\n"
      << "  - {id: camera_middle, device: middle.avi, calibration: "
      << (demo / "calib" / "camera_middle.yaml").string() << "}\n"
      << "  - {id: camera_left, device: left.avi, calibration: "
      << (demo / "calib" / "camera_left.yaml").string() << "}\n";
  const fs::path out = dir / "out", rec = dir / "rec", err = dir / "err.txt", rc = dir / "rc";
  const std::string live = std::string(DREAMSENSE_EXE) + " live --config " +
                           (dir / "live.yaml").string() + " --out " + out.string() + " --record " +
                           rec.string() + " --ui 0 --duration 14 2> " + err.string();
  ASSERT_EQ(std::system(("(" + live + "; echo $? > " + rc.string() + ") &").c_str()), 0);

  // The page's URL (any free port), then the capture.
  std::string url;
  ASSERT_TRUE(wait_for(
      [&] {
        std::smatch m;
        const std::string e = slurp(err);
        if (std::regex_search(e, m, std::regex("operator page: (http://127\\.0\\.0\\.1:[0-9]+/)")))
          url = m[1];
        return !url.empty() && e.find("live analysis into") != std::string::npos;
      },
      60))
      << slurp(err);
  // Analysed ticks (the models load after the capture starts) and a mutual-gaze answer (the
  // demo's child faces the cameras most of the time).
  const int port = std::stoi(url.substr(url.rfind(':') + 1));
  json state;
  std::set<std::string> gaze_states;
  EXPECT_TRUE(wait_for(
      [&] {
        const auto j = json::parse(http_get(port, "/api/operator"), nullptr, false);
        if (j.is_discarded() || !j.is_object()) return false;
        state = j;
        gaze_states.insert(j["mutual_gaze"]["state"].get<std::string>());
        return j["ticks"].get<int>() >= 10 && j["cameras"].size() == 2 &&
               (gaze_states.count("mutual") || gaze_states.count("not_mutual"));
      },
      45))
      << state.dump();

  const fs::path profile = dir / "chromium-profile";
  const std::string browser =
      "timeout 60 chromium --headless --no-sandbox --disable-gpu --hide-scrollbars "
      "--no-first-run --disable-extensions --user-data-dir=" +
      profile.string() + " ";
  // The DOM after a few updates and the mark button pressed by the page's own script.
  const fs::path dom_file = dir / "page.dom.html";
  ASSERT_EQ(std::system((browser + "--virtual-time-budget=6000 --dump-dom '" + url +
                         "?test_mark=1' > " + dom_file.string() + " 2>/dev/null")
                            .c_str()),
            0);
  const std::string dom = slurp(dom_file);
  EXPECT_NE(dom.find("data-updates=\""), std::string::npos) << "the page polled the API";
  EXPECT_NE(dom.find("data-marker-n=\"1\""), std::string::npos) << dom;
  EXPECT_NE(dom.find("marker 1 written at"), std::string::npos);
  EXPECT_NE(dom.find("REC "), std::string::npos) << "recording shown in the status strip";
  EXPECT_NE(dom.find("id=\"cam_camera_middle\""), std::string::npos);
  EXPECT_EQ(dom.find("src=\"http"), std::string::npos) << "nothing fetched from elsewhere";

  const fs::path png = dir / "page.png";
  ASSERT_EQ(std::system((browser +
                         "--virtual-time-budget=4000 --window-size=1400,900 "
                         "--screenshot=" +
                         png.string() + " '" + url + "' > /dev/null 2>&1")
                            .c_str()),
            0);
  const cv::Mat shot = cv::imread(png.string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(shot.empty());
  // The mutual-gaze card, large, in one of its colours: green (#2e9d4a, looking), blue-grey
  // (#78909c, not looking) or light grey (#e0e0e0, no estimate at that moment).
  cv::Mat green, grey, none;
  cv::inRange(shot, cv::Scalar(0x46, 0x99, 0x2a), cv::Scalar(0x4e, 0xa1, 0x32), green);
  cv::inRange(shot, cv::Scalar(0x98, 0x8c, 0x74), cv::Scalar(0xa0, 0x94, 0x7c), grey);
  cv::inRange(shot, cv::Scalar(0xdc, 0xdc, 0xdc), cv::Scalar(0xe4, 0xe4, 0xe4), none);
  EXPECT_GT(cv::countNonZero(green) + cv::countNonZero(grey) + cv::countNonZero(none), 20000)
      << "mutual-gaze indicator (green " << cv::countNonZero(green) << ", blue-grey "
      << cv::countNonZero(grey) << ", light grey " << cv::countNonZero(none) << ")";
  // Camera pictures below the indicators: not blank, with the overlay's face boxes (light blue)
  // or the selected face (yellow).
  const cv::Mat cams = shot.rowRange(shot.rows / 3, shot.rows);
  cv::Scalar mean, sd;
  cv::meanStdDev(cams, mean, sd);
  EXPECT_GT(sd[0], 20.0) << "camera pictures shown";
  cv::Mat box, selected;
  cv::inRange(cams, cv::Scalar(215, 160, 0), cv::Scalar(255, 240, 60), box);
  cv::inRange(cams, cv::Scalar(0, 190, 215), cv::Scalar(60, 255, 255), selected);
  EXPECT_GT(cv::countNonZero(box) + cv::countNonZero(selected), 100) << "face boxes drawn";

  ASSERT_TRUE(wait_for([&] { return fs::exists(rc) && !slurp(rc).empty(); }, 90)) << slurp(err);
  ASSERT_EQ(std::stoi(slurp(rc)), 0) << slurp(err);

  // The recorded session holds the marker, on the session clock.
  std::ifstream markers(rec / "markers.jsonl");
  std::string line;
  ASSERT_TRUE(std::getline(markers, line)) << "no markers.jsonl in the recording";
  const json m = json::parse(line);
  EXPECT_EQ(m["n"], 1);
  EXPECT_EQ(m["label"], "mark");
  EXPECT_GT(m["stamp_ns"].get<int64_t>(), 0);
  EXPECT_LT(m["stamp_ns"].get<int64_t>(), int64_t{30'000'000'000});
  // The live analysis' event table and summary.
  const std::string events = slurp(out / "tables" / "events.csv");
  EXPECT_NE(events.find("\nmarker,mark,"), std::string::npos) << events;
  EXPECT_EQ(json::parse(slurp(out / "summary.json"))["markers"].size(), 1u);
  // `check` reads it back; `analyze` of the recording carries it into its events.csv.
  ASSERT_EQ(std::system((std::string(DREAMSENSE_EXE) + " -q check " + rec.string() + " --json " +
                         (dir / "check.json").string())
                            .c_str()),
            0);
  EXPECT_EQ(json::parse(slurp(dir / "check.json"))["markers"], 1);
  ASSERT_EQ(std::system((std::string(DREAMSENSE_EXE) + " -q analyze " + rec.string() + " --out " +
                         (dir / "replay").string() + " --csv 2> " + (dir / "replay.err").string())
                            .c_str()),
            0)
      << slurp(dir / "replay.err");
  const std::string replay_events = slurp(dir / "replay" / "tables" / "events.csv");
  EXPECT_NE(replay_events.find("\nmarker,mark,"), std::string::npos) << replay_events;
  if (!HasFailure()) fs::remove_all(dir);
}

}  // namespace
