#include <gtest/gtest.h>

#include <queue>
#include <random>

#include "breccia/common/union_find.hpp"

using breccia::UnionFind;

TEST(UnionFind, UniteReportsWhetherSetsWereSeparate) {
  UnionFind uf(4);
  EXPECT_TRUE(uf.unite(0, 1));
  EXPECT_FALSE(uf.unite(1, 0));
  EXPECT_TRUE(uf.unite(2, 3));
  EXPECT_TRUE(uf.unite(0, 3));
  EXPECT_FALSE(uf.unite(1, 2));
  int32_t count = 0;
  const auto label = uf.labels(&count);
  EXPECT_EQ(count, 1);
  EXPECT_EQ(label, std::vector<int32_t>(4, 0));
}

// Reference: breadth-first search over the same random graph.
TEST(UnionFind, ComponentsMatchBreadthFirstSearchOnRandomGraph) {
  const int n = 5000, edges = 4000;  // below the percolation threshold: many components
  std::mt19937 rng(12345);
  std::uniform_int_distribution<int> pick(0, n - 1);
  std::vector<std::vector<int>> adj(n);
  UnionFind uf(n);
  for (int e = 0; e < edges; ++e) {
    const int a = pick(rng), b = pick(rng);
    adj[a].push_back(b);
    adj[b].push_back(a);
    uf.unite(a, b);
  }
  int32_t count = 0;
  const auto label = uf.labels(&count);
  std::vector<int> bfs(n, -1);
  int components = 0;
  for (int s = 0; s < n; ++s) {
    if (bfs[s] >= 0) continue;
    std::queue<int> q;
    q.push(s);
    bfs[s] = components;
    while (!q.empty()) {
      const int v = q.front();
      q.pop();
      for (int w : adj[v])
        if (bfs[w] < 0) { bfs[w] = components; q.push(w); }
    }
    ++components;
  }
  EXPECT_EQ(count, components);
  // Both label by first member, so the labelings agree exactly.
  EXPECT_EQ(label, std::vector<int32_t>(bfs.begin(), bfs.end()));
}
