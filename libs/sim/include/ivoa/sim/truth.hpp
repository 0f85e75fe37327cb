#pragma once
// Ground-truth occupancy of a footprint on the ground, computed analytically
// from the scene geometry (no rendering, no sensor noise).
namespace ivoa::sim {

enum class TruthState {
  kFree,      // nothing stands in the footprint and the ground is there
  kObstacle,  // some solid stands above min_height inside the footprint
  kHole,      // no solid, but the ground is missing (a pit) somewhere inside it
};

// Definition used by Scene::truth_at and Simulator::footprint_truth: the
// footprint is the disc of `radius` around a ground point. It is kObstacle
// if any solid (wall, box, cylinder, chair part, curb, pole, ...) has its
// footprint intersecting the disc and its top above `min_height` and its
// bottom below `max_height` (overhangs count while they are lower than
// max_height). Otherwise it is kHole if any pit's opening intersects the
// disc, and kFree if not.
struct TruthQuery {
  double radius = 0.10;       // metres, the IVOA safety radius r
  double min_height = 0.05;   // metres, solids lower than this are traversable
  double max_height = 1.0e9;  // metres, solids entirely above this are ignored
};

const char* to_string(TruthState state);

}  // namespace ivoa::sim
