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
