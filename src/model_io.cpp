#include "model_io.hpp"

#include <pinocchio/multibody/geometry.hpp>
#include <pinocchio/multibody/model.hpp>
#include <pinocchio/serialization.hpp>

namespace bhgrasp {

pinocchio::Model model_from_text(const std::string& text) {
  pinocchio::Model model;
  model.loadFromString(text);
  return model;
}

pinocchio::GeometryModel geometry_from_text(const std::string& text) {
  pinocchio::GeometryModel geometry;
  geometry.loadFromString(text);
  return geometry;
}

}  // namespace bhgrasp
