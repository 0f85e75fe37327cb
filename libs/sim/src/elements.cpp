#include "ivoa/sim/elements.hpp"

namespace ivoa::sim::elements {
namespace {

ElementSpec make(ElementSpec::Type type, const Eigen::Vector2d& position, const std::string& material) {
  ElementSpec e;
  e.type = type;
  e.position = position;
  e.material = material;
  return e;
}

}  // namespace

ElementSpec box(const Eigen::Vector2d& centre, const Eigen::Vector3d& size, const std::string& material, double yaw) {
  ElementSpec e = make(ElementSpec::Type::kBox, centre, material);
  e.size = size;
  e.yaw = yaw;
  return e;
}

ElementSpec cylinder(const Eigen::Vector2d& centre, double diameter, double height, const std::string& material) {
  ElementSpec e = make(ElementSpec::Type::kCylinder, centre, material);
  e.size = {diameter, diameter, height};
  return e;
}

ElementSpec wall(const Eigen::Vector2d& from, const Eigen::Vector2d& to, const std::string& material, double height,
                 double baseboard_height, const std::string& baseboard) {
  ElementSpec e = make(ElementSpec::Type::kWall, from, material);
  e.end = to;
  e.size = {0, 0.12, height};
  e.baseboard_height = baseboard_height;
  e.baseboard_material = baseboard;
  return e;
}

ElementSpec floor_patch(const Eigen::Vector2d& centre, const Eigen::Vector2d& size, const std::string& material,
                        bool ellipse) {
  ElementSpec e = make(ElementSpec::Type::kFloorPatch, centre, material);
  e.size = {size.x(), size.y(), 0};
  e.shape = ellipse ? "ellipse" : "rect";
  return e;
}

ElementSpec puddle(const Eigen::Vector2d& centre, const Eigen::Vector2d& size) {
  ElementSpec e = make(ElementSpec::Type::kPuddle, centre, "water");
  e.size = {size.x(), size.y(), 0};
  return e;
}

ElementSpec pit(const Eigen::Vector2d& centre, const Eigen::Vector2d& size, double depth) {
  ElementSpec e = make(ElementSpec::Type::kPit, centre, "");
  e.size = {size.x(), size.y(), 0};
  e.depth = depth;
  return e;
}

ElementSpec lamp_post(const Eigen::Vector2d& position, double height, double emission) {
  ElementSpec e = make(ElementSpec::Type::kLampPost, position, "");
  e.size = {0.14, 0.14, height};
  e.intensity = emission;
  return e;
}

ElementSpec ceiling_light(const Eigen::Vector2d& centre, const Eigen::Vector2d& size, double emission) {
  ElementSpec e = make(ElementSpec::Type::kLight, centre, "");
  e.size = {size.x(), size.y(), 0};
  e.intensity = emission;
  return e;
}

}  // namespace ivoa::sim::elements
