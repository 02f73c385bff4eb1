#include "dynamics.hpp"

#include <stdexcept>

#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/serialization.hpp>

namespace bhgrasp {

HandDynamics::HandDynamics(const std::string& model) {
  model_.loadFromString(model);
  data_ = pinocchio::Data(model_);
  zero_ = Eigen::VectorXd::Zero(model_.nv);
  sum_.resize(model_.nv);
  difference_.resize(model_.nv);
  plus_.resize(model_.nv);
  result_.resize(model_.nv);
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

}  // namespace bhgrasp
