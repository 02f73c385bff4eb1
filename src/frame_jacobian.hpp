// A frame's Jacobian (pinocchio::computeFrameJacobian) through the instantiation Pinocchio ships precompiled in
// libpinocchio_default, not one compiled again here: see frame_jacobian.cpp.
#pragma once

#include <Eigen/Core>

#include <pinocchio/multibody/fwd.hpp>

namespace bhgrasp {

// pinocchio::computeFrameJacobian(model, data, q, frame, reference, jacobian): the forward kinematics at q, then the
// (6, nv) Jacobian of `frame` in `reference` written into `jacobian` (zeroed by the caller, as Pinocchio asks).
void compute_frame_jacobian(const pinocchio::Model& model, pinocchio::Data& data, const Eigen::VectorXd& q,
                            pinocchio::FrameIndex frame, pinocchio::ReferenceFrame reference,
                            Eigen::Matrix<double, 6, Eigen::Dynamic>& jacobian);  // pinocchio::Data::Matrix6x

}  // namespace bhgrasp
