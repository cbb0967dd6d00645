#include <gtest/gtest.h>

#include "unjam/core/cell.hpp"

namespace unjam {

TEST(Cell, MinimumImageFoldsEachComponentIntoHalfTheCell) {
  const Cell cell{10.0, 8.0};
  const Vec2 d = cell.min_image({9.0, -7.0});
  EXPECT_DOUBLE_EQ(d.x(), -1.0);
  EXPECT_DOUBLE_EQ(d.y(), 1.0);
  const Vec2 e = cell.min_image({4.0, 3.9});
  EXPECT_DOUBLE_EQ(e.x(), 4.0);
  EXPECT_DOUBLE_EQ(e.y(), 3.9);
}

TEST(Cell, WrapPutsPositionsInsideTheCell) {
  const Cell cell{10.0, 10.0};
  const Vec2 r = cell.wrap({-0.5, 23.0});
  EXPECT_DOUBLE_EQ(r.x(), 9.5);
  EXPECT_DOUBLE_EQ(r.y(), 3.0);
  const Vec2 s = cell.wrap({-1e-18, 0.0});  // round-off would give exactly L
  EXPECT_GE(s.x(), 0.0);
  EXPECT_LT(s.x(), 10.0);
}

}  // namespace unjam
