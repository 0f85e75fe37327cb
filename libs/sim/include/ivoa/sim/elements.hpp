#pragma once
// One-line constructors for explicit scene elements, so a test can build an
// exact situation ("a texture-less wall 1.2 m ahead") in a few lines:
//   SceneSpec spec = make_bare_spec(Environment::kIndoor, "carpet_grey");
//   spec.elements.push_back(wall({1.2, -3}, {1.2, 3}, "paint_white"));
// World frame, metres; the robot starts at the origin facing +x unless the
// spec says otherwise.
#include <string>

#include "ivoa/sim/scene_spec.hpp"

namespace ivoa::sim::elements {

ElementSpec box(const Eigen::Vector2d& centre, const Eigen::Vector3d& size, const std::string& material = "cardboard",
                double yaw = 0);
ElementSpec cylinder(const Eigen::Vector2d& centre, double diameter, double height,
                     const std::string& material = "plastic_blue");
ElementSpec wall(const Eigen::Vector2d& from, const Eigen::Vector2d& to, const std::string& material = "paint_white",
                 double height = 2.5, double baseboard_height = 0, const std::string& baseboard = "baseboard_black");
ElementSpec floor_patch(const Eigen::Vector2d& centre, const Eigen::Vector2d& size, const std::string& material,
                        bool ellipse = false);
ElementSpec puddle(const Eigen::Vector2d& centre, const Eigen::Vector2d& size);
ElementSpec pit(const Eigen::Vector2d& centre, const Eigen::Vector2d& size, double depth);
ElementSpec lamp_post(const Eigen::Vector2d& position, double height = 4.0, double emission = 0);
ElementSpec ceiling_light(const Eigen::Vector2d& centre, const Eigen::Vector2d& size, double emission);

}  // namespace ivoa::sim::elements
