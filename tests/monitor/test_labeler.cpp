#include <gtest/gtest.h>

#include "ivoa/core/grid_messages.hpp"
#include "ivoa/monitor/labeler.hpp"

namespace ivoa::monitor {
namespace {

using G = obstacle_grid_t;
using L = introspection_labels_t;

obstacle_grid_t grid_with(std::vector<int8_t> states, const std::string& detector) {
  obstacle_grid_t g{};
  g.utime = 100;
  g.detector = detector;
  g.num_x = 1;
  g.num_y = static_cast<int32_t>(states.size());
  g.safety_radius = 0.1;
  g.state = states;
  for (size_t i = 0; i < states.size(); ++i) {
    g.x.push_back(1.0f);
    g.y.push_back(static_cast<float>(i));
    g.u.push_back(10.0f * static_cast<float>(i));
    g.v.push_back(300.0f);
    g.in_image.push_back(1);
  }
  g.num_cells = static_cast<int32_t>(states.size());
  return g;
}

TEST(Labeler, AlgorithmOneFourCases) {
  // O = obstacle free.  (stereo, depth)
  EXPECT_EQ(label_of_verdicts(G::STATE_FREE, G::STATE_FREE), L::LABEL_TN);          // O_M & O_S
  EXPECT_EQ(label_of_verdicts(G::STATE_OBSTACLE, G::STATE_FREE), L::LABEL_FP);      // O_M & !O_S
  EXPECT_EQ(label_of_verdicts(G::STATE_FREE, G::STATE_OBSTACLE), L::LABEL_FN);      // !O_M & O_S
  EXPECT_EQ(label_of_verdicts(G::STATE_OBSTACLE, G::STATE_OBSTACLE), L::LABEL_TP);  // !O_M & !O_S
}

TEST(Labeler, UnknownOnEitherSideGivesNoLabel) {
  EXPECT_EQ(label_of_verdicts(G::STATE_UNKNOWN, G::STATE_FREE), L::LABEL_NONE);
  EXPECT_EQ(label_of_verdicts(G::STATE_OBSTACLE, G::STATE_UNKNOWN), L::LABEL_NONE);
  EXPECT_EQ(label_of_verdicts(G::STATE_UNKNOWN, G::STATE_UNKNOWN), L::LABEL_NONE);
}

TEST(Labeler, LabelsAFrameCellByCell) {
  const obstacle_grid_t stereo = grid_with({0, 1, 0, 1, 2}, "jppc");
  obstacle_grid_t depth = grid_with({0, 0, 1, 1, 0}, "depth_monitor");
  depth.depth_utime = 104;
  const introspection_labels_t labels = label_frame(stereo, depth);
  EXPECT_EQ(labels.utime, 100);
  EXPECT_EQ(labels.depth_utime, 104);
  EXPECT_EQ(labels.detector, "jppc");
  EXPECT_EQ(labels.label, (std::vector<int8_t>{L::LABEL_TN, L::LABEL_FP, L::LABEL_FN, L::LABEL_TP, L::LABEL_NONE}));
  EXPECT_EQ(labels.stereo_state, stereo.state);
  EXPECT_EQ(labels.depth_state, depth.state);
  EXPECT_EQ(labels.u, stereo.u);
  EXPECT_EQ(labels.num_cells, 5);
}

TEST(Labeler, DifferentGeometryIsRefused) {
  const obstacle_grid_t stereo = grid_with({0, 1, 0}, "jppc");
  obstacle_grid_t depth = grid_with({0, 0, 1}, "depth_monitor");
  depth.safety_radius = 0.2;
  EXPECT_THROW(label_frame(stereo, depth), LabelError);
  depth = grid_with({0, 0}, "depth_monitor");
  EXPECT_THROW(label_frame(stereo, depth), LabelError);
}

}  // namespace
}  // namespace ivoa::monitor
