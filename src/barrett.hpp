// The BH8-280's four motors, TorqueSwitch and self-locking worm drives for the compiled Simulator and batch
// (bhgrasp/sim/actuation.py: BarrettActuation, the readable twin; bhgrasp/barrett/transmission.py explains the
// model).  Per finger the mode is 0 coupled (armed), 1 broken away (the motor drives the distal joint alone), 2
// re-opening the proximal link; then per finger 1 if its worm drive is locked (its column leaves the transmission).
// tests/test_batch.py steps a batch of Barrett hands against separate Simulator runs bit for bit, and
// tests/test_compiled_drive.py a Simulator (a mounted hand too) against the Python actuation's rules.  The Barrett struct (the drive's parameters) is declared in options.hpp.
#pragma once

#include <array>
#include <vector>

#include "engine.hpp"

namespace bhgrasp {

using Modes = std::array<int, 6>;  // TorqueSwitch mode of F1, F2, F3, then their worm locks (0 or 1)
using MotorInputs = Vector;  // spread, F1, F2, F3 motor torques [N m], then one input per direct joint [N m, N]

// The transmission and damping in `modes` (BarrettActuation.transmission, joint_damping; drive_of in compiled.py).
Drive barrett_drive(const Barrett& barrett, const Modes& modes);

// Joint torques [N m] the motor inputs apply in `modes` (BarrettActuation.joint_torques).
Vector barrett_torques(const Barrett& barrett, const Modes& modes, const MotorInputs& u);

// After a step to (q_hand, v_hand) under inputs u with delivered drive torques and the links' load (the drive less
// their own inertia): the switches' next modes and the worm locks (BarrettActuation.update; BarrettTransmission.switch
// and locks).
void barrett_update(const Barrett& barrett, Modes& modes, const Vector& q_hand, const Vector& v_hand,
                    const MotorInputs& u, const Vector& drive_torques, const Vector& load);

// A hand's drive: its parameters and the drive of each of the 27 x 8 mode combinations, built once.
class BarrettDrive {
 public:
  explicit BarrettDrive(const Barrett& barrett);  // std::invalid_argument if its sizes do not agree

  const Barrett& barrett() const { return barrett_; }
  int inputs() const { return 4 + static_cast<int>(barrett_.direct.size()); }

  // One step of `engine` from (q, v) under inputs u (inputs()) and `extra` torques added to theirs (nv_hand joint
  // torques or nv generalized forces; empty: none), the drive in `modes`: an idle motor's worm locks for the step
  // (BarrettActuation.begin), the engine steps, and `modes` become the step's (BarrettActuation.update; not after a
  // step that diverged).
  StepResult step(Engine& engine, const Vector& q, const Vector& v, const MotorInputs& u, const Vector& extra,
                  Modes& modes, const Memory& memory, double max_speed, double max_penetration) const;

 private:
  Barrett barrett_;
  std::vector<Drive> drives_;  // by code 9 m0 + 3 m1 + m2 + 27 (4 l0 + 2 l1 + l2)
};

}  // namespace bhgrasp
