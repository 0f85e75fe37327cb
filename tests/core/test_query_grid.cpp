#include <gtest/gtest.h>

#include "ivoa/core/grid_messages.hpp"
#include "ivoa/core/query_grid.hpp"
#include "test_rig.hpp"

namespace ivoa {
namespace {

TEST(QueryGrid, CountsAreExactDespiteFloatSteps) {
  EXPECT_EQ(grid_count(0.5, 3.0, 0.25), 11);
  EXPECT_EQ(grid_count(-1.5, 1.5, 0.25), 13);
  EXPECT_EQ(grid_count(0.0, 0.3, 0.1), 4);  // 0.3/0.1 = 2.9999999999999996
  EXPECT_EQ(grid_count(0.0, 0.1, 0.05), 3);
  EXPECT_EQ(grid_count(1.0, 0.0, 0.1), 0);
}

TEST(QueryGrid, CellsHaveRowMajorLayoutPixelsAndPatchFlags) {
  const RigGeometry geo(test::make_test_rig());
  QueryGridConfig config;
  const QueryGrid grid(config, geo.left);
  ASSERT_EQ(grid.num_x(), 11);
  ASSERT_EQ(grid.num_y(), 13);
  ASSERT_EQ(grid.size(), 143);
  const QueryCell& c = grid.cell(grid.index(2, 5));
  EXPECT_DOUBLE_EQ(c.x, 1.0);
  EXPECT_DOUBLE_EQ(c.y, -0.25);
  ASSERT_TRUE(c.projects);
  const auto px = geo.left.project({1.0, -0.25, 0.0});
  EXPECT_DOUBLE_EQ(c.u, px->x());
  EXPECT_DOUBLE_EQ(c.v, px->y());
  // The patch flag agrees with an independent check of the patch corners.
  int inside = 0;
  for (const auto& cell : grid.cells()) {
    const cv::Rect r = patch_rect(cell.u, cell.v, 100);
    const bool expect = cell.projects && r.x >= 0 && r.y >= 0 && r.x + 100 <= 960 && r.y + 100 <= 600;
    EXPECT_EQ(cell.in_image, expect) << cell.x << "," << cell.y;
    inside += cell.in_image;
  }
  EXPECT_EQ(grid.count_in_image(), inside);
  EXPECT_GT(inside, 30);   // the ground 0.5-3 m ahead fills the lower image
  EXPECT_LT(inside, 143);  // points far to the side are outside
}

TEST(QueryGrid, PatchRectIsCentred) {
  const cv::Rect r = patch_rect(100.4, 200.6, 100);
  EXPECT_EQ(r, cv::Rect(50, 151, 100, 100));
}

TEST(QueryGrid, MessageCarriesGeometryAndMismatchIsExplained) {
  const RigGeometry geo(test::make_test_rig());
  const QueryGrid grid(QueryGridConfig{}, geo.left);
  obstacle_grid_t msg = make_obstacle_grid(grid, "test", 99);
  EXPECT_EQ(msg.num_cells, grid.size());
  EXPECT_EQ(msg.state[0], obstacle_grid_t::STATE_UNKNOWN);
  EXPECT_EQ(geometry_mismatch(msg, grid), "");
  QueryGridConfig other;
  other.spacing = 0.2;
  EXPECT_NE(geometry_mismatch(msg, QueryGrid(other, geo.left)), "");
  other = QueryGridConfig{};
  other.safety_radius = 0.2;
  EXPECT_NE(geometry_mismatch(msg, QueryGrid(other, geo.left)).find("safety radius"), std::string::npos);
}

TEST(QueryGrid, RejectsEmptyConfig) {
  const RigGeometry geo(test::make_test_rig());
  QueryGridConfig config;
  config.spacing = 0;
  EXPECT_THROW(QueryGrid(config, geo.left), std::invalid_argument);
}

}  // namespace
}  // namespace ivoa
