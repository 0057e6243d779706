#pragma once
// Readers of the face datasets (spec/cli.md `--dataset NAME DIR`). Every reader checks the
// layout and names the first offending file or folder; hidden files and top-level notes
// (*.txt, *.md, README) are ignored.
//   ckplus48  DIR/<emotion>/S###_###_########.png (CK+48 crops; subject = S###)
//   fer2013   DIR/<class>/*.jpg|png, classes angry, disgust, fear, happy, neutral, sad, surprise
//             (every image its own "subject": FER2013 has no subject ids)
//   att       DIR/sN/M.pgm (AT&T / ORL)
//   yale      DIR/subjectNN.condition (Yale faces, GIF; a trailing image extension is accepted;
//             the UCSD archive's "subject01.gif" stands for subject01.centerlight)
// Items come sorted: subjects and images in natural order (numbers compared numerically:
// s2 < s10, 2.pgm < 10.pgm); Yale by condition name.

#include "dreamsense/core/status.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace dreamsense::eval::faces {

struct FaceImageItem {
  std::filesystem::path path;
  std::string subject;  // person id within the dataset ("S010", "s7", "subject03", ...)
  std::string label;    // expression datasets: canonical expression label; identity: = subject
};

inline constexpr const char* kExpressionDatasets[] = {"ckplus48", "fer2013"};
inline constexpr const char* kIdentityDatasets[] = {"att", "yale"};

Result<std::vector<FaceImageItem>> read_ckplus48(const std::filesystem::path& dir);
Result<std::vector<FaceImageItem>> read_fer2013(const std::filesystem::path& dir);
Result<std::vector<FaceImageItem>> read_att(const std::filesystem::path& dir);
Result<std::vector<FaceImageItem>> read_yale(const std::filesystem::path& dir);

// By --dataset name; an unknown name is an error listing the supported ones.
Result<std::vector<FaceImageItem>> read_expression_dataset(const std::string& name,
                                                           const std::filesystem::path& dir);
Result<std::vector<FaceImageItem>> read_identity_dataset(const std::string& name,
                                                         const std::filesystem::path& dir);

// Natural order of names: digit runs compare as numbers, the rest character by character.
bool natural_less(const std::string& a, const std::string& b);

}  // namespace dreamsense::eval::faces
