// The BH8-280's four motors, TorqueSwitch and self-locking worm drives for the compiled batch
// (bhgrasp/sim/actuation.py: BarrettActuation, the readable twin; bhgrasp/barrett/transmission.py explains the
// model).  Per finger the mode is 0 coupled (armed), 1 broken away (the motor drives the distal joint alone), 2
// re-opening the proximal link; then per finger 1 if its worm drive is locked (its column leaves the transmission).  tests/test_batch.py steps a batch
// of Barrett hands against separate Simulator runs (the Python actuation) bit for bit.
#pragma once

#include <array>

#include "engine.hpp"

namespace bhgrasp {

using Modes = std::array<int, 6>;  // TorqueSwitch mode of F1, F2, F3, then their worm locks (0 or 1)
using MotorInputs = Eigen::Vector4d;  // spread, F1, F2, F3 motor torques [N m]

struct Barrett {
  int nv_hand = 0;
  int spread_first = -1, spread_second = -1;  // hand joint indices of F1_spread, F2_spread
  std::array<int, 3> proximal{{-1, -1, -1}}, distal{{-1, -1, -1}};
  double spread_ratio = 0.0, proximal_ratio = 0.0, distal_ratio = 0.0, distal_alone_ratio = 0.0;  // motor : joint
  double max_motor_torque = 0.0;  // [N m], the clip when `saturate`
  double breakaway_torque = 0.0;  // [N m] proximal load torque that breaks the switch away
  double motor_damping = 0.0;     // [N m s/rad] at the motor shaft
  double efficiency = 1.0;        // forward efficiency of the finger worm drives
  bool saturate = false, self_locking = false;
  Vector damping, friction, lower;  // (nv_hand,) passive joint damping, Coulomb friction, lower joint limits
};

// The transmission and damping in `modes` (BarrettActuation.transmission, joint_damping; drive_of in compiled.py).
Drive barrett_drive(const Barrett& barrett, const Modes& modes);

// Joint torques [N m] the motor inputs apply in `modes` (BarrettActuation.joint_torques).
Vector barrett_torques(const Barrett& barrett, const Modes& modes, const MotorInputs& u);

// After a step to (q_hand, v_hand) under inputs u with delivered drive torques and the links' load (the drive less
// their own inertia): the switches' next modes and the worm locks (BarrettActuation.update; BarrettTransmission.switch
// and locks).
void barrett_update(const Barrett& barrett, Modes& modes, const Vector& q_hand, const Vector& v_hand,
                    const MotorInputs& u, const Vector& drive_torques, const Vector& load);

}  // namespace bhgrasp
