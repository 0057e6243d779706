#include "dreamsense/eval/faces/datasets.hpp"

#include "dreamsense/expression/labels.hpp"

#include <algorithm>
#include <cctype>
#include <map>
#include <regex>

namespace dreamsense::eval::faces {
namespace fs = std::filesystem;
namespace {

bool ignorable(const fs::path& p) {
  const std::string name = p.filename().string();
  if (name.empty() || name[0] == '.') return true;
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  std::string stem = p.stem().string();
  std::transform(stem.begin(), stem.end(), stem.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext == ".txt" || ext == ".md" || stem == "readme" || stem == "license";
}

Result<std::vector<fs::path>> entries(const fs::path& dir, const std::string& dataset) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    return make_error(ErrorCode::kNotFound, "{}: no such {} folder", dir.string(), dataset);
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (!ignorable(e.path())) out.push_back(e.path());
  if (ec)
    return make_error(ErrorCode::kIoError, "{}: cannot list ({})", dir.string(), ec.message());
  std::sort(out.begin(), out.end(), [](const fs::path& a, const fs::path& b) {
    return natural_less(a.filename().string(), b.filename().string());
  });
  return out;
}

bool is_image_extension(std::string ext) {
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".pgm" || ext == ".bmp" ||
         ext == ".gif" || ext == ".tif" || ext == ".tiff";
}

// Class folders of expression images (ckplus48, fer2013).
Result<std::vector<FaceImageItem>> read_class_folders(const fs::path& dir,
                                                      const std::string& dataset,
                                                      const std::regex* name_pattern) {
  auto top = entries(dir, dataset);
  if (!top) return tl::unexpected(top.error());
  std::vector<FaceImageItem> items;
  for (const fs::path& cls : *top) {
    if (!fs::is_directory(cls))
      return make_error(ErrorCode::kUnsupported,
                        "{}: unexpected file in a {} folder (expected class folders only)",
                        cls.string(), dataset);
    const auto label = expression::canonical_label(cls.filename().string());
    if (!label)
      return make_error(ErrorCode::kUnsupported, "{}: '{}' is not an expression class folder of {}",
                        cls.string(), cls.filename().string(), dataset);
    auto files = entries(cls, dataset);
    if (!files) return tl::unexpected(files.error());
    for (const fs::path& f : *files) {
      const std::string name = f.filename().string();
      std::smatch m;
      if (fs::is_directory(f) || !is_image_extension(f.extension().string()) ||
          (name_pattern && !std::regex_match(name, m, *name_pattern)))
        return make_error(ErrorCode::kUnsupported, "{}: not a {} image name", f.string(), dataset);
      FaceImageItem item;
      item.path = f;
      item.label = *label;
      item.subject = name_pattern ? m[1].str() : f.stem().string();
      items.push_back(std::move(item));
    }
  }
  if (items.empty())
    return make_error(ErrorCode::kNotFound, "{}: no {} images (expected DIR/<class>/<image>)",
                      dir.string(), dataset);
  return items;
}

}  // namespace

bool natural_less(const std::string& a, const std::string& b) {
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (std::isdigit(static_cast<unsigned char>(a[i])) &&
        std::isdigit(static_cast<unsigned char>(b[j]))) {
      size_t ie = i, je = j;
      while (ie < a.size() && std::isdigit(static_cast<unsigned char>(a[ie]))) ++ie;
      while (je < b.size() && std::isdigit(static_cast<unsigned char>(b[je]))) ++je;
      std::string na = a.substr(i, ie - i), nb = b.substr(j, je - j);
      na.erase(0, std::min(na.find_first_not_of('0'), na.size()));
      nb.erase(0, std::min(nb.find_first_not_of('0'), nb.size()));
      if (na.size() != nb.size()) return na.size() < nb.size();
      if (na != nb) return na < nb;
      if (ie - i != je - j) return ie - i < je - j;  // fewer leading zeros first
      i = ie, j = je;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i, ++j;
    }
  }
  return a.size() - i < b.size() - j;
}

Result<std::vector<FaceImageItem>> read_ckplus48(const fs::path& dir) {
  static const std::regex kName(R"((S\d{3})_\d{3}_\d{8}\.png)", std::regex::icase);
  return read_class_folders(dir, "ckplus48", &kName);
}

