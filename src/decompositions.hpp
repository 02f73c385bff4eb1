// Eigen's decompositions of the matrix types the core factorises, compiled once in decompositions.cpp.  Each costs
// the file that instantiates it memory and time (workspace.cpp: 1.51 GB and 19 s with its SVD, 1.09 GB and 8 s
// without; engine.cpp: 1.58 GB with LLT's and LU's factorisations, 1.48 GB without, their solves stay); the extern
// declarations below make every other file call decompositions.cpp's copy.  The heavy members (JacobiSVD::compute,
// PartialPivLU::compute, LLT::compute) are defined outside their classes without `inline`, so GCC honours the
// declarations: the same code, compiled once.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/LU>
#include <Eigen/SVD>

namespace bhgrasp {

// A finger's fingertip Jacobian J_f: 3 rows, one column per joint of the finger (n_f <= 3), no heap allocation.
using FingerJacobian = Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::ColMajor, 3, 3>;

}  // namespace bhgrasp

extern template class Eigen::JacobiSVD<Eigen::MatrixXd>;
extern template class Eigen::JacobiSVD<bhgrasp::FingerJacobian>;
extern template class Eigen::PartialPivLU<Eigen::MatrixXd>;
extern template class Eigen::LLT<Eigen::MatrixXd>;
extern template Eigen::LLT<Eigen::MatrixXd>& Eigen::LLT<Eigen::MatrixXd>::compute<Eigen::MatrixXd>(
    const Eigen::EigenBase<Eigen::MatrixXd>&);
