// A finger's task-space terms (see workspace.hpp): in bhgrasp/controllers/_workspace_terms.py, workspace() mirrors
// _workspace_dynamics and fingertip_torque() _fingertip_torque (the same maths, line for line).  The joint-space
// terms that workspace() starts from are finger_terms.cpp.
#include "workspace.hpp"
#include "decompositions.hpp"

#include <algorithm>
#include <stdexcept>

#include <Eigen/LU>

namespace bhgrasp {

const WorkspaceTerms& FingerDynamics::workspace(int finger, const Eigen::Vector3d& gravity,
                                                const RowMatrix3& rotation, const Eigen::Vector3d& translation,
                                                const ConstVector& q, const ConstVector& v) {
  const FingerTerms& terms = compute(finger, gravity, q, v);  // checks the finger number and the sizes
  const std::vector<Eigen::Index>& index = indices_[static_cast<std::size_t>(finger)];
  const auto n = static_cast<Eigen::Index>(index.size());
  if (n > 3) throw std::invalid_argument("FingerDynamics.workspace: a finger of at most 3 joints (J_t square)");
  WorkspaceTerms& out = workspace_[static_cast<std::size_t>(finger)];

  // _finger_terms: to the world frame, x_world = R x + p (the hand's products)
  out.position = terms.positions.row(finger).transpose();
  Eigen::Vector3d bias = terms.bias;
  if (rotation.isIdentity(0.0) && translation.isZero(0.0)) {
    out.jacobian = terms.jacobian;
  } else {
    out.position = (rotation * out.position + translation).eval();
    out.jacobian.noalias() = rotation * terms.jacobian;
    bias = rotation * terms.bias;
  }

  // _workspace_dynamics: B from the SVD of J_f (signs made unique), J_t = B^T J_f, then (2.35)-(2.37)
  FingerJacobian jacobian(3, n);
  for (Eigen::Index k = 0; k < n; ++k) jacobian.col(k) = out.jacobian.col(index[k]);
  const Eigen::JacobiSVD<decltype(jacobian)> svd(jacobian, Eigen::ComputeFullU);
  const auto& singular = svd.singularValues();
  out.singular = singular(n - 1) < 1e-6 * std::max(singular(0), 1e-12);
  if (out.singular) return out;
  out.basis = svd.matrixU().leftCols(n);
  for (Eigen::Index j = 0; j < n; ++j) {
    Eigen::Index largest = 0;
    out.basis.col(j).cwiseAbs().maxCoeff(&largest);
    if (out.basis(largest, j) < 0.0) out.basis.col(j) *= -1.0;
  }
  out.task_jacobian.noalias() = out.basis.transpose() * jacobian;
  const TaskMatrix inverse = out.task_jacobian.inverse();
  const TaskMatrix mass_f = terms.mass;
  const TaskMatrix mass_x = inverse.transpose() * mass_f * inverse;
  const TaskVector velocity_f = terms.velocity, gravity_f = terms.gravity;
  const TaskVector bias_t = out.basis.transpose() * bias;
  out.coriolis = inverse.transpose() * velocity_f - mass_x * bias_t;
  out.mass = 0.5 * (mass_x + mass_x.transpose());
  out.gravity = inverse.transpose() * gravity_f;
  return out;
}

TaskVector fingertip_torque(const WorkspaceTerms& terms, const Eigen::Ref<const Eigen::VectorXd>& velocity,
                            const Eigen::Vector3d& x_d, const Eigen::Vector3d& xd_d, const Eigen::Vector3d& xdd_d,
                            const RowMatrix3& kp, const RowMatrix3& kv) {
  if (terms.singular || velocity.size() != terms.task_jacobian.cols())
    throw std::invalid_argument("fingertip_torque: terms of a regular configuration, velocity of size n_f");
  const TaskMatrix& b = terms.basis;
  const TaskMatrix& jacobian = terms.task_jacobian;
  const TaskVector velocity_f = velocity;
  const Eigen::Vector3d error = terms.position - x_d;
  const TaskVector error_dot = jacobian * velocity_f - b.transpose() * xd_d;  // task coordinates: J_t q_f' = B^T x'
  const TaskMatrix kp_t = b.transpose() * kp * b, kv_t = b.transpose() * kv * b;
  const TaskVector command = b.transpose() * xdd_d - kv_t * error_dot - kp_t * (b.transpose() * error);
  return jacobian.transpose() * (terms.mass * command + terms.coriolis + terms.gravity);
}

}  // namespace bhgrasp
