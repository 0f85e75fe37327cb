#pragma once
// Footprint-scaled introspection patches. The paper's fixed square (100 px)
// shows the whole footprint disc (2 r across) only far from the robot: on
// the simulator's rig the disc is 162 px wide at 0.75 m, and the rows whose
// disc overflows the patch are the ones introspection gets wrong most. With
// a patch scale k > 0 the square cut around a query cell is k times the
// disc's width in pixels (never under patch_size, shrunk to stay inside
// the image) and is then resized to patch_size, so the network sees the
// disc and a like share of its surroundings at every distance. k = 0 keeps
// the fixed square. The dataset builder, ivoa-eval and the introspection
// process all cut patches with these functions.
#include <vector>

#include <opencv2/core.hpp>

#include "ivoa/core/grid_messages.hpp"
#include "ivoa/core/patch_square.hpp"
#include "ivoa/core/query_grid.hpp"

namespace ivoa {

// Side in pixels of the square cut around each cell of a num_x x num_y grid
// (cell ix * num_y + iy at pixel (u, v), NaN if it does not project). The
// disc's width is measured as the pixel distance to the lateral neighbours
// (same x, y +- spacing) times 2 r / spacing; a cell with no projecting
// neighbour, and every cell when scale <= 0, gets grid.patch_size. Sides
// are even.
std::vector<int> footprint_patch_sides(const QueryGridConfig& grid, int num_x, int num_y, const std::vector<float>& u,
                                       const std::vector<float>& v, cv::Size image, double scale);

// The same for a grid message (obstacle_grid_t, introspection_labels_t),
// with squares of at least `patch_size` (the dataset's or the model's, not
// necessarily the grid's).
template <class Msg>
std::vector<int> footprint_patch_sides(const Msg& msg, int patch_size, cv::Size image, double scale) {
  QueryGridConfig grid = geometry_of(msg);
  grid.patch_size = patch_size;
  return footprint_patch_sides(grid, msg.num_x, msg.num_y, msg.u, msg.v, image, scale);
}

// The side x side square centred on (u, v) (patch_rect) from each of
// `views` images stacked in `stacked` (views x image height rows), stacked
// in the same order and resized to out_size x out_size per view (area
// averaging; a copy either way). Empty if the square leaves the image.
cv::Mat cut_patch(const cv::Mat& stacked, int views, double u, double v, int side, int out_size);

// cut_patch for every square (empty where one leaves the image), spread
// over OpenCV's threads one square a stripe: resizing a near cell's square
// (area averaging at a scale that is rarely a whole number) takes about
// 0.15 ms a view. parallel = false cuts them on the calling thread. The
// patches are the same either way.
std::vector<cv::Mat> cut_patches(const cv::Mat& stacked, int views, const std::vector<PatchSquare>& squares,
                                 int out_size, bool parallel = true);

}  // namespace ivoa
