// The joint-space terms of one finger that the fingertip workspace dynamics of thesis (2.35)-(2.37) transform
// (bhgrasp/controllers/workspace.py), in one call on Pinocchio's C++ API.
//
// The Python twin is bhgrasp.controllers.workspace._finger_terms_python (the same Pinocchio algorithms through its
// Python API); tests/test_workspace_kernels.py holds both equal to the bit, so the controllers built on them give the
// same torques with or without the compiled core.  The small linear algebra that follows (SVD, inverse, products)
// stays in NumPy: its LAPACK/BLAS rounding is what the published results were computed with.
// Units SI, the hand's model frame (Python turns the results into the world frame, as bhgrasp.hand.Hand does).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include <pinocchio/multibody.hpp>

namespace bhgrasp {

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;  // NumPy's layout

// What Hand.fingertip_positions, fingertip_jacobian, mass_matrix, gravity_torques, nonlinear_effects and
// fingertip_bias_acceleration give for one finger with n_f joints (velocity indices `index`), model frame.
struct FingerTerms {
  RowMatrix positions;       // (fingers, 3) every fingertip frame origin [m]
  RowMatrix jacobian;        // (3, nv) the finger's fingertip translational Jacobian, at the tip, model-frame axes
  RowMatrix mass;            // (n_f, n_f) the finger's block of M(q) [kg m^2]
  Eigen::VectorXd gravity;   // (n_f,) G(q) of the finger's joints [N m]
  Eigen::VectorXd velocity;  // (n_f,) C(q, v) v = nonlinear effects less gravity, of the finger's joints [N m]
  Eigen::Vector3d bias;      // J_dot v: the fingertip's classical acceleration at zero joint acceleration [m/s^2]
};

class FingerDynamics {
 public:
  using ConstVector = Eigen::Ref<const Eigen::VectorXd>;

  // `model`: Pinocchio's text serialisation of the hand (Model.saveToString); its inertias are not changed afterwards.
  // Finger f has its fingertip frame `frames[f]` and its joints at velocity indices `indices[f]` (at least one).
  // Sizes and ids are checked (std::invalid_argument).
  FingerDynamics(const std::string& model, const std::vector<int>& frames,
                 const std::vector<std::vector<int>>& indices);

  // The terms of finger `finger` at (q [rad], v [rad/s]) under `gravity` [m/s^2] (model frame).  The result lives in
  // this object until the next call for the same finger.  Sizes are checked (std::invalid_argument); values are not.
  const FingerTerms& compute(int finger, const Eigen::Vector3d& gravity, const ConstVector& q, const ConstVector& v);

  int nq() const { return model_.nq; }
  int nv() const { return model_.nv; }
  int fingers() const { return static_cast<int>(frames_.size()); }

 private:
  pinocchio::Model model_;
  pinocchio::Data data_;
  std::vector<pinocchio::FrameIndex> frames_;
  std::vector<std::vector<Eigen::Index>> indices_;
  Eigen::VectorXd q_, zero_, gravity_torque_;  // work buffers, (nq,), (nv,), (nv,)
  pinocchio::Data::Matrix6x frame_jacobian_;   // (6, nv)
  std::vector<FingerTerms> terms_;             // one per finger, sized once
};

}  // namespace bhgrasp
