// The finger kernels: see workspace.hpp.  In bhgrasp/controllers/_workspace_terms.py, compute() mirrors
// _finger_terms_python (the same Pinocchio algorithms, called as the Python API calls them), workspace()
// _workspace_dynamics and fingertip_torque() _fingertip_torque (the same maths, line for line).
#include "workspace.hpp"

#include <algorithm>
#include <stdexcept>

#include <Eigen/LU>
#include <Eigen/SVD>

#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/algorithm/kinematics.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/serialization.hpp>

namespace bhgrasp {

FingerDynamics::FingerDynamics(const std::string& model, const std::vector<int>& frames,
                               const std::vector<std::vector<int>>& indices) {
  model_.loadFromString(model);
  data_ = pinocchio::Data(model_);
  if (frames.size() != indices.size()) throw std::invalid_argument("one fingertip frame and one index list a finger");
  for (std::size_t f = 0; f < frames.size(); ++f) {
    if (frames[f] < 0 || frames[f] >= static_cast<int>(model_.nframes))
      throw std::invalid_argument("a fingertip frame id the model lacks");
    if (indices[f].empty()) throw std::invalid_argument("a finger without joints");
    std::vector<Eigen::Index> index;
    for (int i : indices[f]) {
      if (i < 0 || i >= model_.nv) throw std::invalid_argument("a joint index outside 0 .. nv - 1");
      index.push_back(i);
    }
    frames_.push_back(static_cast<pinocchio::FrameIndex>(frames[f]));
    indices_.push_back(std::move(index));
  }
  q_.resize(model_.nq);
  zero_ = Eigen::VectorXd::Zero(model_.nv);
  gravity_torque_.resize(model_.nv);
  frame_jacobian_.resize(6, model_.nv);
  terms_.resize(frames_.size());
  workspace_.resize(frames_.size());
  for (std::size_t f = 0; f < frames_.size(); ++f) {
    const auto n = static_cast<Eigen::Index>(indices_[f].size());
    terms_[f].positions.resize(static_cast<Eigen::Index>(frames_.size()), 3);
    terms_[f].jacobian.resize(3, model_.nv);
    terms_[f].mass.resize(n, n);
    terms_[f].gravity.resize(n);
    terms_[f].velocity.resize(n);
    workspace_[f].jacobian.resize(3, model_.nv);
  }
}

const FingerTerms& FingerDynamics::compute(int finger, const Eigen::Vector3d& gravity, const ConstVector& q,
                                           const ConstVector& v) {
  if (finger < 0 || finger >= fingers() || q.size() != model_.nq || v.size() != model_.nv)
    throw std::invalid_argument("FingerDynamics: a finger number 0 .. fingers - 1, q of size nq, v of size nv");
  using Ref = Eigen::Ref<const Eigen::VectorXd>;
  const std::vector<Eigen::Index>& index = indices_[static_cast<std::size_t>(finger)];
  const pinocchio::FrameIndex frame = frames_[static_cast<std::size_t>(finger)];
  const auto n = static_cast<Eigen::Index>(index.size());
  model_.gravity.linear(gravity);
  FingerTerms& out = terms_[static_cast<std::size_t>(finger)];
  q_ = q;

  // Hand.fingertip_positions: framesForwardKinematics, then every fingertip frame's origin
  pinocchio::framesForwardKinematics(model_, data_, q_);
  for (std::size_t f = 0; f < frames_.size(); ++f)
    out.positions.row(static_cast<Eigen::Index>(f)) = data_.oMf[frames_[f]].translation().transpose();

  // Hand.fingertip_jacobian: computeFrameJacobian (world-aligned at the frame), its translational rows
  frame_jacobian_.setZero();
  pinocchio::computeFrameJacobian(model_, data_, q_, frame, pinocchio::LOCAL_WORLD_ALIGNED, frame_jacobian_);
  out.jacobian = frame_jacobian_.topRows<3>();

  // Hand.mass_matrix: CRBA's upper triangle, mirrored; the finger's block
  const Eigen::MatrixXd& mass = pinocchio::crba(model_, data_, Ref(q));
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < n; ++j)
      out.mass(i, j) = mass(std::min(index[i], index[j]), std::max(index[i], index[j]));

  // Hand.gravity_torques, Hand.nonlinear_effects less gravity
  gravity_torque_ = pinocchio::computeGeneralizedGravity(model_, data_, Ref(q));
  const Eigen::VectorXd& effects = pinocchio::nonLinearEffects(model_, data_, Ref(q), Ref(v));
  for (Eigen::Index k = 0; k < n; ++k) {
    out.gravity[k] = gravity_torque_[index[k]];
    out.velocity[k] = effects[index[k]] - gravity_torque_[index[k]];
  }

  // Hand.fingertip_bias_acceleration: second-order kinematics at zero acceleration, the frame's classical acceleration
  pinocchio::forwardKinematics(model_, data_, Ref(q), Ref(v), Ref(zero_));
  out.bias = pinocchio::getFrameClassicalAcceleration(model_, data_, frame, pinocchio::LOCAL_WORLD_ALIGNED).linear();
  return out;
}

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
  Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::ColMajor, 3, 3> jacobian(3, n);
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
