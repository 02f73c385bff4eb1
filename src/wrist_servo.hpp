// The wrist servo of a mounted hand on a pose path (bhgrasp/controllers/mount.py: MountServo, the readable twin, with
// bhgrasp/motion/pose_references.py: PosePath, bhgrasp/motion/held.py: HeldReference and bhgrasp/motion/wrist.py:
// MountReference).  One call: the path's pose sample at t (back-to-back minimum-jerk moves by world offsets, or where
// it was held), its mount coordinates c = (x, y, z, yaw, pitch, roll) with their rates and accelerations, and the
// servo's torques tau_m = [ID(q, v, a_ref)]_m + kp (c_d - c) + kd (c_dot_d - c_dot) on the mount's rows, the fingers'
// rows zero (another input drives them) or the fingers held where the first call found them (a joint PD on the same
// inverse dynamics).  tests/test_wrist_servo.py holds it to the Python twin to round-off.  Units SI, radians.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include <pinocchio/multibody.hpp>

#include "pose_path.hpp"

namespace bhgrasp {

class WristServo {
 public:
  // `model`: the mounted hand (Model.saveToString), its first six joints the mount's; `moves` in time order;
  // `origin`: the mount's origin in the world; gains per mount coordinate; `hold_fingers`: the finger rows hold the
  // first call's configuration with (finger_kp, finger_kd), else they are zero.  std::invalid_argument on bad sizes.
  WristServo(const std::string& model, const Eigen::Vector3d& gravity, std::vector<PoseMove> moves,
             const Eigen::Matrix3d& origin_rotation, const Eigen::Vector3d& origin_translation, const Vector6& kp,
             const Vector6& kd, bool hold_fingers, double finger_kp, double finger_kd);

  // The joint torques at time t [s] for the sensed (q, v); `held` [s]: the path stops there from then on (NaN: it
  // is followed).  The result, the reference c_d and the error c - c_d live here until the next call.
  const Eigen::VectorXd& torques(double t, double held, const Eigen::Ref<const Eigen::VectorXd>& q,
                                 const Eigen::Ref<const Eigen::VectorXd>& v);

  // The mount coordinates, their rates and accelerations of the path at t [s] (the reference of `torques`).
  void reference(double t, double held, Vector6& c, Vector6& c_dot, Vector6& c_dd) const;

  void reset() { holding_ = false; }  // the next call takes the fingers' hold
  void hold(const Eigen::VectorXd& fingers);  // hold the fingers there (a copy's hold); std::invalid_argument on size
  const Vector6& mount_reference() const { return c_; }
  const Vector6& mount_error() const { return error_; }
  int nq() const { return model_.nq; }
  int nv() const { return model_.nv; }

 private:
  void pose(double t, Vector6& sample, Vector6& twist, Vector6& derivative) const;

  pinocchio::Model model_;
  pinocchio::Data data_;
  PosePath path_;
  Eigen::Matrix3d origin_rotation_;
  Eigen::Vector3d origin_translation_;
  Vector6 kp_, kd_;
  bool hold_fingers_;
  double finger_kp_, finger_kd_;
  bool holding_ = false;
  Eigen::VectorXd hold_, acceleration_, tau_;
  Vector6 c_, c_dot_, c_dd_, error_;
};

}  // namespace bhgrasp
