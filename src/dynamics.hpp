// A hand's inverse dynamics for its control laws, on Pinocchio's C++ API (bhgrasp/hand.py: Hand).
// The Python twin is Hand.slotine_li_torque's NumPy path; tests/test_hand_kernels.py holds both to the bit.
// Units SI; joint space of the hand's model.
#pragma once

#include <string>

#include <Eigen/Core>

#include <pinocchio/multibody.hpp>

namespace bhgrasp {

class HandDynamics {
 public:
  using ConstVector = Eigen::Ref<const Eigen::VectorXd>;

  // `model`: Pinocchio's text serialisation of the hand (Model.saveToString); its inertias are not changed afterwards.
  explicit HandDynamics(const std::string& model);

  // M(q) a_r + C(q, v) v_r + G(q) [N m] under `gravity` [m/s^2] (in the model's base frame): the Christoffel C by
  // polarisation of RNEA's velocity products, C(q, v) v_r = (h(v + v_r) - h(v - v_r)) / 4, three RNEA passes.
  // The result lives in this object until the next call.  Sizes are checked (std::invalid_argument).
  const Eigen::VectorXd& slotine_li_torque(const Eigen::Vector3d& gravity, const ConstVector& q, const ConstVector& v,
                                           const ConstVector& v_r, const ConstVector& a_r);

  int nq() const { return model_.nq; }
  int nv() const { return model_.nv; }

 private:
  pinocchio::Model model_;
  pinocchio::Data data_;
  Eigen::VectorXd zero_, sum_, difference_, plus_, result_;  // work buffers, (nv,)
};

}  // namespace bhgrasp
