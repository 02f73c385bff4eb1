#include "barrett.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace bhgrasp {

namespace {

// Finger f's motor-coordinate column (proximal, distal entries) in TorqueSwitch mode `mode` (BarrettTransmission.matrix).
std::array<double, 2> finger_column(const Barrett& barrett, int mode) {
  if (mode == 1) return {{0.0, 1.0}};
  if (mode == 2) return {{1.0, 0.0}};
  return {{1.0, barrett.proximal_ratio / barrett.distal_ratio}};
}

}  // namespace

Drive barrett_drive(const Barrett& barrett, const Modes& modes) {
  Drive drive;
  const auto direct = static_cast<Eigen::Index>(barrett.direct.size());
  drive.transmission = Matrix::Zero(barrett.nv_hand, 4 + direct);
  for (Eigen::Index k = 0; k < direct; ++k) drive.transmission(barrett.direct[static_cast<std::size_t>(k)], 4 + k) = 1.0;
  drive.transmission(barrett.spread_first, 0) = drive.transmission(barrett.spread_second, 0) = 1.0;
  Vector damping = barrett.damping;
  damping[barrett.spread_first] += barrett.motor_damping * (barrett.spread_ratio * barrett.spread_ratio);
  for (int finger = 0; finger < 3; ++finger) {
    const int proximal = barrett.proximal[finger], distal = barrett.distal[finger];
    if (modes[finger] == 1) {
      drive.transmission(distal, finger + 1) = 1.0;
      damping[distal] += barrett.efficiency * barrett.motor_damping * (barrett.distal_alone_ratio * barrett.distal_alone_ratio);
    } else {
      drive.transmission(proximal, finger + 1) = 1.0;
      if (modes[finger] == 0) drive.transmission(distal, finger + 1) = barrett.proximal_ratio / barrett.distal_ratio;
      damping[proximal] += barrett.efficiency * barrett.motor_damping * (barrett.proximal_ratio * barrett.proximal_ratio);
    }
  }
  std::vector<Eigen::Index> kept{0};  // locked fingers' columns leave T: their joints hold
  for (int finger = 0; finger < 3; ++finger)
    if (!modes[static_cast<std::size_t>(finger + 3)]) kept.push_back(finger + 1);
  for (Eigen::Index k = 0; k < direct; ++k) kept.push_back(4 + k);
  if (static_cast<Eigen::Index>(kept.size()) < 4 + direct) drive.transmission = Matrix(drive.transmission(Eigen::all, kept));
  drive.joint_damping = damping;
  drive.friction = barrett.friction;
  drive.motor_damping = damping - barrett.damping;
  return drive;
}

Vector barrett_torques(const Barrett& barrett, const Modes& modes, const MotorInputs& u) {
  Eigen::Vector4d clipped = u.head<4>();
  if (barrett.saturate)
    for (int k = 0; k < 4; ++k) clipped[k] = std::min(std::max(u[k], -barrett.max_motor_torque), barrett.max_motor_torque);
  Vector tau = Vector::Zero(barrett.nv_hand);
  for (std::size_t k = 0; k < barrett.direct.size(); ++k) tau[barrett.direct[k]] = u[4 + static_cast<Eigen::Index>(k)];
  tau[barrett.spread_first] = barrett.spread_ratio * clipped[0];  // the coupled F2 spread shares the column
  for (int finger = 0; finger < 3; ++finger) {
    if (modes[finger] == 1)
      tau[barrett.distal[finger]] = barrett.efficiency * barrett.distal_alone_ratio * clipped[finger + 1];
    else
      tau[barrett.proximal[finger]] = barrett.efficiency * barrett.proximal_ratio * clipped[finger + 1];
  }
  return tau;
}

