#include "dreamsense/batch/table.hpp"

#include <gtest/gtest.h>

#include "test_util.hpp"

namespace dreamsense::batch {
namespace {

using test::parse_csv;

TEST(Table, Rfc4180Quoting) {
  EXPECT_EQ(csv_cell("plain text"), "plain text");
  EXPECT_EQ(csv_cell("a,b"), "\"a,b\"");
  EXPECT_EQ(csv_cell("say \"hi\""), "\"say \"\"hi\"\"\"");
  EXPECT_EQ(csv_cell("two\nlines"), "\"two\nlines\"");
  EXPECT_EQ(csv_cell("cr\r"), "\"cr\r\"");
  EXPECT_EQ(csv_cell(""), "");
  EXPECT_EQ(csv_row({"a", "b,c", ""}), "a,\"b,c\",\n");
}

TEST(Table, FlattenNestedScalarsAndArrays) {
  const auto j = nlohmann::json::parse(R"({
    "ticks": 75, "media_seconds": 3.0, "session": "seed 1", "flag": true, "none": null,
    "analyzers": ["face", "gaze"],
    "status_counts": {"sessionDetect": {"ok": 70, "absent": 5}},
    "stages": [{"name": "face", "calls": 75}],
    "status": "would collide", "seconds": 9
  })");
  std::map<std::string, std::string> f;
  flatten_json(j, f);
  EXPECT_EQ(f.at("ticks"), "75");
  EXPECT_EQ(f.at("media_seconds"), "3.0");
  EXPECT_EQ(f.at("session"), "seed 1");
  EXPECT_EQ(f.at("flag"), "true");
  EXPECT_EQ(f.at("none"), "");
  EXPECT_EQ(f.at("analyzers"), "face;gaze");
  EXPECT_EQ(f.at("status_counts.sessionDetect.ok"), "70");
  EXPECT_EQ(f.at("status_counts.sessionDetect.absent"), "5");
  EXPECT_EQ(f.count("stages"), 0u);  // arrays of objects are detail, not figures
  EXPECT_EQ(f.at("summary.status"), "would collide");
  EXPECT_EQ(f.at("summary.seconds"), "9");
  EXPECT_EQ(f.count("status"), 0u);
}

TEST(Table, ColumnsAreTheUnionAndCellsReadBack) {
  std::vector<TableRow> rows(3);
  rows[0] = {"/in/a", "a-1", "ok", "", 1.5, {{"ticks", "10"}, {"x.y", "1"}}};
  rows[1] = {"/in/b,with comma", "", "failed", "bad \"session.yaml\"\nline 2", std::nullopt, {}};
  rows[2] = {"/in/c", "c-3", "ok", "", 2.0, {{"ticks", "20"}, {"z", "q"}}};
  const std::string text = format_table(rows);
  const auto cells = parse_csv(text);
  ASSERT_EQ(cells.size(), 4u) << text;
  const std::vector<std::string> header = {"input",   "output", "status", "reason",
                                           "seconds", "ticks",  "x.y",    "z"};
  EXPECT_EQ(cells[0], header);
  EXPECT_EQ(cells[1], (std::vector<std::string>{"/in/a", "a-1", "ok", "", "1.500", "10", "1", ""}));
  EXPECT_EQ(cells[2], (std::vector<std::string>{"/in/b,with comma", "", "failed",
                                                "bad \"session.yaml\"\nline 2", "", "", "", ""}));
  EXPECT_EQ(cells[3], (std::vector<std::string>{"/in/c", "c-3", "ok", "", "2.000", "20", "", "q"}));
}

TEST(Table, NoRowsStillHasTheHeader) {
  EXPECT_EQ(format_table({}), "input,output,status,reason,seconds\n");
}

}  // namespace
}  // namespace dreamsense::batch
