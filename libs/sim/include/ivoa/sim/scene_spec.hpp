#pragma once
// What a scene is made of, before the seed decides the details: the layout,
// material palettes, how many obstacles, how often each stereo-failure
// phenomenon appears, and explicit elements placed exactly (for tests and
// hand-made situations). Loaded from a YAML scene file (libs/sim/scenes/README.md)
// or filled in code.
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "ivoa/sim/material.hpp"
#include "ivoa/sim/pose.hpp"

namespace ivoa::sim {

// Thrown for an unusable scene file or spec; what() names the file and key.
class SceneSpecError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A uniformly drawn value in [min, max] (min == max: fixed).
struct Range {
  double min = 0, max = 0;
  Range() = default;
  Range(double lo, double hi) : min(lo), max(hi) {}
  explicit Range(double v) : min(v), max(v) {}
};

enum class Environment { kIndoor, kOutdoor };

enum class LayoutType {
  kNone,      // only the explicit elements (on an endless floor)
  kRoom,      // one rectangular room
  kCorridor,  // a long corridor with doors
  kOffice,    // a block of rooms joined by doorways
  kOpen,      // an outdoor area bounded by facades and hedges
};

// One thing placed exactly where the scene says (world frame, metres).
struct ElementSpec {
  enum class Type {
    kBox,         // position, size (length along yaw, width, height), yaw, elevation
    kCylinder,    // position, size.x = diameter, size.z = height
    kChair,       // position, yaw; size = seat width, depth, back height
    kTable,       // position, yaw, size = top length, width, height
    kWall,        // from (position) -> to (end); size.y = thickness, size.z = height; baseboard; doors
    kPole,        // thin cylinder: position, size.x = diameter, size.z = height
    kLampPost,    // pole with a glowing head and a light: position, size.z = height, intensity
    kCurb,        // low long box: from -> to, size.y = width, size.z = height
    kFloorPatch,  // a region of floor in another material: position, size.x/y, yaw, shape
    kPuddle,      // an irregular water puddle (mirror): position, size.x/y, yaw
    kPit,         // a hole in the ground: position, size.x/y, depth, yaw, shape
    kLight,       // a ceiling light panel (indoor): position, size.x/y, intensity
  };
  struct Door {
    double offset = 0;     // metres from the wall's `from` end to the door's near edge
    double width = 0.9;    // metres
    double height = 2.05;  // metres
    std::string material;  // "" = door_wood
    bool open = false;     // an open doorway (a gap) instead of a closed door
  };

  Type type = Type::kBox;
  Eigen::Vector2d position{0, 0};
  Eigen::Vector2d end{0, 0};
  Eigen::Vector3d size{0.4, 0.4, 0.5};
  double yaw = 0;               // radians
  double elevation = 0;         // metres above the ground (boxes only)
  double depth = 0.3;           // pits: metres below the ground
  double intensity = 0;         // lights and lamp posts: emitted radiance (0 = default)
  std::string shape = "rect";   // floor patches and pits: "rect" or "ellipse"
  std::string material;         // "" = the element type's default
  double baseboard_height = 0;  // walls: dark stripe height, metres (0 = none)
  std::string baseboard_material;
  std::vector<Door> doors;  // walls

