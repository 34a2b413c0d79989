#include "plugins/omt/algorithms/tsp.h"

#include <algorithm>
#include <limits>
#include <utility>

namespace voxplan::omt {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kGain = 1e-9;

// Prim's MST on the complete graph, O(n²); edges as (parent, child).
std::vector<std::pair<int, int>> MinimumSpanningTree(const DistanceMatrix& d) {
  const int n = d.rows;
  std::vector<std::pair<int, int>> edges;
  std::vector<double> key(n, kInf);
  std::vector<int> parent(n, -1);
  std::vector<bool> in(n, false);
  key[0] = 0.0;
  for (int it = 0; it < n; ++it) {
    int u = -1;
    for (int v = 0; v < n; ++v)
      if (!in[v] && (u < 0 || key[v] < key[u])) u = v;
    in[u] = true;
    if (parent[u] >= 0) edges.emplace_back(parent[u], u);
    for (int v = 0; v < n; ++v) {
      if (!in[v] && d(u, v) < key[v]) {
        key[v] = d(u, v);
        parent[v] = u;
      }
    }
  }
  return edges;
}

// Minimum-weight perfect matching on an even vertex set: bitmask DP when small, else greedy
// over edges sorted by weight.
std::vector<std::pair<int, int>> PerfectMatching(const DistanceMatrix& d,
                                                 const std::vector<int>& verts) {
  const int m = static_cast<int>(verts.size());
  std::vector<std::pair<int, int>> out;
  if (m == 0) return out;
  if (m <= kExactMatchingMax) {
    const int full = (1 << m) - 1;
    std::vector<double> best(static_cast<std::size_t>(full) + 1, kInf);
    std::vector<int> choice(static_cast<std::size_t>(full) + 1, -1);
    best[0] = 0.0;
    // best[mask] = min matching of the vertices in mask; the lowest vertex pairs with some j.
    for (int mask = 1; mask <= full; ++mask) {
      if (__builtin_popcount(static_cast<unsigned>(mask)) % 2) continue;
      const int i = __builtin_ctz(static_cast<unsigned>(mask));
      for (int j = i + 1; j < m; ++j) {
        if (!(mask & (1 << j))) continue;
        const int rest = mask & ~(1 << i) & ~(1 << j);
        const double c = best[rest] + d(verts[i], verts[j]);
        if (c < best[mask]) {
          best[mask] = c;
          choice[mask] = j;
        }
      }
    }
    for (int mask = full; mask;) {
      const int i = __builtin_ctz(static_cast<unsigned>(mask));
      const int j = choice[mask];
      out.emplace_back(verts[i], verts[j]);
      mask &= ~(1 << i) & ~(1 << j);
    }
    return out;
  }
  std::vector<std::pair<int, int>> pairs;
  for (int i = 0; i < m; ++i)
    for (int j = i + 1; j < m; ++j) pairs.emplace_back(i, j);
  std::stable_sort(pairs.begin(), pairs.end(), [&](const auto& a, const auto& b) {
    return d(verts[a.first], verts[a.second]) < d(verts[b.first], verts[b.second]);
  });
  std::vector<bool> used(m, false);
  for (const auto& [i, j] : pairs) {
    if (used[i] || used[j]) continue;
    used[i] = used[j] = true;
    out.emplace_back(verts[i], verts[j]);
  }
  return out;
}

// Hierholzer on a multigraph given as an edge list; returns the vertex sequence from start.
std::vector<int> EulerPath(int n, const std::vector<std::pair<int, int>>& edges, int start) {
  std::vector<std::vector<std::pair<int, int>>> adj(n);  // (neighbour, edge id)
  for (int e = 0; e < static_cast<int>(edges.size()); ++e) {
    adj[edges[e].first].emplace_back(edges[e].second, e);
    adj[edges[e].second].emplace_back(edges[e].first, e);
  }
  std::vector<bool> used(edges.size(), false);
  std::vector<std::size_t> next(n, 0);
  std::vector<int> stack{start};
  std::vector<int> path;
  while (!stack.empty()) {
    const int v = stack.back();
    while (next[v] < adj[v].size() && used[adj[v][next[v]].second]) ++next[v];
    if (next[v] == adj[v].size()) {
      path.push_back(v);
      stack.pop_back();
    } else {
      const auto [w, e] = adj[v][next[v]];
      used[e] = true;
      stack.push_back(w);
    }
  }
  std::reverse(path.begin(), path.end());
  return path;
}

// 2-opt (reverse order[i..j]) and Or-opt (move 1–3 node segments) with fixed endpoints.
void ImprovePath(const DistanceMatrix& d, std::vector<int>* order, int max_passes) {
  std::vector<int>& o = *order;
  const int n = static_cast<int>(o.size());
  if (n < 4) return;
  bool improved = true;
  for (int pass = 0; improved && pass < max_passes; ++pass) {
    improved = false;
    for (int i = 1; i < n - 2; ++i) {
      for (int j = i + 1; j < n - 1; ++j) {
        const double delta =
            d(o[i - 1], o[j]) + d(o[i], o[j + 1]) - d(o[i - 1], o[i]) - d(o[j], o[j + 1]);
        if (delta < -kGain) {
          std::reverse(o.begin() + i, o.begin() + j + 1);
          improved = true;
        }
      }
    }
    for (int len = 1; len <= 3; ++len) {
      for (int i = 1; i + len < n; ++i) {  // segment o[i .. i+len-1], never the end node
        const int a = o[i - 1];
        const int s0 = o[i];
        const int s1 = o[i + len - 1];
        const int b = o[i + len];
        const double removed = d(a, s0) + d(s1, b) - d(a, b);
        // Insert between o[j-1] and o[j] outside the segment, forward or reversed.
        for (int j = 1; j < n; ++j) {
          if (j >= i && j <= i + len) continue;
          const int p = o[j - 1];
          const int q = o[j];
          const double fwd = d(p, s0) + d(s1, q) - d(p, q);
          const double rev = d(p, s1) + d(s0, q) - d(p, q);
          const bool reversed = rev < fwd;
          if (std::min(fwd, rev) - removed < -kGain) {
            std::vector<int> seg(o.begin() + i, o.begin() + i + len);
            if (reversed) std::reverse(seg.begin(), seg.end());
            o.erase(o.begin() + i, o.begin() + i + len);
            const int at = j > i ? j - len : j;
            o.insert(o.begin() + at, seg.begin(), seg.end());
            improved = true;
            break;
          }
        }
      }
    }
  }
}

}  // namespace

