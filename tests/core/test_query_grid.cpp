#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

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
  // the header right, the cells elsewhere: the labels would be of other ground points
  obstacle_grid_t moved = msg;
  for (float& x : moved.x) x += 0.01f;
  EXPECT_EQ(geometry_mismatch(moved, grid).rfind("cell 0 is at (", 0), 0u) << geometry_mismatch(moved, grid);
  moved = msg;
  moved.x[3] += 5e-5f;  // a last bit rounded otherwise on another machine
  EXPECT_EQ(geometry_mismatch(moved, grid), "");
}

TEST(QueryGrid, ReceivedCellsThatCannotBeUsedAreNamed) {
  const QueryGrid grid(QueryGridConfig{}, RigGeometry(test::make_test_rig()).left);
  const obstacle_grid_t good = make_obstacle_grid(grid, "test", 99);
  EXPECT_EQ(grid_content_error(good), "");
  obstacle_grid_t msg = good;
  msg.state[7] = 42;
  EXPECT_EQ(grid_content_error(msg), "cell 7: state 42 is none of FREE 0, OBSTACLE 1, UNKNOWN 2");
  msg = good;
  msg.u.pop_back();
  EXPECT_EQ(grid_content_error(msg),
            "u has " + std::to_string(good.num_cells - 1) + " entries, num_cells is " + std::to_string(good.num_cells));
  msg = good;
  const size_t seen =
      static_cast<size_t>(std::find(good.in_image.begin(), good.in_image.end(), 1) - good.in_image.begin());
  ASSERT_LT(seen, good.in_image.size());
  msg.u[seen] = std::nanf("");
  EXPECT_EQ(grid_content_error(msg).rfind("cell " + std::to_string(seen) + ": in_image, but its pixel (nan", 0), 0u);
  msg = good;
  msg.v[seen] = 1e9f;  // was predicted at, and labelled as if in view
  EXPECT_NE(grid_content_error(msg).find(") lies outside any image"), std::string::npos) << grid_content_error(msg);
  msg = good;
  msg.in_image[seen] = 0;  // a cell out of view may have no pixel (behind the camera)
  msg.u[seen] = std::nanf("");
  EXPECT_EQ(grid_content_error(msg), "");
  msg.y[0] = std::numeric_limits<float>::infinity();
  EXPECT_EQ(grid_content_error(msg), "cell 0: position is not finite");
  msg = good;
  msg.num_x = 0;  // was taken for every later frame's grid, and failed each of them
  EXPECT_EQ(grid_content_error(msg), "num_x 0 by num_y " + std::to_string(good.num_y) + " is not its " +
                                         std::to_string(good.num_cells) + " cells");
}

TEST(QueryGrid, RejectsEmptyConfig) {
  const RigGeometry geo(test::make_test_rig());
  QueryGridConfig config;
  config.spacing = 0;
  EXPECT_THROW(QueryGrid(config, geo.left), std::invalid_argument);
}

}  // namespace
}  // namespace ivoa
