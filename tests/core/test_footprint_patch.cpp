// Footprint-scaled patches: the side follows the disc's width in pixels
// measured between neighbouring cells, stays inside the image and never
// drops under the fixed patch; cutting resizes the square of every view,
// many squares at once as each alone.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "ivoa/core/footprint_patch.hpp"
#include "ivoa/core/query_grid.hpp"
#include "test_rig.hpp"

namespace ivoa {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// A 1 x 3 grid whose cells lie `step` pixels apart along the image row v.
struct Row {
  std::vector<float> u, v;
};
Row row_of_three(float u0, float step, float v) { return {{u0, u0 + step, u0 + 2 * step}, {v, v, v}}; }

QueryGridConfig grid_config() {
  QueryGridConfig g;
  g.spacing = 0.25;
  g.safety_radius = 0.1;  // the disc is 0.8 spacings wide
  g.patch_size = 100;
  return g;
}

TEST(FootprintPatch, ZeroScaleKeepsTheFixedPatchEverywhere) {
  const Row r = row_of_three(300, 400, 300);
  EXPECT_EQ(footprint_patch_sides(grid_config(), 1, 3, r.u, r.v, {2000, 1000}, 0.0), std::vector<int>(3, 100));
}

TEST(FootprintPatch, SideIsScaleTimesTheDiscWidthFromTheNeighbours) {
  // 250 px between cells: the disc is 200 px wide; x1.6 = 320 px.
  const Row r = row_of_three(400, 250, 500);
  EXPECT_EQ(footprint_patch_sides(grid_config(), 1, 3, r.u, r.v, {2000, 1000}, 1.6), (std::vector<int>{320, 320, 320}));
  // Far cells (60 px apart: disc 48 px, x1.6 = 77 px) keep the fixed patch.
  const Row far = row_of_three(400, 60, 500);
  EXPECT_EQ(footprint_patch_sides(grid_config(), 1, 3, far.u, far.v, {2000, 1000}, 1.6), std::vector<int>(3, 100));
}

TEST(FootprintPatch, SideShrinksToStayInsideTheImageButNotUnderThePatch) {
  const Row r = row_of_three(130, 250, 500);  // the first cell is 130 px from the left edge
  const auto sides = footprint_patch_sides(grid_config(), 1, 3, r.u, r.v, {2000, 1000}, 1.6);
  EXPECT_EQ(sides[0], 260);
  EXPECT_EQ(sides[1], 320);
  const Row edge = row_of_three(30, 250, 500);  // 30 px from the edge: not even the fixed patch fits
  EXPECT_EQ(footprint_patch_sides(grid_config(), 1, 3, edge.u, edge.v, {2000, 1000}, 1.6)[0], 100);
}

TEST(FootprintPatch, CellsWithoutProjectingNeighboursKeepTheFixedPatch) {
  Row r = row_of_three(400, 250, 500);
  r.u[0] = r.v[0] = r.u[2] = r.v[2] = kNaN;
  EXPECT_EQ(footprint_patch_sides(grid_config(), 1, 3, r.u, r.v, {2000, 1000}, 1.6), std::vector<int>(3, 100));
  // Two rows of a 2 x 2 grid: neighbours are taken along y only, never across rows.
  const std::vector<float> u{100, 300, kNaN, 500}, v{100, 100, 400, 400};
  const auto sides = footprint_patch_sides(grid_config(), 2, 2, u, v, {2000, 1000}, 1.0);
  EXPECT_EQ(sides[0], 160);
  EXPECT_EQ(sides[3], 100);
  EXPECT_THROW(footprint_patch_sides(grid_config(), 2, 3, u, v, {2000, 1000}, 1.0), std::invalid_argument);
}

TEST(FootprintPatch, SidesFollowTheProjectedDiscOfARealRig) {
  const RigGeometry geo(test::make_test_rig());
  const QueryGrid grid(QueryGridConfig{}, geo.left);
  std::vector<float> u, v;
  for (const auto& c : grid.cells()) {
    u.push_back(static_cast<float>(c.u));
    v.push_back(static_cast<float>(c.v));
  }
  const auto sides = footprint_patch_sides(grid.config(), grid.num_x(), grid.num_y(), u, v, {960, 600}, 1.0);
  // Straight ahead at 0.75 m and 1 m: the 0.2 m disc against the projection's own width.
  for (const int ix : {1, 2}) {
    const QueryCell& c = grid.cell(grid.index(ix, 6));
    const double disc = (*geo.left.project({c.x, 0.1, 0.0}) - *geo.left.project({c.x, -0.1, 0.0})).norm();
    EXPECT_NEAR(sides[static_cast<size_t>(grid.index(ix, 6))], std::max(disc, 100.0), 3.0) << "x = " << c.x;
  }
  EXPECT_GT(sides[static_cast<size_t>(grid.index(1, 6))], 110);  // near cells are scaled up
  // From 2 m on the disc fits in the fixed patch.
  EXPECT_EQ(sides[static_cast<size_t>(grid.index(6, 6))], 100);
}

TEST(FootprintPatch, CutResizesTheSquareOfEachStackedView) {
  cv::Mat stacked(400, 300, CV_8UC3);
  cv::randu(stacked, 0, 255);
  const cv::Mat patch = cut_patch(stacked, 2, 150, 100, 120, 60);
  ASSERT_EQ(patch.size(), cv::Size(60, 120));
  cv::Mat expected_top, expected_bottom;
  cv::resize(stacked(cv::Rect(90, 40, 120, 120)), expected_top, {60, 60}, 0, 0, cv::INTER_AREA);
  cv::resize(stacked(cv::Rect(90, 240, 120, 120)), expected_bottom, {60, 60}, 0, 0, cv::INTER_AREA);
  EXPECT_EQ(cv::norm(patch.rowRange(0, 60), expected_top, cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(patch.rowRange(60, 120), expected_bottom, cv::NORM_INF), 0);
  // Equal sides copy the pixels; a square leaving its view is refused.
  EXPECT_EQ(cv::norm(cut_patch(stacked, 1, 150, 100, 40, 40), stacked(cv::Rect(130, 80, 40, 40)), cv::NORM_INF), 0);
  EXPECT_TRUE(cut_patch(stacked, 2, 150, 100, 220, 60).empty());
  EXPECT_THROW(cut_patch(stacked, 3, 150, 100, 40, 40), std::invalid_argument);
}

TEST(FootprintPatch, CuttingManyOverThreadsGivesEachPatchAsAlone) {
  cv::Mat stacked(400, 300, CV_8UC3);
  cv::randu(stacked, 0, 255);
  std::vector<PatchSquare> squares;
  for (int k = 0; k < 24; ++k) squares.push_back({100.0 + 3 * k, 90.0 + k, 60 + 6 * k});  // sides 60..198
  for (const bool parallel : {true, false}) {
    const auto patches = cut_patches(stacked, 2, squares, 50, parallel);
    ASSERT_EQ(patches.size(), squares.size());
    for (size_t k = 0; k < squares.size(); ++k) {
      const cv::Mat alone = cut_patch(stacked, 2, squares[k].u, squares[k].v, squares[k].side, 50);
      ASSERT_EQ(patches[k].empty(), alone.empty()) << "square " << k;
      if (!alone.empty()) {
        EXPECT_EQ(cv::norm(patches[k], alone, cv::NORM_INF), 0) << "square " << k;
      }
    }
    EXPECT_TRUE(patches.back().empty());  // 198 px around row 113 leaves the 200-row view
  }
}

}  // namespace
}  // namespace ivoa
