#include "dynamics.hpp"
#include "model_io.hpp"

#include <stdexcept>

#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/algorithm/jacobian.hpp>
#include <pinocchio/algorithm/rnea.hpp>

namespace bhgrasp {

HandDynamics::HandDynamics(const std::string& model) {
  model_ = model_from_text(model);
  data_ = pinocchio::Data(model_);
  zero_ = Eigen::VectorXd::Zero(model_.nv);
  sum_.resize(model_.nv);
  difference_.resize(model_.nv);
  plus_.resize(model_.nv);
  result_.resize(model_.nv);
  jacobian_.resize(6, model_.nv);
  linear_.resize(3, model_.nv);
}

const Eigen::VectorXd& HandDynamics::slotine_li_torque(const Eigen::Vector3d& gravity, const ConstVector& q,
                                                       const ConstVector& v, const ConstVector& v_r,
                                                       const ConstVector& a_r) {
  if (q.size() != model_.nq || v.size() != model_.nv || v_r.size() != model_.nv || a_r.size() != model_.nv)
    throw std::invalid_argument("q, v, v_r or a_r of the wrong size");
  using Ref = Eigen::Ref<const Eigen::VectorXd>;
  model_.gravity.linear(gravity);
  sum_ = v + v_r;
  difference_ = v - v_r;
  plus_ = pinocchio::rnea(model_, data_, Ref(q), Ref(sum_), Ref(zero_));
  const Eigen::VectorXd& minus = pinocchio::rnea(model_, data_, Ref(q), Ref(difference_), Ref(zero_));
  result_ = plus_ - minus;  // gravity cancels in the difference
  result_ *= 0.25;
  result_ += pinocchio::rnea(model_, data_, Ref(q), Ref(zero_), Ref(a_r));  // (as NumPy: rnea + 0.25 (plus - minus))
  return result_;
}

const Eigen::VectorXd& HandDynamics::inverse_dynamics(const Eigen::Vector3d& gravity, const ConstVector& q,
                                                      const ConstVector& v, const ConstVector& a) {
  if (q.size() != model_.nq || v.size() != model_.nv || a.size() != model_.nv)
    throw std::invalid_argument("q, v or a of the wrong size");
  using Ref = Eigen::Ref<const Eigen::VectorXd>;
  model_.gravity.linear(gravity);
  result_ = pinocchio::rnea(model_, data_, Ref(q), Ref(v), Ref(a));
  return result_;
}

const Eigen::VectorXd& HandDynamics::contact_torques(const Eigen::Matrix3d& base_rotation,
                                                     const Eigen::Vector3d& base_translation, const ConstVector& q,
                                                     const std::vector<int>& joints, const ConstRows& points,
                                                     const ConstRows& forces) {
  const Eigen::Index count = points.rows();
  if (q.size() != model_.nq || forces.rows() != count || static_cast<Eigen::Index>(joints.size()) != count)
    throw std::invalid_argument("contact_torques: q of size nq, points and forces (n, 3) and n joints are needed");
  for (int joint : joints)
    if (joint < 0 || joint >= model_.njoints) throw std::invalid_argument("a contact names a joint the model lacks");
  const bool moved = !(base_rotation.isIdentity(0.0) && base_translation.isZero(0.0));  // (Hand._base_at_origin)
  pinocchio::computeJointJacobians(model_, data_, q);  // places the joints too
  result_.setZero();
  for (Eigen::Index i = 0; i < count; ++i) {  // Hand.point_jacobians, then the sum of J_i^T f_i
    const auto joint = static_cast<pinocchio::JointIndex>(joints[static_cast<std::size_t>(i)]);
    Eigen::Vector3d point = points.row(i).transpose();
    if (moved) point = base_rotation.transpose() * (point - base_translation);  // the point in the model frame
    const pinocchio::SE3 on_joint(Eigen::Matrix3d::Identity(), data_.oMi[joint].actInv(point));
    jacobian_.setZero();
    pinocchio::getFrameJacobian(model_, data_, joint, on_joint, pinocchio::LOCAL_WORLD_ALIGNED, jacobian_);
    if (moved)
      linear_.noalias() = base_rotation * jacobian_.topRows<3>();
    else
      linear_ = jacobian_.topRows<3>();
    result_.noalias() -= linear_.transpose() * forces.row(i).transpose();
  }
  return result_;
}

}  // namespace bhgrasp
