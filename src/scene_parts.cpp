// The scene's parts: see scene_parts.hpp.  Each function mirrors the method of the same name in
// bhgrasp/sim/scene_parts.py (SceneParts); hand_gravity serves the engine's gravity() and has no twin there, and the
// Python twin's potential_energy (for Scene.energy) none here.
#include "scene_parts.hpp"

#include <stdexcept>

#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/algorithm/jacobian.hpp>
#include <pinocchio/algorithm/kinematics.hpp>
#include <pinocchio/algorithm/rnea.hpp>

namespace bhgrasp {

SceneParts::SceneParts(const pinocchio::Model& scene, int nv_hand) : nv_(scene.nv) {
  where_.assign(1, {0, 0});
  std::vector<pinocchio::JointIndex> local(static_cast<std::size_t>(scene.njoints), 0);
  std::vector<int> part_of(static_cast<std::size_t>(scene.njoints), -1);
  parts_.emplace_back();  // the hand's, possibly without joints
  for (pinocchio::JointIndex j = 1; j < static_cast<pinocchio::JointIndex>(scene.njoints); ++j) {
    const pinocchio::JointIndex parent = scene.parents[j];
    int index;
    if (scene.idx_vs[j] < nv_hand) {
      index = 0;
    } else if (parent == 0) {
      parts_.emplace_back();
      index = static_cast<int>(parts_.size()) - 1;
    } else {
      index = part_of[parent];
      if (index != static_cast<int>(parts_.size()) - 1 || index == 0)
        throw std::invalid_argument("an object's joint hangs from a joint of the hand or of an earlier object");
    }
    Part& part = parts_[static_cast<std::size_t>(index)];
    if (part.model.njoints == 1) {  // the part's first joint: where its coordinates start
      part.q0 = scene.idx_qs[j];
      part.v0 = scene.idx_vs[j];
      part.model.gravity = scene.gravity;
    }
    const pinocchio::JointIndex id = part.model.addJoint(parent == 0 ? 0 : local[parent], scene.joints[j],
                                                         scene.jointPlacements[j], scene.names[j]);
    part.model.inertias[id] = scene.inertias[j];
    local[j] = id;
    part_of[j] = index;
    where_.emplace_back(index, static_cast<int>(id));
  }
  parts_[0].model.gravity = scene.gravity;
  for (Part& part : parts_) {
    part.model.armature = scene.armature.segment(part.v0, part.model.nv);
    part.data = pinocchio::Data(part.model);
    part.jacobian = Jacobian::Zero(6, part.model.nv);
  }
}

void SceneParts::forward_kinematics(const Vector& q) {
  for (Part& part : parts_)
    pinocchio::forwardKinematics(part.model, part.data, q.segment(part.q0, part.model.nq));
}

void SceneParts::compute_joint_jacobians(const Vector& q) {
  for (Part& part : parts_)
    pinocchio::computeJointJacobians(part.model, part.data, q.segment(part.q0, part.model.nq));
}

const pinocchio::SE3& SceneParts::placement(int joint) const {
  if (joint == 0) return identity_;
  const auto& [index, local] = where_[static_cast<std::size_t>(joint)];
  return parts_[static_cast<std::size_t>(index)].data.oMi[static_cast<std::size_t>(local)];
}

void SceneParts::update_geometry_placements(const pinocchio::GeometryModel& geometry,
                                            pinocchio::GeometryData& data) const {
  for (std::size_t i = 0; i < geometry.ngeoms; ++i) {
    const pinocchio::GeometryObject& object = geometry.geometryObjects[i];
    data.oMg[i] = placement(static_cast<int>(object.parentJoint)) * object.placement;
  }
}

const SceneParts::Jacobian& SceneParts::point_jacobian(int joint, const pinocchio::SE3& placement,
                                                       Eigen::Index& first) {
  const auto& [index, local] = where_[static_cast<std::size_t>(joint)];
  Part& part = parts_[static_cast<std::size_t>(index)];
  part.jacobian.setZero();
  pinocchio::getFrameJacobian(part.model, part.data, static_cast<pinocchio::JointIndex>(local), placement,
                              pinocchio::LOCAL_WORLD_ALIGNED, part.jacobian);
  first = part.v0;
  return part.jacobian;
}

void SceneParts::mass_matrix(const Vector& q, Matrix& mass) {
  mass.setZero(nv_, nv_);
  for (Part& part : parts_) {
    const Eigen::Index n = part.model.nv;
    pinocchio::crba(part.model, part.data, q.segment(part.q0, part.model.nq));
    mass.block(part.v0, part.v0, n, n) = part.data.M;
  }
  mass.triangularView<Eigen::StrictlyLower>() = mass.transpose();
}

void SceneParts::mass_blocks(const Vector& q, std::vector<Matrix>& blocks) {
  blocks.resize(parts_.size());
  for (std::size_t p = 0; p < parts_.size(); ++p) {
    Part& part = parts_[p];
    pinocchio::crba(part.model, part.data, q.segment(part.q0, part.model.nq));
    blocks[p] = part.data.M;
    blocks[p].triangularView<Eigen::StrictlyLower>() = blocks[p].transpose();
  }
}

void SceneParts::nonlinear_effects(const Vector& q, const Vector& v, Vector& bias) {
  bias.resize(nv_);
  for (Part& part : parts_) {
    const Eigen::Index n = part.model.nv;
    bias.segment(part.v0, n) = pinocchio::nonLinearEffects(part.model, part.data, q.segment(part.q0, part.model.nq),
                                                            v.segment(part.v0, n));
  }
}

Vector SceneParts::hand_gravity(const Vector& q) {
  Part& hand = parts_.front();
  return pinocchio::computeGeneralizedGravity(hand.model, hand.data, q.segment(hand.q0, hand.model.nq));
}

}  // namespace bhgrasp