double PathLength(const DistanceMatrix& d, const std::vector<int>& order) {
  double len = 0.0;
  for (std::size_t i = 1; i < order.size(); ++i) len += d(order[i - 1], order[i]);
  return len;
}

std::vector<int> OpenPathChristofides(const DistanceMatrix& d, int start, int end,
                                      const TspParams& params) {
  const int n = d.rows;
  if (n <= 0) return {};
  if (n == 1) return {start};
  if (n == 2) return {start, end};
  std::vector<std::pair<int, int>> edges = MinimumSpanningTree(d);
  std::vector<int> degree(n, 0);
  for (const auto& [a, b] : edges) {
    ++degree[a];
    ++degree[b];
  }
  // Odd vertices with start and end flipped, so the multigraph has odd degree exactly there.
  std::vector<int> odd;
  for (int v = 0; v < n; ++v) {
    const bool flip = v == start || v == end;
    if ((degree[v] % 2 == 1) != flip) odd.push_back(v);
  }
  for (const auto& e : PerfectMatching(d, odd)) edges.push_back(e);
  const std::vector<int> euler = EulerPath(n, edges, start);
  std::vector<int> order;
  std::vector<bool> seen(n, false);
  seen[end] = true;  // end is appended last whatever the Euler path's shortcuts do
  for (int v : euler) {
    if (seen[v]) continue;
    seen[v] = true;
    order.push_back(v);
  }
  order.push_back(end);
  if (params.local_search) ImprovePath(d, &order, params.max_passes);
  return order;
}

std::vector<int> OpenPathHeldKarp(const DistanceMatrix& d, int start, int end) {
  const int n = d.rows;
  if (n <= 0 || n > kHeldKarpMax) return {};
  if (n == 1) return {start};
  if (n == 2) return {start, end};
  // Subsets of the interior nodes (all but start and end).
  std::vector<int> inner;
  for (int v = 0; v < n; ++v)
    if (v != start && v != end) inner.push_back(v);
  const int m = static_cast<int>(inner.size());
  const int full = (1 << m) - 1;
  // cost[mask][j]: shortest path start → ... → inner[j] visiting exactly mask.
  std::vector<double> cost(static_cast<std::size_t>(full + 1) * m, kInf);
  std::vector<int> parent(static_cast<std::size_t>(full + 1) * m, -1);
  auto at = [m](int mask, int j) { return static_cast<std::size_t>(mask) * m + j; };
  for (int j = 0; j < m; ++j) cost[at(1 << j, j)] = d(start, inner[j]);
  for (int mask = 1; mask <= full; ++mask) {
    for (int j = 0; j < m; ++j) {
      if (!(mask & (1 << j)) || cost[at(mask, j)] == kInf) continue;
      for (int k = 0; k < m; ++k) {
        if (mask & (1 << k)) continue;
        const int next = mask | (1 << k);
        const double c = cost[at(mask, j)] + d(inner[j], inner[k]);
        if (c < cost[at(next, k)]) {
          cost[at(next, k)] = c;
          parent[at(next, k)] = j;
        }
      }
    }
  }
  int last = -1;
  double best = kInf;
  for (int j = 0; j < m; ++j) {
    const double c = cost[at(full, j)] + d(inner[j], end);
    if (c < best) {
      best = c;
      last = j;
    }
  }
  std::vector<int> order{end};
  for (int mask = full, j = last; j >= 0;) {
    order.push_back(inner[j]);
    const int pj = parent[at(mask, j)];
    mask &= ~(1 << j);
    j = pj;
  }
  order.push_back(start);
  std::reverse(order.begin(), order.end());
  return order;
}

std::vector<int> OpenPathGreedy(const DistanceMatrix& d, int start) {
  const int n = d.rows;
  std::vector<int> order;
  if (n <= 0) return order;
  std::vector<bool> seen(n, false);
  int v = start;
  seen[v] = true;
  order.push_back(v);
  for (int it = 1; it < n; ++it) {
    int best = -1;
    for (int w = 0; w < n; ++w)
      if (!seen[w] && (best < 0 || d(v, w) < d(v, best))) best = w;
    seen[best] = true;
    order.push_back(best);
    v = best;
  }
  return order;
}

}  // namespace voxplan::omt
