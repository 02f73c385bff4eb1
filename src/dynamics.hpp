// A hand's inverse dynamics for its control laws, on Pinocchio's C++ API (bhgrasp/model/hand_dynamics.py: HandDynamics).
// The Python twins are Hand.slotine_li_torque's NumPy path (tests/test_hand_kernels.py holds both to the bit) and
// ContactSensing._reaction_torques_python in bhgrasp/grasp/sensing.py (to round-off, tests/test_sensing_kernels.py).
// Units SI; joint space of the hand's model.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include <pinocchio/multibody.hpp>

namespace bhgrasp {

class HandDynamics {
 public:
  using ConstVector = Eigen::Ref<const Eigen::VectorXd>;
  using ConstRows = Eigen::Ref<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>;

  // `model`: Pinocchio's text serialisation of the hand (Model.saveToString); its inertias are not changed afterwards.
  explicit HandDynamics(const std::string& model);

  // M(q) a_r + C(q, v) v_r + G(q) [N m] under `gravity` [m/s^2] (in the model's base frame): the Christoffel C by
  // polarisation of RNEA's velocity products, C(q, v) v_r = (h(v + v_r) - h(v - v_r)) / 4, three RNEA passes.
  // The result lives in this object until the next call.  Sizes are checked (std::invalid_argument).
  const Eigen::VectorXd& slotine_li_torque(const Eigen::Vector3d& gravity, const ConstVector& q, const ConstVector& v,
                                           const ConstVector& v_r, const ConstVector& a_r);

  // -sum_i J_i^T f_i [N m]: the joint torques on the hand of contact forces f_i [N, world] on the object at points
  // p_i [m, world] (rows of `points`, `forces`) fixed on the bodies of joints `joints[i]`, J_i the points'
  // translational Jacobians (world-aligned) at q, for a hand whose model frame sits at (base_rotation,
  // base_translation) in the world.  The result lives in this object until the next call.  Sizes and joint ids are
  // checked (std::invalid_argument).
  const Eigen::VectorXd& contact_torques(const Eigen::Matrix3d& base_rotation, const Eigen::Vector3d& base_translation,
                                         const ConstVector& q, const std::vector<int>& joints, const ConstRows& points,
                                         const ConstRows& forces);

  // pin.rnea on the same model: M(q) a + C(q, v) v + G(q) [N m] under `gravity` [m/s^2] (the model's base frame).
  // The result lives in this object until the next call.  Sizes are checked (std::invalid_argument).
  const Eigen::VectorXd& inverse_dynamics(const Eigen::Vector3d& gravity, const ConstVector& q, const ConstVector& v,
                                          const ConstVector& a);

  int nq() const { return model_.nq; }
  int nv() const { return model_.nv; }

 private:
  pinocchio::Model model_;
  pinocchio::Data data_;
  Eigen::VectorXd zero_, sum_, difference_, plus_, result_;  // work buffers, (nv,)
  pinocchio::Data::Matrix6x jacobian_;                        // (6, nv)
  Eigen::Matrix<double, 3, Eigen::Dynamic> linear_;           // (3, nv): a point's translational rows, world
};

}  // namespace bhgrasp
