// The grasp kinematics kernel: see grasp.hpp.  compute() mirrors contact_kinematics_python in
// bhgrasp/grasp/kinematics.py line for line; the comments there and the module docstring explain the maths.
#include "grasp.hpp"
#include "model_io.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

#include <pinocchio/algorithm/jacobian.hpp>
#include <pinocchio/spatial/skew.hpp>

namespace bhgrasp {

GraspKinematics::GraspKinematics(const std::string& model) {
  model_ = model_from_text(model);
  data_ = pinocchio::Data(model_);
  masks_ = Eigen::MatrixXd::Zero(model_.njoints, model_.nv);  // (_HandIndex.masks of grasp/kinematics.py)
  for (int joint = 1; joint < model_.njoints; ++joint) {
    const auto& supports = model_.supports[static_cast<std::size_t>(joint)];
    for (std::size_t k = 1; k < supports.size(); ++k) {  // [0] is the universe
      const auto& ancestor = model_.joints[supports[k]];
      masks_.row(joint).segment(ancestor.idx_v(), ancestor.nv()).setOnes();
    }
  }
  spatial_.resize(6, model_.nv);
  rate_.resize(6, model_.nv);
  at_com_.resize(3, model_.nv);
  rate_at_com_.resize(3, model_.nv);
  p_map_.resize(model_.nv, 6);
  p_dot_.resize(model_.nv, 6);
  lifted_.resize(model_.nv, 6);
  gram_.resize(model_.nv, model_.nv);
  q_dot_.resize(model_.nv);
}

void GraspKinematics::resize(Eigen::Index count) {
  const Eigen::Index nv = model_.nv, rows = 3 * count;
  jacobian_world_.resize(rows, nv);
  jacobian_rate_.resize(rows, nv);
  pinv_world_.resize(nv, rows);
  grasp_t_.setZero(rows, 6);
  grasp_t_rate_.setZero(rows, 6);  // its first three columns stay zero
  for (Eigen::Index i = 0; i < count; ++i) grasp_t_.block<3, 3>(3 * i, 0).setIdentity();  // they stay I
  residual_.resize(rows, 6);
  rate_t_.resize(nv, rows);
  projected_.resize(rows, rows);
  maps_.joint_map.resize(nv, 6);
  maps_.joint_map_rate.resize(nv, 6);
  maps_.grasp_map.resize(6, rows);
  maps_.hand_jacobian.resize(rows, nv);
  maps_.hand_jacobian_pinv.resize(nv, rows);
  count_ = count;
}

// J^+ as np.linalg.pinv(J) (V diag(1/s) U^T, singular values at or below 1e-15 of the largest dropped), by blocks.
// A contact's rows of J are nonzero only in the columns of the joints that move its body (masks_), so contacts on
// bodies that share no moving joint (different fingers) have rows in disjoint columns: J is block diagonal up to an
// order of rows and columns, its singular values are its blocks', and J^+ is the blocks' pseudo-inverses put back in
// place (transposed).  A block gathers the contacts linked by shared joints; each gets its own SVD, kept between calls.
// The BH8-280's three fingertips make two 3x3 blocks (fixed-size SVDs) and a 3x2 one (F3 has no spread): a fraction of
// the cost of one SVD of the whole 9x8 J with its QR preconditioner; the result is the same up to round-off
// (tests/test_grasp_kernels.py holds it to NumPy's pinv of the whole J).
void GraspKinematics::pinv_by_blocks(const std::vector<int>& joints) {
  if (!jacobian_world_.allFinite()) {  // NaN in, NaN out (outside the masks too), as an SVD of the whole J gives
    pinv_world_.setConstant(std::numeric_limits<double>::quiet_NaN());
    return;
  }
  const auto count = static_cast<std::size_t>(count_);
  block_of_.assign(count, -1);
  std::size_t blocks = 0;
  for (std::size_t i = 0; i < count; ++i) {  // each block: the closure of its first contact under shared joints
    if (block_of_[i] >= 0) continue;
    block_of_[i] = static_cast<int>(blocks);
    Eigen::RowVectorXd& columns = block_mask_;
    columns = masks_.row(joints[i]);
    for (bool grown = true; grown;) {
      grown = false;
      for (std::size_t j = i + 1; j < count; ++j) {
        if (block_of_[j] >= 0 || !(masks_.row(joints[j]).array() * columns.array()).any()) continue;
        block_of_[j] = static_cast<int>(blocks);
        columns = columns.cwiseMax(masks_.row(joints[j]));
        grown = true;
      }
    }
    if (block_rows_.size() <= blocks) {
      block_rows_.resize(blocks + 1);
      block_columns_.resize(blocks + 1);
      block_.resize(blocks + 1);
      block_pinv_.resize(blocks + 1);
      block_svd_.resize(blocks + 1);
      block_inverse_.resize(blocks + 1);
      block_scaled_.resize(blocks + 1);
      block_u_.resize(blocks + 1);
      block_v_.resize(blocks + 1);
      block_singular_.resize(blocks + 1);
    }
    block_columns_[blocks].clear();
    for (Eigen::Index c = 0; c < columns.size(); ++c)
      if (columns[c] != 0.0) block_columns_[blocks].push_back(c);
    ++blocks;
  }
  for (std::size_t b = 0; b < blocks; ++b) block_rows_[b].clear();
  for (std::size_t i = 0; i < count; ++i)
    for (Eigen::Index k = 0; k < 3; ++k)
      block_rows_[static_cast<std::size_t>(block_of_[i])].push_back(3 * static_cast<Eigen::Index>(i) + k);
  double largest = 0.0;
  for (std::size_t b = 0; b < blocks; ++b) {
    const auto& rows = block_rows_[b];
    const auto& columns = block_columns_[b];
    if (columns.empty()) continue;  // contacts on bodies no joint moves (the palm): zero rows, zero columns of J^+
    Eigen::MatrixXd& block = block_[b];
    block.resize(static_cast<Eigen::Index>(rows.size()), static_cast<Eigen::Index>(columns.size()));
    for (std::size_t r = 0; r < rows.size(); ++r)
      for (std::size_t c = 0; c < columns.size(); ++c)
        block(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = jacobian_world_(rows[r], columns[c]);
    if (block.rows() == 3 && block.cols() == 3) {  // one contact on a three-joint finger: a fixed-size SVD
      square_svd_.compute(Eigen::Matrix3d(block), Eigen::ComputeFullU | Eigen::ComputeFullV);
      block_u_[b] = square_svd_.matrixU();
      block_v_[b] = square_svd_.matrixV();
      block_singular_[b] = square_svd_.singularValues();
    } else {
      auto& svd = block_svd_[b];
      svd.compute(block, Eigen::ComputeThinU | Eigen::ComputeThinV);  // allocates when a size changes
      block_u_[b] = svd.matrixU();
      block_v_[b] = svd.matrixV();
      block_singular_[b] = svd.singularValues();
    }
    largest = std::max(largest, block_singular_[b][0]);
  }
  pinv_world_.setZero();
  for (std::size_t b = 0; b < blocks; ++b) {
    const auto& rows = block_rows_[b];
    const auto& columns = block_columns_[b];
    if (columns.empty()) continue;
    const Eigen::VectorXd& singular = block_singular_[b];
    Eigen::VectorXd& inverse = block_inverse_[b];
    inverse.resize(singular.size());
    for (Eigen::Index k = 0; k < singular.size(); ++k)
      inverse[k] = singular[k] > 1e-15 * largest ? 1.0 / singular[k] : 0.0;
    block_scaled_[b] = block_v_[b] * inverse.asDiagonal();
    block_pinv_[b].noalias() = block_scaled_[b] * block_u_[b].transpose();
    for (std::size_t c = 0; c < columns.size(); ++c)
      for (std::size_t r = 0; r < rows.size(); ++r)
        pinv_world_(columns[c], rows[r]) = block_pinv_[b](static_cast<Eigen::Index>(c), static_cast<Eigen::Index>(r));
  }
}

const GraspMaps& GraspKinematics::compute(const Eigen::Matrix3d& base_rotation, const Eigen::Vector3d& base_translation,
                                          const ConstVector& q, const Eigen::Vector3d& com, const Vector6& twist,
                                          const ConstRows& points, const ConstRows& frames,
                                          const std::vector<int>& joints) {
  const Eigen::Index count = points.rows();
  if (q.size() != model_.nq || count == 0 || points.cols() != 3 || frames.rows() != 3 * count ||
      frames.cols() != 3 || static_cast<Eigen::Index>(joints.size()) != count)
    throw std::invalid_argument("GraspKinematics.compute: q of size nq, points (n, 3) with n >= 1, frames (3n, 3) "
                                "and n joints are needed");
  for (int joint : joints)
    if (joint < 0 || joint >= model_.njoints) throw std::invalid_argument("a contact names a joint the model lacks");
  if (count != count_) resize(count);
  const Eigen::Matrix<double, 6, 6> action = pinocchio::SE3(base_rotation, base_translation).toActionMatrix();
  const bool moved = !(base_rotation.isIdentity(0.0) && base_translation.isZero(0.0));  // world = placement * model
  const Eigen::Vector3d velocity = twist.head<3>(), omega = twist.tail<3>();
  const Eigen::Matrix3d com_skew = pinocchio::skew(com);

  // J_i = J^W_lin - skew(c) J^W_ang - skew(r_i) J^W_ang (the world Jacobian moved to the COM, then to p_i)
  pinocchio::computeJointJacobians(model_, data_, q);
  if (moved)
    spatial_.noalias() = action * data_.J;  // J^W (6, nv), world
  else
    spatial_ = data_.J;
  const auto angular = spatial_.bottomRows<3>();
  at_com_ = spatial_.topRows<3>();
  at_com_.noalias() -= com_skew.lazyProduct(angular);
  for (Eigen::Index i = 0; i < count; ++i) {
    const Eigen::Vector3d offset = points.row(i).transpose() - com;  // r_i = p_i - c [m]
    auto block = jacobian_world_.middleRows<3>(3 * i);
    block = at_com_;
    block.noalias() -= pinocchio::skew(offset).lazyProduct(angular);
    block.array().rowwise() *= masks_.row(joints[static_cast<std::size_t>(i)]).array();
    grasp_t_.block<3, 3>(3 * i, 3) = -pinocchio::skew(offset);
  }
  pinv_by_blocks(joints);  // J^+ (nv, 3n)
  p_map_.noalias() = pinv_world_ * grasp_t_;  // P = J^+ G_w^T (nv, 6)

  // J_dot_i = J^W_dot_lin - skew(c) J^W_dot_ang - skew(v) J^W_ang - skew(r_i) J^W_dot_ang - skew(omega x r_i) J^W_ang
  q_dot_.noalias() = p_map_ * twist;
  pinocchio::computeJointJacobiansTimeVariation(model_, data_, q, ConstVector(q_dot_));
  if (moved)
    rate_.noalias() = action * data_.dJ;  // J^W_dot (6, nv) [1/s]
  else
    rate_ = data_.dJ;
  const auto rate_angular = rate_.bottomRows<3>();
  rate_at_com_ = rate_.topRows<3>();
  rate_at_com_.noalias() -= com_skew.lazyProduct(rate_angular);
  rate_at_com_.noalias() -= pinocchio::skew(velocity).lazyProduct(angular);
  for (Eigen::Index i = 0; i < count; ++i) {
    const Eigen::Vector3d offset = points.row(i).transpose() - com;
    const Eigen::Matrix3d sweep = pinocchio::skew(omega.cross(offset));  // skew(omega x r_i)
    auto block = jacobian_rate_.middleRows<3>(3 * i);
    block = rate_at_com_;
    block.noalias() -= pinocchio::skew(offset).lazyProduct(rate_angular);
    block.noalias() -= sweep.lazyProduct(angular);
    block.array().rowwise() *= masks_.row(joints[static_cast<std::size_t>(i)]).array();
    grasp_t_rate_.block<3, 3>(3 * i, 3) = -sweep;
  }
  // P_dot = d(J^+) G_w^T + J^+ G_w_dot^T, d(J^+) by Golub-Pereyra, multiplied out right to left
  rate_t_ = jacobian_rate_.transpose();
  residual_ = grasp_t_rate_;
  residual_.noalias() -= jacobian_rate_ * p_map_;
  p_dot_.noalias() = pinv_world_ * residual_;  // J^+ (G_w_dot^T - J_dot P)
  residual_ = grasp_t_;
  residual_.noalias() -= jacobian_world_ * p_map_;
  lifted_.noalias() = rate_t_ * residual_;
  gram_.noalias() = pinv_world_ * pinv_world_.transpose();
  p_dot_.noalias() += gram_ * lifted_;  // + J^+ J^+T J_dot^T (G_w^T - J P)
  projected_.noalias() = jacobian_world_ * rate_t_;
  rate_t_.noalias() -= pinv_world_ * projected_;
  residual_.noalias() = pinv_world_.transpose() * p_map_;
  p_dot_.noalias() += rate_t_ * residual_;  // + (I - J^+ J) J_dot^T J^+T P

  // contact coordinates: J_h = R^T J, J_h^+ = J^+ R, G = G_w R (blockwise)
  for (Eigen::Index i = 0; i < count; ++i) {
    const Eigen::Matrix3d frame = frames.middleRows<3>(3 * i);
    maps_.hand_jacobian.middleRows<3>(3 * i).noalias() =
        frame.transpose().lazyProduct(jacobian_world_.middleRows<3>(3 * i));
    maps_.hand_jacobian_pinv.middleCols<3>(3 * i).noalias() = pinv_world_.middleCols<3>(3 * i).lazyProduct(frame);
    maps_.grasp_map.middleCols<3>(3 * i).noalias() = grasp_t_.middleRows<3>(3 * i).transpose().lazyProduct(frame);
  }
  maps_.joint_map = p_map_;
  maps_.joint_map_rate = p_dot_;
  return maps_;
}

}  // namespace bhgrasp
