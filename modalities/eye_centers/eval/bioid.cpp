#include "bioid.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

namespace dreamsense::eye_centers {

Result<BioIdEyes> read_bioid_eye_file(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) return make_error(ErrorCode::kNotFound, "{}: cannot open", path.string());
  std::string line, numbers;
  while (std::getline(in, line)) {
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    numbers += line + " ";
  }
  std::istringstream s(numbers);
  double v[4];
  for (double& x : v)
    if (!(s >> x) || !std::isfinite(x))
      return make_error(ErrorCode::kCorruptData, "{}: expected four numbers LX LY RX RY",
                        path.string());
  return BioIdEyes{{v[0], v[1]}, {v[2], v[3]}};
}

Status write_bioid_eye_file(const std::filesystem::path& path, const BioIdEyes& e) {
  std::ofstream out(path);
  if (!out) return make_error(ErrorCode::kIoError, "{}: cannot write", path.string());
  out << fmt::format("#LX\tLY\tRX\tRY\n{:.2f}\t{:.2f}\t{:.2f}\t{:.2f}\n", e.left_px.x, e.left_px.y,
                     e.right_px.x, e.right_px.y);
  if (!out) return make_error(ErrorCode::kIoError, "{}: write failed", path.string());
  return ok_status();
}

Result<std::vector<BioIdItem>> load_bioid(const std::filesystem::path& dir) {
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec))
    return make_error(ErrorCode::kNotFound, "{}: not a directory", dir.string());
  std::vector<BioIdItem> items;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    const std::filesystem::path& p = entry.path();
    const std::string name = p.filename().string();
    if (p.extension() != ".pgm" || name.rfind("BioID_", 0) != 0) continue;
    BioIdItem item;
    item.id = p.stem().string();
    item.image = p;
    std::filesystem::path eye = p;
    eye.replace_extension(".eye");
    auto eyes = read_bioid_eye_file(eye);
    if (!eyes)
      return make_error(ErrorCode::kCorruptData, "BioID {}: no usable truth ({})", item.id,
                        eyes.error().message);
    item.eyes = *eyes;
    items.push_back(std::move(item));
  }
  if (ec) return make_error(ErrorCode::kIoError, "{}: {}", dir.string(), ec.message());
  if (items.empty())
    return make_error(ErrorCode::kNotFound, "{}: no BioID_*.pgm images", dir.string());
  std::sort(items.begin(), items.end(),
            [](const BioIdItem& a, const BioIdItem& b) { return a.id < b.id; });
  return items;
}

}  // namespace dreamsense::eye_centers
