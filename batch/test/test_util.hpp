#pragma once
// Small helpers for the batch tests: a temporary folder removed at the end, file writing.

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

namespace dreamsense::batch::test {

class TempDir {
 public:
  TempDir() {
    std::string pattern =
        (std::filesystem::temp_directory_path() / "ds_batch_test.XXXXXX").string();
    if (::mkdtemp(pattern.data()) == nullptr) std::abort();
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& p) const { return path_ / p; }

 private:
  std::filesystem::path path_;
};

inline void write_text(const std::filesystem::path& p, const std::string& text) {
  std::filesystem::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

inline std::string read_text(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

inline void make_session(const std::filesystem::path& dir) {
  write_text(dir / "session.yaml", "version: 1\n");
}

// A strict RFC 4180 reader (the tests' own), to check that what batch writes reads back.
inline std::vector<std::vector<std::string>> parse_csv(const std::string& text) {
  std::vector<std::vector<std::string>> rows(1, std::vector<std::string>(1));
  bool quoted = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    auto& cell = rows.back().back();
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
      rows.back().emplace_back();
    } else if (c == '\n') {
      rows.emplace_back(1);
    } else {
      cell += c;
    }
  }
  if (rows.back().size() == 1 && rows.back()[0].empty()) rows.pop_back();
  return rows;
}

// batch.csv as one map (column -> cell) per row; every row must have the header's width.
inline std::vector<std::map<std::string, std::string>> read_table(const std::filesystem::path& p) {
  const auto cells = parse_csv(read_text(p));
  std::vector<std::map<std::string, std::string>> rows;
  if (cells.empty()) return rows;
  for (size_t r = 1; r < cells.size(); ++r) {
    if (cells[r].size() != cells[0].size())
      throw std::runtime_error(p.string() + ": row " + std::to_string(r) + " has " +
                               std::to_string(cells[r].size()) + " cells, the header " +
                               std::to_string(cells[0].size()));
    std::map<std::string, std::string> row;
    for (size_t c = 0; c < cells[0].size(); ++c) row[cells[0][c]] = cells[r][c];
    rows.push_back(std::move(row));
  }
  return rows;
}

}  // namespace dreamsense::batch::test