  static const char* type_name(Type type);
};

struct LayoutSpec {
  LayoutType type = LayoutType::kNone;
  Range width{10, 10};  // x extent of the room / area / office block, metres
  Range depth{8, 8};    // y extent, metres
  Range corridor_width{1.8, 2.6};
  Range corridor_length{18, 28};
  Range room_size{3.5, 6.0};       // office: side length of one room
  Range ceiling_height{2.6, 3.0};  // indoor; also the height of generated walls
  double door_probability = 0.5;   // chance that a wall piece gets a (closed) door
  Range facade_height{6, 12};      // outdoor: height of the bounding facades
};

struct FloorSpec {
  std::vector<std::string> materials{"carpet_grey"};  // one is drawn per floor area
  Range patch_count{0, 0};                            // rugs, mats, other pavements
  std::vector<std::string> patch_materials;
  Range patch_size{0.8, 2.5};  // metres
};

struct WallSpec {
  std::vector<std::string> materials{"paint_white", "plaster"};
  std::vector<std::string> baseboard_materials{"baseboard_black"};
  Range baseboard_height{0.06, 0.14};
  std::vector<std::string> door_materials{"door_wood", "door_grey"};
  Range thickness{0.10, 0.15};
};

struct ObstacleSpec {
  Range count{0, 0};
  // Relative weights of kinds (obstacle_kinds()).
  std::vector<std::pair<std::string, double>> kinds{{"box", 1.0}};
  std::vector<std::string> materials{"cardboard"};  // for boxes, bins, ... (chairs and poles have defaults)
  double color_jitter = 0.15;                       // per-object random tint of the material colour (fraction)
  double min_gap = 0.8;                             // metres of free floor kept between obstacles (the robot must pass)
  Range box_size{0.25, 0.8};                        // metres, footprint side
  Range box_height{0.15, 1.0};                      // metres
};

struct PitSpec {
  double probability = 0.0;  // chance that the scene has pits at all
  Range count{1, 1};
  Range size{0.4, 0.9};   // metres, opening side
  Range depth{0.2, 0.6};  // metres
};

struct LightingSpec {
  Range ambient{0.35, 0.6};         // indoor: irradiance from bounced light (diffuse white ~ this bright)
  Range light_spacing{2.4, 3.6};    // indoor: ceiling panel grid, metres
  Range light_emission{60, 110};    // indoor panels: emitted radiance
  Range sun_elevation_deg{20, 60};  // outdoor
  Range sun_azimuth_deg{0, 360};
  Range sun_irradiance{250, 350};      // outdoor: irradiance of direct sun
  Range sky_irradiance{40, 70};        // outdoor: irradiance from the sky
  double overcast_probability = 0.3;   // outdoor: no direct sun
  Range low_light_factor{0.01, 0.04};  // multiplies all light in a low-light session
  bool night = false;                  // outdoor: sky dark, lamp posts lit
  double max_exposure_scale = 1.0;     // >1 lets the camera integrate longer (static scenes)
};

// How often each stereo-failure phenomenon appears: probabilities in [0, 1]
// unless a Range. Each is physically produced (materials, geometry, light),
// never painted in.
struct PhenomenaSpec {
  double reflective_floor = 0.3;   // a floor area uses a glossy / wet material of the palette
  Range wet_patches{0, 0};         // wet patches and puddles on the floor
  double textureless_walls = 0.5;  // a wall uses a uniform paint of the palette
  double textureless_obstacles = 0.3;
  double dark_stripes = 0.6;      // a wall has a dark baseboard
  double repetitive_floor = 0.3;  // a floor area uses a periodic (tile) material of the palette
  double glare = 0.3;             // strong lights: bright panels / low sun in front / lit lamps
  double low_light = 0.1;         // the whole session is dim (noise-dominated images)
};

struct SceneSpec {
  std::string name = "unnamed";
  std::string source = "<code>";  // file it came from, for messages
  Environment environment = Environment::kIndoor;
  LayoutSpec layout;
  FloorSpec floor;
  WallSpec walls;
  ObstacleSpec obstacles;
  PitSpec pits;
  LightingSpec lighting;
  PhenomenaSpec phenomena;
  // 0..1: how far each material's look strays from its definition, drawn
  // per seed: colours x exp(+-0.5 j) overall and x exp(+-0.15 j) per channel,
  // texture contrast and feature size x exp(+-j). Gloss, wetness, the
  // pattern, whether a material is textureless or periodic, and lights
  // stay; dark materials (baseboards' dark stripes) only darken. 0: as defined.
  double material_jitter = 0;
  std::vector<Material> materials;    // scene-specific materials (added to the library)
  std::vector<ElementSpec> elements;  // placed exactly, in addition to the generated ones
  std::optional<Pose2D> start;        // robot start pose (default: drawn from the seed)
};

// Loads a YAML scene file. Throws SceneSpecError naming the file and key
// (unknown keys, wrong types, unknown materials, bad ranges).
SceneSpec load_scene_spec(const std::string& yaml_path);
SceneSpec parse_scene_spec(const std::string& yaml_text, const std::string& source_name);

// Checks ranges, that every material name resolves and every obstacle kind
// is one of obstacle_kinds(); throws SceneSpecError.
void validate(const SceneSpec& spec);

// The obstacle kinds the generator can place, in name order: bench, bin,
// bollard, box, cabinet, car, chair, curb, cylinder, lamp_post, planter,
// pole, table.
const std::set<std::string>& obstacle_kinds();

// A spec with no layout, no random content and steady lighting: a floor of
// `floor_material` to which tests add explicit elements.
SceneSpec make_bare_spec(Environment environment, const std::string& floor_material);

}  // namespace ivoa::sim
