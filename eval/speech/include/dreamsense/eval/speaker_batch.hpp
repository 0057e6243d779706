#pragma once
// Unsupervised batch speaker adaptation for isolated-word evaluation (FSDD): the clips of one
// speaker are decoded one by one (per-word recogniser scores), then each clip's word posterior
// is combined with those of its nearest neighbours *of the same speaker* (DTW distance between
// MFCC sequences). One person saying the same word twice sounds far more alike than two
// people saying it, so a clip the recogniser is unsure of borrows the evidence of the clips
// that sound like it. No labels are used; see README.md (FSDD) for the protocol and numbers.

#include <cstdint>
#include <span>
#include <vector>

namespace dreamsense::speech {

// One clip's features for DTW: rows = 10 ms frames, 26 columns: c0 (log energy relative to the
// clip's loudest frame), c1..c12 minus the clip mean (24 mel filters, 100-3800 Hz, 25 ms
// Hamming window, pre-emphasis 0.97), and the 13 deltas (+-2 frames). Any rate >= 8 kHz.
using DtwFeatures = std::vector<std::vector<float>>;
DtwFeatures dtw_features(std::span<const int16_t> samples, int sample_rate_hz);

// Symmetric DTW (steps (1,0), (0,1), (1,1)), Euclidean frame distance, total cost divided by
// (rows a + rows b). 0 for identical sequences; +inf when either is empty (such a clip has no
// neighbours in the vote).
double dtw_distance(const DtwFeatures& a, const DtwFeatures& b);

struct NeighbourVoteOptions {
  // Softmax temperature of the per-frame word scores (PocketSphinx log units per 10 ms frame).
  double temperature = 5.0;
  int neighbours = 10;  // at most k nearest clips of the same speaker ...
  // ... and only those within this factor of the nearest one's distance, so that a speaker
  // with few takes per word is not outvoted by other words (1.15: ~9 neighbours, 98 % of
  // them the same word, with 50 takes per word; ~3 with 5 takes).
  double max_distance_ratio = 1.15;
  double weight = 3.0;  // total weight of the neighbours' log posteriors (own clip: 1)
};

// scores[i][w]: clip i's score for word class w (per frame; higher = better; -inf allowed for
// "no path"). distances: symmetric N x N. Returns, per clip, the class maximising
//   log p_i(w) + weight / |V| * sum_{j in V} log p_j(w),  V = the neighbours kept (above),
// p = softmax(scores / temperature). With N = 1 or weight 0: the per-clip argmax; -1 for a
// clip with no finite score and no neighbour.
std::vector<int> neighbour_vote(const std::vector<std::vector<double>>& scores,
                                const std::vector<std::vector<double>>& distances,
                                const NeighbourVoteOptions& options = {});

}  // namespace dreamsense::speech