void barrett_update(const Barrett& barrett, Modes& modes, const Vector& q_hand, const Vector& v_hand,
                    const MotorInputs& u, const Vector& drive_torques, const Vector& load) {
  const Modes before = modes;
  for (int finger = 0; finger < 3; ++finger) {
    const double motor = u[finger + 1];
    const int proximal = barrett.proximal[finger], distal = barrett.distal[finger];
    const bool proximal_at_stop = q_hand[proximal] <= barrett.lower[proximal] + 1e-4;
    const bool distal_at_stop = q_hand[distal] <= barrett.lower[distal] + 1e-4;
    int& mode = modes[static_cast<std::size_t>(finger)];
    if (mode == 0) {
      if (motor > 0.0 && load[proximal] > barrett.breakaway_torque) mode = 1;
    } else if (mode == 1 && motor < 0.0 && distal_at_stop) {
      mode = 2;
    } else if (mode == 2 && (proximal_at_stop || motor > 0.0)) {
      mode = 0;
    }
  }
  if (!barrett.self_locking) {  // no worm holds after a step (BarrettTransmission.locks), whatever a state brought
    modes[3] = modes[4] = modes[5] = 0;
    return;
  }
  const Vector torques = barrett_torques(barrett, modes, u);  // the pucks' torques through the gears
  for (int finger = 0; finger < 3; ++finger) {
    const auto f = static_cast<std::size_t>(finger);
    const double motor = u[finger + 1];
    const int proximal = barrett.proximal[f], distal = barrett.distal[f];
    const std::array<double, 2> c = finger_column(barrett, modes[f]);
    int& locked = modes[f + 3];
    if (modes[f] != before[f]) locked = 0;  // a new coordinate starts unlocked
    if (motor == 0.0) {
      locked = 1;
    } else if (locked) {
      const double given = c[0] * torques[proximal] + c[1] * torques[distal];
      const double held = c[0] * drive_torques[proximal] + c[1] * drive_torques[distal];
      locked = (motor > 0.0 ? 1.0 : -1.0) * (given - held) <= 0.0;
    } else {
      const double speed = (c[0] * v_hand[proximal] + c[1] * v_hand[distal]) / (c[0] * c[0] + c[1] * c[1]);
      locked = motor * speed < 0.0;
    }
  }
}

BarrettDrive::BarrettDrive(const Barrett& barrett) : barrett_(barrett) {
  const int nv = barrett.nv_hand;
  if (barrett.damping.size() != nv || barrett.friction.size() != nv || barrett.lower.size() != nv)
    throw std::invalid_argument("the Barrett model's damping, friction and lower limits need one value per hand joint");
  std::vector<int> joints{barrett.spread_first, barrett.spread_second};
  for (int finger = 0; finger < 3; ++finger) {
    joints.push_back(barrett.proximal[static_cast<std::size_t>(finger)]);
    joints.push_back(barrett.distal[static_cast<std::size_t>(finger)]);
  }
  joints.insert(joints.end(), barrett.direct.begin(), barrett.direct.end());
  for (const int joint : joints)
    if (joint < 0 || joint >= nv) throw std::invalid_argument("a Barrett joint index is outside the hand's joints");
  drives_.reserve(27 * 8);
  for (int code = 0; code < 27 * 8; ++code) {  // TorqueSwitch code 9 m0 + 3 m1 + m2, then 27 x the lock bits
    const int s = code % 27, l = code / 27;
    drives_.push_back(barrett_drive(barrett_, {{s / 9, s / 3 % 3, s % 3, l / 4, l / 2 % 2, l % 2}}));
  }
}

StepResult BarrettDrive::step(Engine& engine, const Vector& q, const Vector& v, const MotorInputs& u,
                              const Vector& extra, Modes& modes, const Memory& memory, double max_speed,
                              double max_penetration) const {
  if (u.size() != inputs()) throw std::invalid_argument("u must hold the four motor torques and one per direct joint");
  for (std::size_t k = 0; k < 6; ++k)
    if (modes[k] < 0 || modes[k] > (k < 3 ? 2 : 1))
      throw std::invalid_argument("a TorqueSwitch mode is 0, 1 or 2 and a worm lock 0 or 1");
  if (barrett_.self_locking) {  // an idle motor's worm holds for the step (BarrettActuation.begin)
    for (std::size_t finger = 0; finger < 3; ++finger)
      if (u[static_cast<Eigen::Index>(finger) + 1] == 0.0) modes[finger + 3] = 1;
  } else {  // no worm holds: a state's locks mean nothing here (BarrettActuation.restore)
    modes[3] = modes[4] = modes[5] = 0;
  }
  const int code = 9 * modes[0] + 3 * modes[1] + modes[2] + 27 * (4 * modes[3] + 2 * modes[4] + modes[5]);
  Vector tau = barrett_torques(barrett_, modes, u);
  if (extra.size() > tau.size()) {  // generalized forces on the objects too: the hand's torques added to theirs
    Vector forces = extra;
    forces.head(tau.size()) += tau;
    tau = std::move(forces);
  } else if (extra.size() == tau.size()) {
    tau += extra;
  } else if (extra.size() != 0) {
    throw std::invalid_argument("extra torques must be empty, nv_hand joint torques or nv generalized forces");
  }
  StepResult result = engine.step(q, v, tau, drives_[static_cast<std::size_t>(code)], memory, max_speed, max_penetration);
  if (!result.divergence.kind)
    barrett_update(barrett_, modes, result.q.head(barrett_.nv_hand), result.v.head(barrett_.nv_hand), u, result.drive,
                   result.load);
  return result;
}

}  // namespace bhgrasp
