// Per-robot open TSP of §3.5: a Hamiltonian path from the robot (start) to its farthest task
// (end) over a symmetric, metric distance matrix.
//
// The paper closes the path with a forced end → start edge and runs Christofides. We use the
// equivalent fixed-endpoint form (Hoogeveen 1991): MST, minimum-weight perfect matching on the
// MST's odd vertices with the parity of start and end flipped, an Euler path start → end,
// shortcuts. The matching is exact (bitmask DP) up to kExactMatchingMax odd vertices, which
// keeps Hoogeveen's 5/3 bound; beyond that it is greedy and the bound is not guaranteed. 2-opt
// and Or-opt then only shorten the path.
#pragma once

#include <vector>

#include "plugins/omt/algorithms/types.h"

namespace voxplan::omt {

inline constexpr int kExactMatchingMax = 16;
inline constexpr int kHeldKarpMax = 16;

struct TspParams {
  bool local_search = true;  // 2-opt + Or-opt after Christofides
  int max_passes = 50;
};

// Node order start, ..., end visiting all n nodes of dist (n × n). start == end is allowed
// only for n == 1.
std::vector<int> OpenPathChristofides(const DistanceMatrix& dist, int start, int end,
                                      const TspParams& params = {});
// Exact Held–Karp DP; empty when n > kHeldKarpMax.
std::vector<int> OpenPathHeldKarp(const DistanceMatrix& dist, int start, int end);
// NoTSP ablation: from start, always the nearest unvisited node (ties to the lower index).
std::vector<int> OpenPathGreedy(const DistanceMatrix& dist, int start);

double PathLength(const DistanceMatrix& dist, const std::vector<int>& order);

}  // namespace voxplan::omt
