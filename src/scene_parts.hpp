// The scene's rigid-body terms part by part (bhgrasp/sim/scene_parts.py, SceneParts; its module doc gives the
// reasons): the hand's joints (velocity indices below nv_hand) in one Pinocchio model, each object's subtree of the
// world in one of its own, so that no work space grows as nv^3.  Each part runs Pinocchio's algorithms on the scene
// model's own joints, placements and inertias: every term is the whole model's to the bit.  Joints keep the scene's
// numbering (0 the world), velocities its layout.
#pragma once

#include <utility>
#include <vector>

#include <Eigen/Core>

#include <pinocchio/geometry.hpp>
#include <pinocchio/multibody.hpp>

#include "options.hpp"

namespace bhgrasp {

class SceneParts {
 public:
  using Jacobian = pinocchio::Data::Matrix6x;

  SceneParts() = default;
  // Split `scene` (a joint of an object must hang from the world or from that object's joints: std::invalid_argument).
  SceneParts(const pinocchio::Model& scene, int nv_hand);

  void forward_kinematics(const Vector& q);       // every joint's placement at q
  void compute_joint_jacobians(const Vector& q);  // placements and joint Jacobians at q

  // A joint's placement in the world at the last kinematics (the identity for joint 0).
  const pinocchio::SE3& placement(int joint) const;
  // Each geometry's placement from its joint's, as pinocchio::updateGeometryPlacements, after the kinematics.
  void update_geometry_placements(const pinocchio::GeometryModel& geometry, pinocchio::GeometryData& data) const;
  // The LOCAL_WORLD_ALIGNED Jacobian (6, the part's nv) of the frame at `placement` on `joint`, the part's first
  // velocity column in `first` (the scene Jacobian's other columns are zero); after compute_joint_jacobians.  It
  // lives here until the next call for the same part.
  const Jacobian& point_jacobian(int joint, const pinocchio::SE3& placement, Eigen::Index& first);

  void mass_matrix(const Vector& q, Matrix& mass);                     // M(q), (nv, nv), both triangles
  // M(q) part by part: blocks[p] is part p's (n, n) diagonal block, both triangles (the same values as mass_matrix's)
  void mass_blocks(const Vector& q, std::vector<Matrix>& blocks);
  int count() const { return static_cast<int>(parts_.size()); }            // parts, the hand's first
  Eigen::Index first(int part) const { return parts_[static_cast<std::size_t>(part)].v0; }  // its first velocity
  Eigen::Index size(int part) const { return parts_[static_cast<std::size_t>(part)].model.nv; }  // its velocities
  void nonlinear_effects(const Vector& q, const Vector& v, Vector& bias);  // h(q, v), (nv,)
  Vector hand_gravity(const Vector& q);  // G(q) of the hand's joints, (nv_hand,) (the engine's gravity())

 private:
  struct Part {
    pinocchio::Model model;
    pinocchio::Data data;
    Eigen::Index q0 = 0, v0 = 0;  // its first coordinate and velocity in the scene's
    Jacobian jacobian;            // (6, nv) work array
  };
  std::vector<Part> parts_;                  // the hand's first
  std::vector<std::pair<int, int>> where_;   // scene joint -> (part, its joint in the part)
  Eigen::Index nv_ = 0;
  pinocchio::SE3 identity_ = pinocchio::SE3::Identity();
};

}  // namespace bhgrasp
