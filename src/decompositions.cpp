// The instantiations decompositions.hpp declares: the grasp maps' pseudo-inverse (grasp.cpp, JacobiSVD of MatrixXd),
// the finger's task basis (workspace.cpp, JacobiSVD of FingerJacobian), the engine's reduced solve (engine.cpp, LLT
// and its PartialPivLU fallback).
#include "decompositions.hpp"

template class Eigen::JacobiSVD<Eigen::MatrixXd>;
template class Eigen::JacobiSVD<bhgrasp::FingerJacobian>;
template class Eigen::PartialPivLU<Eigen::MatrixXd>;
template class Eigen::LLT<Eigen::MatrixXd>;
template Eigen::LLT<Eigen::MatrixXd>& Eigen::LLT<Eigen::MatrixXd>::compute<Eigen::MatrixXd>(
    const Eigen::EigenBase<Eigen::MatrixXd>&);
