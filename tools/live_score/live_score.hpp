#pragma once
// Scores the introspection a log recorded: each INTROSPECTION message's
// query-cell predictions against the INTROSPECTION_LABELS the depth monitor
// published for the same frame (matched by utime and cell position), from
// the image alone and given the detector's verdict, all and announced
// (under the model's gate); and how long each frame's introspection took.
// No model is run: this is what the robot predicted, as it happened. The
// detector's grids, where the log has them, tell a labelled cell the
// introspection does not look at (its patch leaves the image: the grid's
// in_image is 0) from one it should have predicted and did not.
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "ivoa/core/label_confusion.hpp"
#include "ivoa/introspection_labels_t.hpp"
#include "ivoa/introspection_t.hpp"
#include "ivoa/obstacle_grid_t.hpp"

namespace ivoa::tools {

struct PredictionScore {
  LabelConfusion all;        // every labelled cell with a prediction
  LabelConfusion announced;  // those whose uncertainty passed the model's gate
};

// compute_ms over the INTROSPECTION messages, milliseconds.
struct ComputeTimes {
  int64_t frames = 0;
  double median = 0, p90 = 0, max = 0;
};

struct LiveScore {
  PredictionScore image;           // from the image alone (the paper's)
  PredictionScore given_verdict;   // given the detector's verdict for the cell
  int64_t labelled_frames = 0;     // frames with INTROSPECTION_LABELS
  int64_t predicted_frames = 0;    // frames with INTROSPECTION
  int64_t repeated_messages = 0;   // of either, for a frame already read (counted once, the latest kept)
  int64_t scored_frames = 0;       // frames with both
  int64_t labelled_cells = 0;      // cells of the scored frames with a label (not NONE)
  int64_t outside_view_cells = 0;  // of those, outside the introspection's view (the grid's in_image 0)
  int64_t no_grid_cells = 0;       // in frames predicted with no query cells (no detector grid had come yet)
  int64_t unmatched_cells = 0;     // the others with no query cell at the same position: a prediction missing
  int64_t verdict_unknown = 0;     // matched, but no detector grid reached the introspection
  int64_t verdict_disagrees = 0;   // the introspection's verdict is not the one the label was made from
  ComputeTimes compute;
  std::set<std::string> models;     // model_id of the INTROSPECTION messages
  std::set<std::string> detectors;  // detector of the labels
};

// Collects both message kinds in any order; finish() matches and scores them.
// Each add() takes the message and returns "", or leaves it out and says
// why: a position that is not finite, a class or label none of the four, a
// compute time that is not a duration.
class LiveScorer {
 public:
  std::string add(const introspection_labels_t& labels);
  std::string add(const introspection_t& prediction);
  std::string add(const obstacle_grid_t& detector_grid);  // the stereo detector's, for in_image
  LiveScore finish() const;

 private:
  struct LabelledCell {
    float x, y;
    int8_t label, stereo_state;
  };
  struct Query {
    float x, y;
    int8_t predicted, announced, verdict, verdict_class, verdict_announced;
  };
  void score_frame(int64_t utime, const std::vector<LabelledCell>& cells, const std::vector<Query>& queries,
                   LiveScore& s) const;

  std::map<int64_t, std::vector<LabelledCell>> labels_;  // by frame utime
  std::map<int64_t, std::vector<Query>> predictions_;
  std::map<int64_t, std::set<std::pair<long, long>>> outside_view_;  // by frame: cells not in_image
  std::map<int64_t, double> compute_ms_;                             // by frame utime
  std::set<std::string> models_, detectors_;
  int64_t repeated_messages_ = 0;
};

ComputeTimes summarize_compute_ms(std::vector<double> ms);

}  // namespace ivoa::tools
