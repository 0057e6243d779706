#include "sendump.hpp"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>

namespace dreamsense::speech::detail {
namespace {

class Reader {
 public:
  explicit Reader(const std::filesystem::path& p) : in_(p, std::ios::binary) {}
  bool open() const { return static_cast<bool>(in_); }
  void set_swap(bool s) { swap_ = s; }
  bool int32(int32_t& v) {
    uint32_t u = 0;
    if (!in_.read(reinterpret_cast<char*>(&u), 4)) return false;
    if (swap_) u = __builtin_bswap32(u);
    v = static_cast<int32_t>(u);
    return true;
  }
  bool bytes(void* dst, size_t n) {
    return static_cast<bool>(in_.read(static_cast<char*>(dst), static_cast<std::streamsize>(n)));
  }
  bool at_end() { return in_.peek() == std::char_traits<char>::eof(); }

 private:
  std::ifstream in_;
  bool swap_ = false;
};

}  // namespace

Result<MixtureWeights> read_sendump(const std::filesystem::path& path) {
  Reader r(path);
  if (!r.open()) return make_error(ErrorCode::kNotFound, "cannot read {}", path.string());
  auto corrupt = [&](const std::string& why) {
    return make_error(ErrorCode::kCorruptData, "{}: not a PocketSphinx sendump ({})", path.string(),
                      why);
  };
  int32_t first = 0;
  if (!r.int32(first)) return corrupt("empty");
  if (first < 1 || first > 999) {
    // The header strings are short: a huge length means the other byte order.
    r = Reader(path);
    r.set_swap(true);
    r.int32(first);
    if (first < 1 || first > 999) return corrupt("bad header");
  }
  int features = 0, densities = 0, senones = 0, clusters = 0, bits = 8, shift = 10;
  double logbase = 1.0001;
  for (int32_t n = first; n != 0;) {
    if (n < 0 || n > 4096) return corrupt("bad header string length");
    std::string s(static_cast<size_t>(n), '\0');
    if (!r.bytes(s.data(), s.size())) return corrupt("truncated header");
    s = s.c_str();  // strings are NUL-terminated inside their length
    auto value = [&](const char* key) -> const char* {
      const size_t l = std::strlen(key);
      return s.compare(0, l, key) == 0 ? s.c_str() + l : nullptr;
    };
    if (auto v = value("feature_count ")) features = std::atoi(v);
    if (auto v = value("mixture_count ")) densities = std::atoi(v);
    if (auto v = value("model_count ")) senones = std::atoi(v);
    if (auto v = value("cluster_count ")) clusters = std::atoi(v);
    if (auto v = value("cluster_bits ")) bits = std::atoi(v);
    if (auto v = value("mixw_shift ")) shift = std::atoi(v);
    if (auto v = value("logbase ")) logbase = std::atof(v);
    if (!r.int32(n)) return corrupt("truncated header");
  }
  if (bits != 4 && bits != 8) return corrupt("cluster_bits must be 4 or 8");
  if (clusters == 0) {
    // Unclustered weights carry their dimensions (densities x senones) here; older files (e.g.
    // Debian's en-us) name neither in the header.
    int32_t rows = 0, columns = 0;
    if (!r.int32(rows) || !r.int32(columns)) return corrupt("truncated dimensions");
    if ((densities > 0 && rows != densities) || (senones > 0 && columns != senones))
      return corrupt("dimensions disagree with header");
    densities = rows;
    senones = columns;
  }
  if (features <= 0 || densities <= 0 || senones <= 0 || densities > 4096 || senones > 1000000)
    return corrupt("feature_count, mixture_count or model_count missing or implausible");
  std::vector<uint8_t> centroids;
  if (clusters > 0) {
    if (clusters == 15) clusters = 16;  // written as 15 by some tools, 16 values follow
    centroids.resize(static_cast<size_t>(clusters));
    if (!r.bytes(centroids.data(), centroids.size())) return corrupt("truncated centroids");
  }
  MixtureWeights m;
  m.senones = senones;
  m.features = features;
  m.densities = densities;
  m.weights.assign(static_cast<size_t>(senones) * features * densities, 0.f);
  const size_t row_bytes = bits == 4 ? (static_cast<size_t>(senones) + 1) / 2 : senones;
  std::vector<uint8_t> row(row_bytes);
  for (int f = 0; f < features; ++f)
    for (int d = 0; d < densities; ++d) {
      if (!r.bytes(row.data(), row.size())) return corrupt("truncated weights");
      for (int s = 0; s < senones; ++s) {
        int v = row[static_cast<size_t>(bits == 4 ? s / 2 : s)];
        if (bits == 4) {
          const int code = (s & 1) ? (v >> 4) : (v & 0x0f);
          if (code >= static_cast<int>(centroids.size())) return corrupt("bad cluster index");
          v = centroids[static_cast<size_t>(code)];
        }
        m.weights[(static_cast<size_t>(s) * features + f) * densities + d] =
            static_cast<float>(std::pow(logbase, -static_cast<double>(v << shift)));
      }
    }
  if (!r.at_end()) return corrupt("trailing bytes");
  // Quantisation leaves each distribution's sum slightly off 1.
  for (size_t i = 0; i < static_cast<size_t>(senones) * features; ++i) {
    double sum = 0;
    for (int d = 0; d < densities; ++d) sum += m.weights[i * densities + d];
    if (sum <= 0) return corrupt("an all-zero distribution");
    for (int d = 0; d < densities; ++d)
      m.weights[i * densities + d] = static_cast<float>(m.weights[i * densities + d] / sum);
  }
  return m;
}

Status write_mixture_weights(const MixtureWeights& m, const std::filesystem::path& path) {
  std::ofstream out(path, std::ios::binary);
  if (!out) return make_error(ErrorCode::kIoError, "cannot write {}", path.string());
  out << "s3\nversion 1.0\nendhdr\n";
  const uint32_t magic = 0x11223344;  // readers swap when they see it reversed
  const int32_t header[4] = {m.senones, m.features, m.densities,
                             static_cast<int32_t>(m.weights.size())};
  out.write(reinterpret_cast<const char*>(&magic), 4);
  out.write(reinterpret_cast<const char*>(header), sizeof header);
  out.write(reinterpret_cast<const char*>(m.weights.data()),
            static_cast<std::streamsize>(m.weights.size() * sizeof(float)));
  if (!out) return make_error(ErrorCode::kIoError, "cannot write {}", path.string());
  return ok_status();
}

}  // namespace dreamsense::speech::detail
