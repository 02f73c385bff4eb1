// A finger's joint-space terms, FingerDynamics' constructor and compute() (see workspace.hpp): the mirror of
// _finger_terms_python in bhgrasp/controllers/_workspace_terms.py (the same Pinocchio algorithms, called as the
// Python API calls them).  The task-space part is workspace.cpp, apart because each half takes ~30 s to compile.
#include "workspace.hpp"
#include "frame_jacobian.hpp"
#include "model_io.hpp"

#include <algorithm>
#include <stdexcept>

#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/algorithm/kinematics.hpp>
#include <pinocchio/algorithm/rnea.hpp>

namespace bhgrasp {

FingerDynamics::FingerDynamics(const std::string& model, const std::vector<int>& frames,
                               const std::vector<std::vector<int>>& indices) {
  model_ = model_from_text(model);
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
  compute_frame_jacobian(model_, data_, q_, frame, pinocchio::LOCAL_WORLD_ALIGNED, frame_jacobian_);
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

}  // namespace bhgrasp
