// The renumbering of a distributed solve (fem/solvers/distributed.hpp): every rank owns a
// contiguous range of nodes, in the old order within a rank; and without an MPI launcher the
// distributed mode is off.
#include <gtest/gtest.h>

#include "fem/solvers/distributed.hpp"
#include "meshing/core/error.hpp"

using namespace curvefem::fem::distributed;

TEST(DistributedRenumbering, RanksOwnContiguousRangesInTheOldOrder) {
  const std::vector<int> owner = {1, 0, 2, 1, 0, 0, 2};
  const Renumbering r = renumber_by_owner(owner, 3);
  EXPECT_EQ(r.offsets, (std::vector<int>{0, 3, 5, 7}));
  EXPECT_EQ(r.new_of, (std::vector<int>{3, 0, 5, 4, 1, 2, 6}));
  EXPECT_EQ(r.old_of, (std::vector<int>{1, 4, 5, 0, 3, 2, 6}));
  for (std::size_t i = 0; i < owner.size(); ++i) {
    EXPECT_EQ(r.old_of[std::size_t(r.new_of[i])], int(i));
    const int k = r.new_of[i];
    EXPECT_GE(k, r.offsets[std::size_t(owner[i])]);
    EXPECT_LT(k, r.offsets[std::size_t(owner[i]) + 1]);
  }
}

TEST(DistributedRenumbering, AnEmptyRankAndABadOwner) {
  const Renumbering r = renumber_by_owner({0, 0, 2}, 3);
  EXPECT_EQ(r.offsets, (std::vector<int>{0, 2, 2, 3}));
  EXPECT_THROW(renumber_by_owner({0, 3}, 3), curvefem::SolverError);
  EXPECT_THROW(renumber_by_owner({-1}, 2), curvefem::SolverError);
}

TEST(DistributedRenumbering, OffWithoutStart) {
  EXPECT_FALSE(active());
  EXPECT_EQ(size(), 1);
  EXPECT_EQ(rank(), 0);
  const std::vector<double> rss = peak_rss_mb_per_rank();  // one rank: no message
  ASSERT_EQ(rss.size(), 1u);
  EXPECT_GT(rss[0], 0.0);
}

// The memory balance's shares: every rank ends at one level heap + share · solve, rank 0's larger
// heap gets it fewer rows, and the floor holds when one heap alone is above the level.
TEST(DistributedRenumbering, MemoryBalancedSharesEvenOutTheRanksPeaks) {
  using curvefem::fem::distributed::memory_balanced_shares;
  // Rank 0 holds 150 MiB more; the solver needs 1000 MiB: 0.425 and 0.575, both at 575 MiB.
  std::vector<double> s = memory_balanced_shares({154, 4}, 1000, 0.1);
  ASSERT_EQ(s.size(), 2u);
  EXPECT_NEAR(s[0], 0.425, 1e-12);
  EXPECT_NEAR(s[1], 0.575, 1e-12);
  EXPECT_NEAR(154 + 1000 * s[0], 4 + 1000 * s[1], 1e-9);
  // Three ranks, two of them equal.
  s = memory_balanced_shares({300, 0, 0}, 900, 0.0);
  EXPECT_NEAR(s[0], 1.0 / 9.0, 1e-12);
  EXPECT_NEAR(s[1], 4.0 / 9.0, 1e-12);
  EXPECT_NEAR(s[2], 4.0 / 9.0, 1e-12);
  // A heap above the whole level: that rank keeps the floor, the others share the rest.
  s = memory_balanced_shares({5000, 10, 30}, 600, 0.05);
  EXPECT_NEAR(s[0], 0.05, 1e-12);
  EXPECT_NEAR(s[0] + s[1] + s[2], 1.0, 1e-12);
  EXPECT_NEAR(10 + 600 * s[1], 30 + 600 * s[2], 1e-9);
  // Equal heaps or no estimate: equal shares.
  for (const auto& v :
       {memory_balanced_shares({50, 50}, 800, 0.1), memory_balanced_shares({150, 4}, 0, 0.1)})
    for (double x : v) EXPECT_DOUBLE_EQ(x, 0.5);
}
