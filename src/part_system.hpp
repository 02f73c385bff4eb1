// The implicit step's velocity system for scenes of many parts (bhgrasp/sim/part_system.py, PartSystem, is its twin and
// gives the reasons): M and the joint terms are block diagonal by part (the hand's joints, each object's), and a
// contact couples at most the two parts it touches, so the system
//     T^T (A + dt sum_i J_i^T G_i J_i) T w = T^T b,   v+ = T w,   A = M + dt diag(dt K + C)
// is assembled from the parts' diagonal blocks and each contact's at most four coupling blocks, and solved by a sparse
// Cholesky factorisation (Eigen's SimplicialLLT, AMD ordering; a sparse LU if it is not positive definite).  T is the
// hand's transmission on the hand's columns and the identity on the objects'.  Work and memory grow with the parts and
// the contacts, not with nv^2.
#pragma once

#include <array>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <Eigen/SparseLU>

#include "options.hpp"
#include "part_jacobian.hpp"

namespace bhgrasp {

class PartSystem {
 public:
  // One step: the hand's transmission T (nv_hand, n_driven) and each part's block A_p, the hand's first (the scene's
  // part layout: first velocities `first`, nv_hand the hand's).  Reduces the hand's block to T^T A_0 T.
  void begin(const Matrix& hand_transmission, const std::vector<Matrix>& blocks, const std::vector<Eigen::Index>& first,
             Eigen::Index nv);
  // Solve for v+ (nv,) with the contacts' Jacobians and gains G_i (scaled by `scale`; none: A alone) and the right
  // side b (nv,).  The first solve of a step orders and analyses the pattern; the step's later ones reuse it (the
  // same contacts: a contact whose gains are zero keeps its entries).
  void solve(const std::vector<PartJacobian>& jacobians, Eigen::Index contacts, const std::vector<Matrix3>& gains,
             double scale, const Vector& rhs, Vector& solution);

 private:
  Eigen::Index reduced_index(Eigen::Index scene) const;  // a scene velocity's column in the driven coordinates
  // Block k of a contact in the driven coordinates (the hand's J T, an object's as it is), into reduced_[k].
  void reduce_block(const PartJacobian& jacobian, int k);

  Matrix transmission_;          // the hand's T
  Eigen::Index nv_hand_ = 0, driven_ = 0, size_ = 0;  // hand velocities, its driven coordinates, the reduced system
  std::vector<Eigen::Triplet<double>> base_, triplets_;  // the parts' blocks; with the contacts'
  Eigen::SparseMatrix<double> matrix_;
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> cholesky_;
  Eigen::SparseLU<Eigen::SparseMatrix<double>> lu_;
  bool analysed_ = false;
  std::array<PartJacobian::Block, 2> reduced_;
  PartJacobian::Block gain_block_;
  Matrix coupling_, hand_block_;  // a contact's coupling block; T^T A_0 T
  Vector right_, reduced_solution_;
};

}  // namespace bhgrasp
