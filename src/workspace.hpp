// The fingertip workspace dynamics of thesis (2.35)-(2.37) (bhgrasp/controllers/workspace.py) on Pinocchio's C++ API:
// the joint-space terms of one finger (FingerDynamics::compute), the task-space terms built from them
// (FingerDynamics::workspace: SVD, inverse and products in Eigen) and the fingertip computed torque (fingertip_torque).
//
// Python twins (bhgrasp.controllers._workspace_terms): _finger_terms_python (the same Pinocchio algorithms through
// its Python API; equal to the bit), _workspace_dynamics and _fingertip_torque (NumPy; equal to round-off, 1e-12
// relative): tests/test_workspace_kernels.py.  Units SI; compute() in the hand's model frame, workspace() and
// fingertip_torque() in the world frame (the hand's base placement passed in).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include <pinocchio/multibody.hpp>

#include "options.hpp"

namespace bhgrasp {

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

// Matrices and vectors of the task space (r <= 3 rows) of a finger of n_f <= 3 joints: no heap allocation.
using TaskMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor, 3, 3>;
using TaskVector = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, 3, 1>;
using RowMatrix3 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;  // a (3, 3) C-order array, taken without reordering

// Thesis (2.35)-(2.37) for one finger of n_f <= 3 joints in task coordinates x_t = B^T x, world frame, r = n_f.
struct WorkspaceTerms {
  bool singular = false;     // sigma_r < 1e-6 max(sigma_1, 1e-12) (J_f of rank < r): the task fields are not set
  Eigen::Vector3d position;  // the finger's fingertip [m]
  RowMatrix jacobian;        // (3, nv) its translational Jacobian J (world axes)
  TaskMatrix basis;          // (3, r) orthonormal basis B of the column space of J_f, each column's largest entry > 0
  TaskMatrix task_jacobian;  // (r, n_f) J_t = B^T J_f
  TaskMatrix mass;           // (r, r) M_x = J_t^-T M_f J_t^-1 [kg], symmetrised
  TaskVector coriolis;       // (r,) C_x x_dot = J_t^-T (C q_dot)_f - M_x B^T J_dot q_dot [N]
  TaskVector gravity;        // (r,) G_x = J_t^-T G_f [N]
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

  // The workspace terms of finger `finger` (n_f <= 3 joints, else std::invalid_argument) at (q, v) for a hand base
  // at (`rotation`, `translation`) in the world and `gravity` in the model frame.  Lives here until the next call for
  // the same finger, as compute()'s result (the binding returns a copy).
  const WorkspaceTerms& workspace(int finger, const Eigen::Vector3d& gravity, const RowMatrix3& rotation,
                                  const Eigen::Vector3d& translation, const ConstVector& q, const ConstVector& v);

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
  std::vector<WorkspaceTerms> workspace_;      // one per finger, sized once
};

// Fingertip computed torque (bhgrasp.controllers.workspace.WorkspaceComputedTorque) from a finger's workspace terms,
// its joint velocities `velocity` (n_f,), the reference x_d [m], x_dot_d, x_ddot_d and the Cartesian gains kp, kv:
//   tau_f = J_t^T (M_x (B^T x_ddot_d - Kv_t e_dot - Kp_t B^T e) + C_x x_dot + G_x),
//   e = x - x_d, e_dot = J_t q_dot_f - B^T x_dot_d, Kp_t = B^T Kp B, Kv_t = B^T Kv B.
// Sizes are checked (std::invalid_argument), and that the terms are not singular.
TaskVector fingertip_torque(const WorkspaceTerms& terms, const Eigen::Ref<const Eigen::VectorXd>& velocity,
                            const Eigen::Vector3d& x_d, const Eigen::Vector3d& xd_d, const Eigen::Vector3d& xdd_d,
                            const RowMatrix3& kp, const RowMatrix3& kv);

}  // namespace bhgrasp
