#pragma once
// Minimum-cost assignment (Hungarian method, Kuhn 1955 / Munkres 1957, O(n^3)) with a gate.

#include <vector>

namespace dreamsense::face_tracks {

// cost[r][c] >= 0 for every row r and column c (all rows the same length). Pairs whose cost
// exceeds `max_cost` are never matched. Returns, per row, the matched column or -1.
// Among assignments, the one with the most matched pairs is chosen, then the smallest total cost.
// The result is deterministic for a given matrix.
std::vector<int> min_cost_assignment(const std::vector<std::vector<double>>& cost, double max_cost);

}  // namespace dreamsense::face_tracks
