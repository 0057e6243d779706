// CSV tables from primitives.jsonl: flattening rules, quoting, column order, episodes.

#include "dreamsense/export/csv_tables.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

namespace dreamsense::exporters {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

std::vector<std::pair<std::string, std::string>> flat(const json& v) {
  std::vector<std::pair<std::string, std::string>> out;
  flatten_json(v, "", out);
  return out;
}

TEST(CsvTables, FlattensNestedValuesWithUnitsInTheNames) {
  const auto cells = flat(json::parse(R"({
      "position_m": [0.1, -0.2, 1.5], "px": [3, 4], "box_px": [1, 2, 30, 40],
      "boxes": {"cam": [5, 6, 7, 8]}, "mutual": true, "label": "wave", "none": null,
      "faces": [{"score": 0.9}, {"score": 0.5}], "tag": ["seven of clubs"]})"));
  std::map<std::string, std::string> m(cells.begin(), cells.end());
  EXPECT_EQ(m.at("position_m.x"), "0.1");
  EXPECT_EQ(m.at("position_m.z"), "1.5");
  EXPECT_EQ(m.at("px.y"), "4");
  EXPECT_EQ(m.at("box_px.w"), "30");
  EXPECT_EQ(m.at("boxes.cam.h"), "8") << "a box nested under a *box* member";
  EXPECT_EQ(m.at("mutual"), "true");
  EXPECT_EQ(m.at("label"), "wave");
  EXPECT_EQ(m.at("none"), "");
  EXPECT_EQ(m.at("faces.count"), "2");
  EXPECT_EQ(m.at("faces.1.score"), "0.5");
  EXPECT_EQ(m.at("tag"), "seven of clubs");
}

TEST(CsvTables, QuotesCellsAsRfc4180) {
  EXPECT_EQ(csv_cell("plain"), "plain");
  EXPECT_EQ(csv_cell("a,b"), "\"a,b\"");
  EXPECT_EQ(csv_cell("say \"hi\""), "\"say \"\"hi\"\"\"");
  EXPECT_EQ(csv_table_name("F12", "getHeadGaze (plane)"), "F12_getHeadGaze_plane.csv");
  EXPECT_EQ(csv_table_name("F1", "checkMutualGaze"), "F01_checkMutualGaze.csv");
}

// Ticks at 25 Hz: mutual gaze true on ticks 2-4, a gesture on ticks 5-6, an utterance reported
// twice (sticky), a primitive that is disabled all along.
TEST(CsvTables, WritesTablesWithAStableHeaderAndEpisodes) {
  const fs::path dir = fs::temp_directory_path() / ("ds_csv_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  {
    std::ofstream out(dir / "primitives.jsonl");
    for (int k = 0; k < 8; ++k) {
      const int64_t stamp = 1'000'000'000LL + k * 40'000'000LL;
      json mg = {{"stamp_ns", stamp}, {"primitive", "checkMutualGaze"},
                 {"id", "F1"},        {"status", k == 7 ? "no_data" : "ok"},
                 {"confidence", 0.9}, {"source", nullptr}};
      mg["value"] = k == 7
                        ? json()
                        : json{{"mutual", k >= 2 && k <= 4}, {"held_s", 0.0}, {"target", "robot"}};
      if (k == 0) mg["value"]["miss_distance_m"] = 0.3;  // a column only the first tick has
      json tr = {{"stamp_ns", stamp},
                 {"primitive", "identifyTrajectory"},
                 {"id", "F20"},
                 {"status", "ok"},
                 {"confidence", 1.0},
                 {"source", "body"},
                 {"value", {{"label", k == 5 || k == 6 ? "wave" : "none"}, {"id", 1}}}};
      json sp = {{"stamp_ns", stamp},
                 {"primitive", "recognizeSpeech"},
                 {"id", "F22"},
                 {"status", k >= 3 && k <= 4 ? "ok" : "no_data"},
                 {"source", "mic_array"}};
      if (k >= 3 && k <= 4)
        sp["value"] = {{"text", "hello, robot"},
                       {"tag", "hello"},
                       {"confidence", 0.8},
                       {"start_ns", 1'000'000'000LL},
                       {"end_ns", 1'100'000'000LL}};
      json off = {
          {"stamp_ns", stamp}, {"primitive", "getObjects"}, {"id", "F13"}, {"status", "disabled"}};
      for (const json& r : {mg, tr, sp, off}) out << r.dump() << "\n";
    }
  }
  auto written = write_csv_tables(dir / "primitives.jsonl", dir / "tables");
  ASSERT_TRUE(written) << written.error().message;
  auto slurp = [](const fs::path& p) {
    std::ifstream in(p);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  };
  const std::string mg = slurp(dir / "tables" / "F01_checkMutualGaze.csv");
  EXPECT_EQ(mg.substr(0, mg.find('\n')),
            "time_s,stamp_ns,status,ok,confidence,source,data_stamp_ns,held_s,miss_distance_m,"
            "mutual,target");
  EXPECT_NE(mg.find("\n0.000,1000000000,ok,1,0.9,,,0.0,0.3,false,robot\n"), std::string::npos)
      << mg;
  EXPECT_NE(mg.find("\n0.040,1040000000,ok,1,0.9,,,0.0,,false,robot\n"), std::string::npos);
  EXPECT_NE(mg.find("\n0.280,1280000000,no_data,0,0.9,,,,,,\n"), std::string::npos);
  EXPECT_FALSE(fs::exists(dir / "tables" / "F13_getObjects.csv")) << "disabled all along";
  EXPECT_NE(slurp(dir / "tables" / "F22_recognizeSpeech.csv").find("\"hello, robot\""),
            std::string::npos);
  EXPECT_EQ(slurp(dir / "tables" / "events.csv"),
            "type,label,start_s,end_s,duration_s,source,detail\n"
            "speech,\"hello, robot\",0.000,0.100,0.100,mic_array,confidence 0.8; tag hello\n"
            "mutual_gaze,looking at robot,0.080,0.200,0.120,,\n"
            "identifyTrajectory,wave,0.200,0.280,0.080,body,\n");
  const std::string wide = slurp(dir / "tables" / "ticks.csv");
  EXPECT_EQ(std::count(wide.begin(), wide.end(), '\n'), 9) << "header + 8 ticks";
  EXPECT_NE(wide.find("checkMutualGaze.ok,checkMutualGaze.confidence,checkMutualGaze.held_s"),
            std::string::npos);
  fs::remove_all(dir);
}

// The operator's markers become events.csv rows at their stamp, in start order with the episodes.
TEST(CsvTables, MarkersBecomeEventRows) {
  const fs::path dir = fs::temp_directory_path() / ("ds_csv_markers_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  {
    std::ofstream out(dir / "primitives.jsonl");
    for (int k = 0; k < 5; ++k)
      out << json{{"stamp_ns", 2'000'000'000LL + k * 40'000'000LL},
                  {"primitive", "checkMutualGaze"},
                  {"id", "F1"},
                  {"status", "ok"},
                  {"value", {{"mutual", k >= 2}, {"held_s", 0.0}, {"target", "robot"}}}}
                 .dump()
          << "\n";
  }
  CsvTablesOptions o;
  o.markers.push_back({2'150'000'000LL, "child, laughing", "operator_page", "marker 2"});
  o.markers.push_back({2'010'000'000LL, "mark", "operator_page", "marker 1"});
  ASSERT_TRUE(write_csv_tables(dir / "primitives.jsonl", dir / "tables", o));
  std::ifstream in(dir / "tables" / "events.csv");
  std::stringstream ss;
  ss << in.rdbuf();
  EXPECT_EQ(ss.str(),
            "type,label,start_s,end_s,duration_s,source,detail\n"
            "marker,mark,0.010,0.010,0.000,operator_page,marker 1\n"
            "mutual_gaze,looking at robot,0.080,0.200,0.120,,\n"
            "marker,\"child, laughing\",0.150,0.150,0.000,operator_page,marker 2\n");
  fs::remove_all(dir);
}

}  // namespace
}  // namespace dreamsense::exporters
