// A controller closed on the compiled step, many steps in one call: the loop of bhgrasp/sim/run_loop.py in its
// plainest case (sensors exact, one control cycle and one recorded sample per step, no disturbance, one torque per
// joint), which Simulator.run hands over while the controller offers a compiled loop controller.  Python keeps
// everything else: the cycles before the first it offers and a phase's switch (the loop stops before it), a cycle
// the loop controller declines, the recorder's assembly of the samples, the errors.  tests/test_closed_loop.py
// holds runs through it to the Python loop, bit for bit.  Units SI: [s], [m], [rad], [N], [N m]; the scene's
// coordinates as the engine's, gravity in the hand model's frame.  The loop runs with the GIL held: its controllers
// use kernels (a hand's HandDynamics) that other Python threads may call.
#pragma once

#include <Eigen/Core>

#include "engine.hpp"
#include "pose_path.hpp"
#include "smc_law.hpp"

namespace bhgrasp {

// What the loop asks of a controller each step.
class LoopController {
 public:
  virtual ~LoopController() = default;
  virtual Eigen::Index inputs() const = 0;    // the size of u
  virtual Eigen::Index log_size() const = 0;  // the size of its log row
  // The inputs u and the log row of the control cycle at t from the scene's (q, v) and the contacts that made it.
  // 0: written; otherwise the loop stops before this step and returns the code (< 0: the cycle is Python's to run,
  // nothing the cycle's Python call would not redo has changed; > 0: the cycle failed, its log row written as far
  // as it got).
  virtual int control(double t, const Vector& q, const Vector& v, const Contacts& contacts, Eigen::Ref<Vector> u,
                      Eigen::Ref<Vector> log) = 0;
};

// The SMC-adaptive law's grasp cycle toward a pose path, as CompiledSMCLaw.__call__ runs it for a simulated state
// with two fingers or more touching (bhgrasp/controllers/_smc_law.py): sense_contacts, the clock, then
// grasp_free_body_on_path; u is the log row's tau.  Fewer than two touching fingers: -1 (the approach branch is
// Python's).  A law status 1-4 is returned as it is.
class SMCGraspLoop : public LoopController {
 public:
  // `law` and `path` are kept by reference (the caller keeps them alive); the per-pair finger and joint maps of the
  // scene; the hand's coordinates first in the scene's q and v, the object's free body at `object_q` (position and
  // quaternion, 7) and `object_v` (6); `last_time` [s]: the law's last grasp cycle.
  SMCGraspLoop(SMCAdaptiveLaw& law, const PosePath& path, Indices finger_of_pair, Indices joint_of_pair,
               Eigen::Index nq_hand, Eigen::Index nv_hand, Eigen::Index object_q, Eigen::Index object_v,
               double last_time);

  Eigen::Index inputs() const override { return nv_hand_; }
  Eigen::Index log_size() const override { return law_.log_size(); }
  int control(double t, const Vector& q, const Vector& v, const Contacts& contacts, Eigen::Ref<Vector> u,
              Eigen::Ref<Vector> log) override;
  double last_time() const { return last_time_; }  // the law's clock: its last grasp cycle [s]

 private:
  SMCAdaptiveLaw& law_;
  const PosePath& path_;
  Indices finger_of_pair_, joint_of_pair_;
  Eigen::Index nq_hand_, nv_hand_, object_q_, object_v_;
  double last_time_;
};

// A GraspSupervisor's approach (bhgrasp/controllers/supervisor.py: __call__ in its approach phase, on the
// ComputedTorque of bhgrasp/controllers/joint.py): the fingers whose sensed normal force reaches `contact_force`
// (finger_contacts' sums, as ContactSensing.fingers) count as arrived; then the computed torque toward the next row
// of `reference` ((q_d, v_d, a_d) at each of `times`, sampled in Python), a_d - kv (v - v_d) - kp (q - q_d) through
// RNEA, plus `damping` v.  -1 (the cycle is Python's): every grasping finger has arrived (the supervisor switches),
// the table is used up or is not at t, or the torque is not finite (Python raises).  Log row: q_d (nv) | error
// q - q_d (nv) | arrived (F).
class ApproachLoop : public LoopController {
 public:
  // `dynamics`: the hand's (kept by reference, alive by the caller), `gravity` [m/s^2] in its model frame; `times`
  // [s] and `reference` rows (q_d [rad], v_d [rad/s], a_d [rad/s^2]); `kp`, `kv` the diagonals of the gains [1/s^2,
  // 1/s]; `damping` [N m s/rad]; `finger_of_pair` per collision pair of the scene (-1: no finger); `grasping` the
  // fingers that must arrive; `arrived` (F) the flags so far (1.0 arrived); `contact_force` [N]; `last_time` [s] the
  // law's last cycle; the hand's coordinates first in the scene's q and v (nq == nv).
  ApproachLoop(HandDynamics& dynamics, const Eigen::Vector3d& gravity, Vector times, RowMatrix reference, Vector kp,
               Vector kv, double damping, Indices finger_of_pair, Indices grasping, Vector arrived,
               double contact_force, double last_time);

  Eigen::Index inputs() const override { return kp_.size(); }
  Eigen::Index log_size() const override { return 2 * kp_.size() + arrived_.size(); }
  int control(double t, const Vector& q, const Vector& v, const Contacts& contacts, Eigen::Ref<Vector> u,
              Eigen::Ref<Vector> log) override;
  double last_time() const { return last_time_; }  // the computed torque's clock: its last cycle [s]

 private:
  HandDynamics& dynamics_;
  Eigen::Vector3d gravity_;
  Vector times_;
  RowMatrix reference_;
  Vector kp_, kv_;
  double damping_;
  Indices finger_of_pair_, grasping_;
  Vector arrived_;
  double contact_force_, last_time_;
  Eigen::Index cycle_ = 0;  // the reference's next row
  Indices row_finger_;
  FingerSums sums_;
  FingerWork work_;
  Vector acceleration_;
};

// What run_closed_loop did.  Row k of t, q, v, drive is the state after step k and the step's drive torques; row k
// of u and log the control cycle that step took.
struct LoopRun {
  Eigen::Index steps = 0;  // steps taken
  // 0: `steps` steps, or the next step's t reached `until`; 1: the controller returned `status` for the next step
  // (for a status > 0 the failed cycle's log row is log's row `steps`; < 0: that row holds nothing); 2: the next step
  // diverged (`last` is its result, at time `diverged_at`; its cycle's log row is log's row `steps`)
  int stop = 0;
  int status = 0;
  double diverged_at = 0.0;
  Vector t;
  RowMatrix q, v, u, drive, log;
  Contacts contacts;  // the contacts of the states after steps 0 .. steps - 2, one after the other (the last's: last)
  Indices counts;     // their rows per state
  StepResult last;    // the last step's result (the diverged one when stop == 2)
};

// Up to `steps` steps of `engine` from (q, v) at time t [s] with the contacts and memory that made them, under
// `drive`, each step's joint torques [N m] the controller's u (clipped to +-limit [N m] when `limit` is not empty);
// the clock advances as Simulator.step's (round(t / dt + 1) dt, dt [s]).  Stops early before a step whose t >= until
// [s], when the controller stops, or at a diverged step (speed above max_speed [m/s or rad/s], depth above
// max_penetration [m], or not finite).
LoopRun run_closed_loop(Engine& engine, LoopController& controller, const Drive& drive, const Vector& q,
                        const Vector& v, const Contacts& contacts, const Memory& memory, double t, double dt,
                        Eigen::Index steps, double until, const Vector& limit, double max_speed,
                        double max_penetration);

}  // namespace bhgrasp
