// The BH8-280's four motors, TorqueSwitch and self-locking worm drives for the compiled batch
// (bhgrasp/sim/actuation.py: BarrettActuation, the readable twin; bhgrasp/barrett/transmission.py explains the
// model).  Per finger the mode is 0 coupled (armed), 1 broken away (the motor drives the distal joint alone), 2
// re-opening the proximal link; then per finger 1 if its worm drive is locked (its column leaves the transmission).
// tests/test_batch.py steps a batch of Barrett hands against separate Simulator runs (the Python actuation) bit for
// bit.  The Barrett struct (the drive's parameters) is declared in options.hpp.
#pragma once

#include <array>

#include "engine.hpp"

namespace bhgrasp {

using Modes = std::array<int, 6>;  // TorqueSwitch mode of F1, F2, F3, then their worm locks (0 or 1)
using MotorInputs = Eigen::Vector4d;  // spread, F1, F2, F3 motor torques [N m]

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
