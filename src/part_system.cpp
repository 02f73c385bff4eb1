// The velocity system by parts: see part_system.hpp.  Each function mirrors bhgrasp/sim/part_system.py (PartSystem).
#include "part_system.hpp"

#include <limits>

namespace bhgrasp {

void PartSystem::begin(const Matrix& hand_transmission, const std::vector<Matrix>& blocks,
                       const std::vector<Eigen::Index>& first, Eigen::Index nv) {
  transmission_ = hand_transmission;
  nv_hand_ = hand_transmission.rows();
  driven_ = hand_transmission.cols();
  size_ = driven_ + nv - nv_hand_;
  base_.clear();
  for (std::size_t p = 0; p < blocks.size(); ++p) {
    if (p == 0) hand_block_ = transmission_.transpose() * blocks[p] * transmission_;
    const Matrix& block = p == 0 ? hand_block_ : blocks[p];
    const Eigen::Index at = p == 0 ? 0 : reduced_index(first[p]);
    for (Eigen::Index c = 0; c < block.cols(); ++c)
      for (Eigen::Index r = 0; r < block.rows(); ++r) base_.emplace_back(at + r, at + c, block(r, c));
  }
  analysed_ = false;
}

Eigen::Index PartSystem::reduced_index(Eigen::Index scene) const {
  return scene < nv_hand_ ? scene : scene - nv_hand_ + driven_;
}

void PartSystem::reduce_block(const PartJacobian& jacobian, int k) {
  const auto s = static_cast<std::size_t>(k);
  if (jacobian.first[s] < nv_hand_) {  // the hand's part: its columns start at 0
    reduced_[s].noalias() = jacobian.block[s] * transmission_;
  } else {
    reduced_[s] = jacobian.block[s];
  }
}

void PartSystem::solve(const std::vector<PartJacobian>& jacobians, Eigen::Index contacts,
                       const std::vector<Matrix3>& gains, double scale, const Vector& rhs, Vector& solution) {
  triplets_ = base_;
  for (Eigen::Index i = 0; i < contacts; ++i) {
    const PartJacobian& jacobian = jacobians[static_cast<std::size_t>(i)];
    for (int a = 0; a < jacobian.count; ++a) reduce_block(jacobian, a);
    for (int b = 0; b < jacobian.count; ++b) {
      const auto sb = static_cast<std::size_t>(b);
      gain_block_.noalias() = scale * (gains[static_cast<std::size_t>(i)] * reduced_[sb]);
      const Eigen::Index column = reduced_index(jacobian.first[sb]);
      for (int a = 0; a < jacobian.count; ++a) {
        const auto sa = static_cast<std::size_t>(a);
        coupling_.noalias() = reduced_[sa].transpose() * gain_block_;
        const Eigen::Index row = reduced_index(jacobian.first[sa]);
        for (Eigen::Index c = 0; c < coupling_.cols(); ++c)
          for (Eigen::Index r = 0; r < coupling_.rows(); ++r) triplets_.emplace_back(row + r, column + c, coupling_(r, c));
      }
    }
  }
  matrix_.resize(size_, size_);
  matrix_.setFromTriplets(triplets_.begin(), triplets_.end());
  right_.resize(size_);
  right_.head(driven_).noalias() = transmission_.transpose() * rhs.head(nv_hand_);
  right_.tail(size_ - driven_) = rhs.tail(rhs.size() - nv_hand_);
  if (!analysed_) {
    cholesky_.analyzePattern(matrix_);
    analysed_ = true;
  }
  cholesky_.factorize(matrix_);
  if (cholesky_.info() == Eigen::Success) {
    reduced_solution_ = cholesky_.solve(right_);
  } else {
    lu_.compute(matrix_);
    if (lu_.info() == Eigen::Success) {
      reduced_solution_ = lu_.solve(right_);
    } else {  // singular: a non-finite step, which the divergence check reports
      reduced_solution_.setConstant(size_, std::numeric_limits<double>::quiet_NaN());
    }
  }
  solution.resize(rhs.size());
  solution.head(nv_hand_).noalias() = transmission_ * reduced_solution_.head(driven_);
  solution.tail(rhs.size() - nv_hand_) = reduced_solution_.tail(size_ - driven_);
}

}  // namespace bhgrasp
