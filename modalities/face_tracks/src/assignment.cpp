#include "dreamsense/face_tracks/assignment.hpp"

#include "dreamsense/core/status.hpp"

#include <algorithm>
#include <limits>

namespace dreamsense::face_tracks {

std::vector<int> min_cost_assignment(const std::vector<std::vector<double>>& cost,
                                     double max_cost) {
  const size_t rows = cost.size();
  const size_t cols = rows == 0 ? 0 : cost[0].size();
  std::vector<int> result(rows, -1);
  if (rows == 0 || cols == 0) return result;
  for (const auto& r : cost) DS_CHECK_EQ(r.size(), cols);

  // Square matrix; out-of-gate pairs and padding cost `big`, which exceeds any sum of gated
  // costs, so minimising the total first maximises the number of gated matches.
  const size_t n = std::max(rows, cols);
  double gated_sum = 0;
  for (const auto& r : cost)
    for (double c : r)
      if (c <= max_cost) gated_sum += c;
  const double big = 2 * gated_sum + 1;
  std::vector<std::vector<double>> a(n, std::vector<double>(n, big));
  for (size_t r = 0; r < rows; ++r)
    for (size_t c = 0; c < cols; ++c) {
      DS_CHECK_GE(cost[r][c], 0.0);
      if (cost[r][c] <= max_cost) a[r][c] = cost[r][c];
    }

  // Potentials formulation (1-based, column 0 is a sentinel).
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> u(n + 1, 0), v(n + 1, 0);
  std::vector<size_t> p(n + 1, 0), way(n + 1, 0);
  for (size_t i = 1; i <= n; ++i) {
    p[0] = i;
    size_t j0 = 0;
    std::vector<double> minv(n + 1, inf);
    std::vector<bool> used(n + 1, false);
    do {
      used[j0] = true;
      const size_t i0 = p[j0];
      double delta = inf;
      size_t j1 = 0;
      for (size_t j = 1; j <= n; ++j) {
        if (used[j]) continue;
        const double cur = a[i0 - 1][j - 1] - u[i0] - v[j];
        if (cur < minv[j]) {
          minv[j] = cur;
          way[j] = j0;
        }
        if (minv[j] < delta) {
          delta = minv[j];
          j1 = j;
        }
      }
      for (size_t j = 0; j <= n; ++j) {
        if (used[j]) {
          u[p[j]] += delta;
          v[j] -= delta;
        } else {
          minv[j] -= delta;
        }
      }
      j0 = j1;
    } while (p[j0] != 0);
    do {
      const size_t j1 = way[j0];
      p[j0] = p[j1];
      j0 = j1;
    } while (j0 != 0);
  }
  for (size_t j = 1; j <= n; ++j) {
    const size_t r = p[j] - 1, c = j - 1;
    if (r < rows && c < cols && cost[r][c] <= max_cost) result[r] = static_cast<int>(c);
  }
  return result;
}

}  // namespace dreamsense::face_tracks
