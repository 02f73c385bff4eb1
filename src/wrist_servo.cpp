#include "wrist_servo.hpp"
#include "model_io.hpp"

#include <cmath>
#include <stdexcept>

#include <Eigen/LU>

#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/math/rpy.hpp>
#include <pinocchio/spatial/explog.hpp>

namespace bhgrasp {

namespace {

// E (3, 3) with omega = E (yaw_dot, pitch_dot, roll_dot) (bhgrasp.model.mount.angular_map).
Eigen::Matrix3d angular_map(double yaw, double pitch) {
  Eigen::Matrix3d map;
  map.col(0) << 0.0, 0.0, 1.0;
  map.col(1) << -std::sin(yaw), std::cos(yaw), 0.0;
  map.col(2) << std::cos(yaw) * std::cos(pitch), std::sin(yaw) * std::cos(pitch), -std::sin(pitch);
  return map;
}

// dE/dt along the angle rates (bhgrasp.model.mount.angular_map_rate).
Eigen::Matrix3d angular_map_rate(double yaw, double pitch, double yaw_dot, double pitch_dot) {
  const double sy = std::sin(yaw), cy = std::cos(yaw), sp = std::sin(pitch), cp = std::cos(pitch);
  Eigen::Matrix3d rate;
  rate.col(0).setZero();
  rate.col(1) << -cy * yaw_dot, -sy * yaw_dot, 0.0;
  rate.col(2) << -sy * cp * yaw_dot - cy * sp * pitch_dot, cy * cp * yaw_dot - sy * sp * pitch_dot, -cp * pitch_dot;
  return rate;
}

}  // namespace

WristServo::WristServo(const std::string& model, const Eigen::Vector3d& gravity, std::vector<PoseMove> moves,
                       const Eigen::Matrix3d& origin_rotation, const Eigen::Vector3d& origin_translation,
                       const Vector6& kp, const Vector6& kd, bool hold_fingers, double finger_kp, double finger_kd)
    : path_(std::move(moves)),
      origin_rotation_(origin_rotation),
      origin_translation_(origin_translation),
      kp_(kp),
      kd_(kd),
      hold_fingers_(hold_fingers),
      finger_kp_(finger_kp),
      finger_kd_(finger_kd) {
  model_ = model_from_text(model);
  model_.gravity.linear(gravity);
  data_ = pinocchio::Data(model_);
  if (model_.nv < 6 || model_.nq != model_.nv) throw std::invalid_argument("the mounted hand needs six mount joints");
  acceleration_ = Eigen::VectorXd::Zero(model_.nv);
  tau_ = Eigen::VectorXd::Zero(model_.nv);
  hold_ = Eigen::VectorXd::Zero(model_.nq - 6);
}

void WristServo::pose(double t, Vector6& sample, Vector6& twist, Vector6& derivative) const {
  Eigen::Matrix3d rotation;
  Eigen::Vector3d position;
  path_.at(t, rotation, position, twist, derivative);
  sample.head<3>() = position;
  sample.tail<3>() = pinocchio::log3(rotation);
}

void WristServo::reference(double t, double held, Vector6& c, Vector6& c_dot, Vector6& c_dd) const {
  Vector6 sample, twist, derivative;
  if (std::isnan(held) || t < held) {  // HeldReference
    pose(t, sample, twist, derivative);
  } else {
    pose(held, sample, twist, derivative);
    twist.setZero();
    derivative.setZero();
  }
  const Eigen::Matrix3d rotation_t = origin_rotation_.transpose();  // MountReference
  const Eigen::Matrix3d local = rotation_t * pinocchio::exp3(Eigen::Vector3d(sample.tail<3>()));
  const Eigen::Vector3d position = rotation_t * (sample.head<3>() - origin_translation_);
  const Eigen::Vector3d rpy = pinocchio::rpy::matrixToRpy(local);  // (roll, pitch, yaw)
  c << position, rpy[2], rpy[1], rpy[0];
  const Eigen::Matrix3d map = angular_map(c[3], c[4]);
  const Eigen::PartialPivLU<Eigen::Matrix3d> lu(map);
  c_dot.head<3>() = rotation_t * twist.head<3>();
  c_dot.tail<3>() = lu.solve(Eigen::Vector3d(rotation_t * twist.tail<3>()));
  const Eigen::Vector3d spin =
      rotation_t * derivative.tail<3>() - angular_map_rate(c[3], c[4], c_dot[3], c_dot[4]) * c_dot.tail<3>();
  c_dd.head<3>() = rotation_t * derivative.head<3>();
  c_dd.tail<3>() = lu.solve(spin);
}

void WristServo::hold(const Eigen::VectorXd& fingers) {
  if (fingers.size() != hold_.size()) throw std::invalid_argument("the hold needs one value per finger joint");
  hold_ = fingers;
  holding_ = true;
}

const Eigen::VectorXd& WristServo::torques(double t, double held, const Eigen::Ref<const Eigen::VectorXd>& q,
                                           const Eigen::Ref<const Eigen::VectorXd>& v) {
  if (q.size() != model_.nq || v.size() != model_.nv) throw std::invalid_argument("q or v of the wrong size");
  reference(t, held, c_, c_dot_, c_dd_);
  acceleration_.head<6>() = c_dd_;
  const Eigen::VectorXd& model = pinocchio::rnea(model_, data_, q, v, acceleration_);
  const Eigen::Index fingers = model_.nv - 6;
  if (hold_fingers_) {
    if (!holding_) {
      hold_ = q.tail(fingers);
      holding_ = true;
    }
    tau_.tail(fingers) = model.tail(fingers) - (finger_kp_ * (q.tail(fingers) - hold_) + finger_kd_ * v.tail(fingers));
  } else {
    tau_.tail(fingers).setZero();
  }
  error_ = q.head<6>() - c_;
  tau_.head<6>() = model.head<6>() - kp_.cwiseProduct(error_) - kd_.cwiseProduct(v.head<6>() - c_dot_);
  return tau_;
}

}  // namespace bhgrasp
