#pragma once
// PocketSphinx's quantised mixture weights (`sendump`) <-> SphinxTrain's float
// `mixture_weights`. Adaptation with sphinxtrain's bw needs the float form; Debian's models ship
// only the sendump. Format as read by pocketsphinx s2_semi_mgau.c / ptm_mgau.c read_sendump():
// int32 length-prefixed header strings (byte order found from the first length), keys
// feature_count, mixture_count (densities), model_count (senones), cluster_count, cluster_bits,
// mixw_shift, logbase; then either the 16 centroid bytes of 4-bit clustered weights
// (cluster_count > 0) or two int32 (rows, columns); then, per feature and density, one value
// per senone (8 bit, or 4 bit: senone n in the low nibble of byte n/2 when n is even). A value
// v stands for p = logbase^-(v << mixw_shift).

#include "dreamsense/core/status.hpp"

#include <filesystem>
#include <vector>

namespace dreamsense::speech::detail {

struct MixtureWeights {
  int senones = 0, features = 0, densities = 0;
  std::vector<float> weights;  // [senone][feature][density], each (senone, feature) sums to 1
  float at(int senone, int feature, int density) const {
    return weights[(static_cast<size_t>(senone) * features + feature) * densities + density];
  }
};

Result<MixtureWeights> read_sendump(const std::filesystem::path& path);

// SphinxTrain's s3 binary format ("s3" header, byte-order magic, 4 int32 dimensions, float32).
Status write_mixture_weights(const MixtureWeights& m, const std::filesystem::path& path);

}  // namespace dreamsense::speech::detail
