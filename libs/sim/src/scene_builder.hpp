#pragma once
// Builds SceneData from primitives: materials by name, prisms, floor
// features, lights. The layouts (scene_layouts.cpp) and explicit elements
// both go through it.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "ivoa/sim/scene_spec.hpp"
#include "rng.hpp"
#include "scene_data.hpp"

namespace ivoa::sim::detail {

// The renderer's form of a material: its texture (synthesised once per
// process and shared), linear colours and the phenomena it carries.
MaterialData make_material_data(const Material& m);

class SceneBuilder {
 public:
  SceneBuilder(const SceneSpec& spec, uint64_t seed);

  // Material index for a name (scene materials first, then the library).
  uint16_t material(const std::string& name);
  const Material& resolve(const std::string& name) const;
  // Picks from a palette: with probability `p` among entries that satisfy
  // `has_property`, otherwise among the others (falls back to the whole palette).
  std::string pick(const std::vector<std::string>& palette, const std::function<bool(const Material&)>& has_property,
                   double p);
  std::string pick_floor(const std::vector<std::string>& palette);
  std::string pick_wall(const std::vector<std::string>& palette);
  std::string pick_obstacle(const std::vector<std::string>& palette);

  Prism& add_rect(double cx, double cy, double length, double width, double yaw, double z0, double z1,
                  uint16_t material, uint8_t surface);
  Prism& add_circle(double cx, double cy, double radius, double z0, double z1, uint16_t material, uint8_t surface);

  // Elements (world frame, metres).
  void add_box(const Eigen::Vector2d& p, const Eigen::Vector3d& size, double yaw, double elevation,
               const std::string& material, double color_jitter = 0);
  void add_cylinder(const Eigen::Vector2d& p, double radius, double height, const std::string& material,
                    double color_jitter = 0);
  void add_chair(const Eigen::Vector2d& p, double yaw, const Eigen::Vector3d& size, const std::string& seat_material,
                 const std::string& frame_material);
  void add_table(const Eigen::Vector2d& p, double yaw, const Eigen::Vector3d& size, const std::string& top_material,
                 const std::string& leg_material);
  void add_bench(const Eigen::Vector2d& p, double yaw, double length);
  void add_car(const Eigen::Vector2d& p, double yaw);
  void add_wall(const Eigen::Vector2d& from, const Eigen::Vector2d& to, double height, double thickness,
                const std::string& material, double baseboard_height, const std::string& baseboard_material,
                const std::vector<ElementSpec::Door>& doors);
  void add_curb(const Eigen::Vector2d& from, const Eigen::Vector2d& to, double width, double height,
                const std::string& material);
  void add_pole(const Eigen::Vector2d& p, double diameter, double height, const std::string& material);
  void add_lamp_post(const Eigen::Vector2d& p, double height, double emission);
  void add_ceiling_light(const Eigen::Vector2d& p, const Eigen::Vector2d& size, double emission);
  void add_patch(const Eigen::Vector2d& p, const Eigen::Vector2d& size, double yaw, bool ellipse,
                 const std::string& material);
  void add_puddle(const Eigen::Vector2d& p, const Eigen::Vector2d& size, double yaw, const std::string& material);
  void add_pit(const Eigen::Vector2d& p, const Eigen::Vector2d& size, double depth, double yaw, bool ellipse,
               const std::string& material);
  void add_element(const ElementSpec& e);

  // Placement helper: smallest horizontal gap between a circle and what is
  // already placed (solids standing on the ground, pits), metres.
  enum class Placed { kAll, kWalls, kNotWalls };
  double gap_to_placed(const Eigen::Vector2d& p, double radius, Placed which = Placed::kAll) const;

  SceneData& data() { return *data_; }
  const SceneSpec& spec() const { return spec_; }
  Rng& rng() { return rng_; }
  std::shared_ptr<SceneData> finish();

  // Ceiling panels (for the ceiling's radiance map), world rectangles.
  struct Panel {
    Eigen::Vector2d centre, half;
    float emission;
  };
  std::vector<Panel>& panels() { return panels_; }

 private:
  // `m` as this seed shows it: SceneSpec::material_jitter, drawn per
  // material from a generator of its own, so the rest of the scene is the
  // same seed's without it.
  Material as_this_seed_shows(Material m) const;

  const SceneSpec& spec_;
  Rng rng_;
  std::shared_ptr<SceneData> data_;
  std::vector<Panel> panels_;
};

// The procedural layouts (scene_layouts.cpp).
void build_layout(SceneBuilder& b);
void place_obstacles(SceneBuilder& b);
void place_floor_details(SceneBuilder& b);  // patches, wet patches, puddles, pits
void place_lights(SceneBuilder& b);
void choose_start(SceneBuilder& b);
void build_ceiling(SceneBuilder& b);

// generate_scene's steps (validate, layout, elements, obstacles, floor,
// lights, start, finish); `before_finish` may adjust the scene before its
// light maps are computed (counterfactual scenes).
std::shared_ptr<SceneData> build_scene(const SceneSpec& spec, uint64_t seed,
                                       const std::function<void(SceneBuilder&)>& before_finish = {});

}  // namespace ivoa::sim::detail