Result<std::vector<FaceImageItem>> read_fer2013(const fs::path& dir) {
  return read_class_folders(dir, "fer2013", nullptr);
}

Result<std::vector<FaceImageItem>> read_att(const fs::path& dir) {
  static const std::regex kSubject(R"(s\d+)");
  static const std::regex kImage(R"(\d+\.pgm)", std::regex::icase);
  auto top = entries(dir, "att");
  if (!top) return tl::unexpected(top.error());
  std::vector<FaceImageItem> items;
  for (const fs::path& s : *top) {
    const std::string subject = s.filename().string();
    if (!fs::is_directory(s) || !std::regex_match(subject, kSubject))
      return make_error(ErrorCode::kUnsupported, "{}: not an AT&T subject folder (expected sN/)",
                        s.string());
    auto files = entries(s, "att");
    if (!files) return tl::unexpected(files.error());
    for (const fs::path& f : *files) {
      if (!std::regex_match(f.filename().string(), kImage))
        return make_error(ErrorCode::kUnsupported, "{}: not an AT&T image (expected sN/M.pgm)",
                          f.string());
      items.push_back({f, subject, subject});
    }
  }
  if (items.empty())
    return make_error(ErrorCode::kNotFound, "{}: no AT&T images (expected DIR/sN/M.pgm)",
                      dir.string());
  return items;
}

Result<std::vector<FaceImageItem>> read_yale(const fs::path& dir) {
  static const std::regex kName(R"((subject\d+)\.([A-Za-z]+)(\.(gif|pgm|png|jpg|bmp))?)",
                                std::regex::icase);
  auto top = entries(dir, "yale");
  if (!top) return tl::unexpected(top.error());
  struct Entry {
    std::string subject, condition;
    fs::path path;
  };
  std::vector<Entry> found;
  for (const fs::path& f : *top) {
    std::smatch m;
    const std::string name = f.filename().string();
    if (fs::is_directory(f) || !std::regex_match(name, m, kName))
      return make_error(ErrorCode::kUnsupported,
                        "{}: not a Yale face file (expected subjectNN.condition)", f.string());
    std::string condition = m[2].str();
    std::transform(condition.begin(), condition.end(), condition.begin(),
                   [](unsigned char c) { return std::tolower(c); });
    if (!m[3].matched && is_image_extension("." + condition)) condition = "centerlight";
    found.push_back({m[1].str(), condition, f});
  }
  std::stable_sort(found.begin(), found.end(), [](const Entry& a, const Entry& b) {
    if (a.subject != b.subject) return natural_less(a.subject, b.subject);
    return a.condition < b.condition;
  });
  std::vector<FaceImageItem> items;
  for (size_t i = 0; i < found.size(); ++i) {
    if (i > 0 && found[i].subject == found[i - 1].subject &&
        found[i].condition == found[i - 1].condition)
      return make_error(ErrorCode::kUnsupported, "{}: second image of {} {}",
                        found[i].path.string(), found[i].subject, found[i].condition);
    items.push_back({found[i].path, found[i].subject, found[i].subject});
  }
  if (items.empty())
    return make_error(ErrorCode::kNotFound, "{}: no Yale images (expected subjectNN.condition)",
                      dir.string());
  return items;
}

Result<std::vector<FaceImageItem>> read_expression_dataset(const std::string& name,
                                                           const fs::path& dir) {
  if (name == "ckplus48") return read_ckplus48(dir);
  if (name == "fer2013") return read_fer2013(dir);
  return make_error(ErrorCode::kInvalidArgument,
                    "--dataset {}: not an expression dataset (ckplus48, fer2013)", name);
}

Result<std::vector<FaceImageItem>> read_identity_dataset(const std::string& name,
                                                         const fs::path& dir) {
  if (name == "att") return read_att(dir);
  if (name == "yale") return read_yale(dir);
  return make_error(ErrorCode::kInvalidArgument,
                    "--dataset {}: not a face identity dataset (att, yale)", name);
}

}  // namespace dreamsense::eval::faces
