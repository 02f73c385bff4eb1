// A controller closed on the compiled step: see closed_loop.hpp.
#include "closed_loop.hpp"

#include <cmath>
#include <initializer_list>
#include <stdexcept>
#include <vector>
#include <utility>

#include "recording.hpp"

namespace bhgrasp {

SMCGraspLoop::SMCGraspLoop(SMCAdaptiveLaw& law, const PosePath& path, Indices finger_of_pair, Indices joint_of_pair,
                           Eigen::Index nq_hand, Eigen::Index nv_hand, Eigen::Index object_q, Eigen::Index object_v,
                           double last_time)
    : law_(law),
      path_(path),
      finger_of_pair_(std::move(finger_of_pair)),
      joint_of_pair_(std::move(joint_of_pair)),
      nq_hand_(nq_hand),
      nv_hand_(nv_hand),
      object_q_(object_q),
      object_v_(object_v),
      last_time_(last_time) {
  if (nq_hand < 0 || nv_hand < 0 || object_q < 0 || object_v < 0)
    throw std::invalid_argument("SMCGraspLoop: the hand's sizes and the object's offsets must be >= 0");
}

int SMCGraspLoop::control(double t, const Vector& q, const Vector& v, const Contacts& contacts, Eigen::Ref<Vector> u,
                          Eigen::Ref<Vector> log) {
  if (object_q_ + 7 > q.size() || object_v_ + 6 > v.size() || nq_hand_ > q.size() || nv_hand_ > v.size())
    throw std::invalid_argument("SMCGraspLoop: the scene's q and v are shorter than the hand and object in them");
  if (law_.sense_contacts(contacts, finger_of_pair_, joint_of_pair_) < 2) return -1;
  const double dt = t - last_time_;  // (the twin's check of a clock going back cannot fail: the loop's t grows)
  last_time_ = t;
  const int status = law_.grasp_free_body_on_path(q.head(nq_hand_), v.head(nv_hand_), q.segment<7>(object_q_),
                                                  v.segment<6>(object_v_), dt, path_, t, log);
  if (status == 0) u = log.head(nv_hand_);
  return status;
}

ApproachLoop::ApproachLoop(HandDynamics& dynamics, const Eigen::Vector3d& gravity, Vector times, RowMatrix reference,
                           Vector kp, Vector kv, double damping, Indices finger_of_pair, Indices grasping,
                           Vector arrived, double contact_force, double last_time)
    : dynamics_(dynamics),
      gravity_(gravity),
      times_(std::move(times)),
      reference_(std::move(reference)),
      kp_(std::move(kp)),
      kv_(std::move(kv)),
      damping_(damping),
      finger_of_pair_(std::move(finger_of_pair)),
      grasping_(std::move(grasping)),
      arrived_(std::move(arrived)),
      contact_force_(contact_force),
      last_time_(last_time) {
  const Eigen::Index nv = kp_.size();
  if (nv != dynamics.nv() || nv != dynamics.nq() || kv_.size() != nv || reference_.cols() != 3 * nv ||
      times_.size() != reference_.rows())
    throw std::invalid_argument("ApproachLoop: kp, kv of nv and a reference of 3 nv columns at each time (nq == nv)");
  for (Eigen::Index i = 0; i < grasping_.size(); ++i)
    if (grasping_(i) < 0 || grasping_(i) >= arrived_.size())
      throw std::invalid_argument("ApproachLoop: a grasping finger beyond the fingers' flags");
  for (Eigen::Index i = 0; i < finger_of_pair_.size(); ++i)
    if (finger_of_pair_(i) < -1 || finger_of_pair_(i) >= arrived_.size())
      throw std::invalid_argument("ApproachLoop: a pair's finger beyond the fingers' flags");
  acceleration_.resize(nv);
}

int ApproachLoop::control(double t, const Vector& q, const Vector& v, const Contacts& contacts, Eigen::Ref<Vector> u,
                          Eigen::Ref<Vector> log) {
  const Eigen::Index nv = kp_.size(), fingers = arrived_.size();
  if (q.size() < nv || v.size() < nv) throw std::invalid_argument("ApproachLoop: q and v shorter than the hand's");
  const Eigen::Index rows = contacts.size();
  row_finger_.resize(rows);
  for (Eigen::Index row = 0; row < rows; ++row) {
    const std::int64_t pair = contacts.pair[row];
    if (pair < 0 || pair >= finger_of_pair_.size()) throw std::invalid_argument("a contact's pair is not the scene's");
    row_finger_[row] = finger_of_pair_[pair];
  }
  finger_contacts_into(row_finger_, fingers, contacts.point, contacts.normal, contacts.force, sums_, work_);
  for (Eigen::Index f = 0; f < fingers; ++f)
    if (sums_.count(f) > 0 && sums_.normal_force(f) >= contact_force_) arrived_(f) = 1.0;
  bool all = true;
  for (Eigen::Index i = 0; i < grasping_.size(); ++i) all = all && arrived_(grasping_(i)) != 0.0;
  if (all || cycle_ >= reference_.rows() || times_(cycle_) != t) return -1;
  const auto q_d = reference_.row(cycle_).segment(0, nv).transpose();
  const auto v_d = reference_.row(cycle_).segment(nv, nv).transpose();
  const auto a_d = reference_.row(cycle_).segment(2 * nv, nv).transpose();
  const auto q_hand = q.head(nv), v_hand = v.head(nv);
  // a_d - Kv @ (v - v_d) - Kp @ (q - q_d) with diagonal gains: NumPy's product sums one term and zeros from +0, so
  // each row is the term, a -0 made +0 (x + 0.0)
  acceleration_ = (a_d.array() - (kv_.cwiseProduct(v_hand - v_d).array() + 0.0)) -
                  (kp_.cwiseProduct(q_hand - q_d).array() + 0.0);
  const Eigen::VectorXd& torque = dynamics_.inverse_dynamics(gravity_, q_hand, v_hand, acceleration_);
  if (!torque.allFinite()) return -1;
  last_time_ = t;
  u = torque + damping_ * v_hand;
  log.segment(0, nv) = q_d;
  log.segment(nv, nv) = q_hand - q_d;
  log.segment(2 * nv, fingers) = arrived_;
  ++cycle_;
  return 0;
}

LoopRun run_closed_loop(Engine& engine, LoopController& controller, const Drive& drive, const Vector& q,
                        const Vector& v, const Contacts& contacts, const Memory& memory, double t, double dt,
                        Eigen::Index steps, double until, const Vector& limit, double max_speed,
                        double max_penetration) {
  const Eigen::Index inputs = controller.inputs();
  if (steps < 0 || !(dt > 0.0) || (limit.size() != 0 && limit.size() != inputs))
    throw std::invalid_argument("run_closed_loop: steps >= 0, dt > 0 and a limit per input (or none)");
  LoopRun run;
  run.t.resize(steps);
  run.q.resize(steps, q.size());
  run.v.resize(steps, v.size());
  run.u.resize(steps, inputs);
  run.drive.resize(steps, inputs);
  run.log.resize(steps + 1, controller.log_size());  // one more: the row of a cycle that stopped the loop
  std::vector<Contacts> kept;  // the contacts of each state after a step but the last
  kept.reserve(static_cast<std::size_t>(steps));
  const Vector *state_q = &q, *state_v = &v;
  const Contacts* state_contacts = &contacts;
  const Memory* state_memory = &memory;
  StepResult current;
  Vector u(inputs), tau(inputs);
  Eigen::Index k = 0;
  for (; k < steps && t < until; ++k) {
    const int status = controller.control(t, *state_q, *state_v, *state_contacts, u, run.log.row(k).transpose());
    if (status != 0) {
      run.stop = 1;
      run.status = status;
      break;
    }
    if (limit.size() != 0) {
      for (Eigen::Index i = 0; i < inputs; ++i) {  // np.clip(u, -limit, limit) for finite u, its signs of zero too
        const double low = -limit(i), high = limit(i), above = u(i) > low ? u(i) : low;
        tau(i) = above < high ? above : high;
      }
    } else {
      tau = u;
    }
    StepResult result = engine.step(*state_q, *state_v, tau, drive, *state_memory, max_speed, max_penetration);
    t = std::nearbyint(t / dt + 1.0) * dt;  // Simulator.step's clock: k dt exactly
    if (result.divergence.kind != 0) {
      run.stop = 2;
      run.diverged_at = t;
      current = std::move(result);
      break;
    }
    run.t(k) = t;
    run.q.row(k) = result.q.transpose();
    run.v.row(k) = result.v.transpose();
    run.u.row(k) = u.transpose();
    run.drive.row(k) = result.drive.transpose();
    if (k > 0) kept.push_back(std::move(current.contacts));  // the state before this step: sample k's
    current = std::move(result);
    state_q = &current.q;
    state_v = &current.v;
    state_contacts = &current.contacts;
    state_memory = &current.memory;
  }
  run.steps = k;
  run.last = std::move(current);
  run.t.conservativeResize(k);
  for (RowMatrix* rows : {&run.q, &run.v, &run.u, &run.drive}) rows->conservativeResize(k, Eigen::NoChange);
  run.log.conservativeResize(run.stop == 0 ? k : k + 1, Eigen::NoChange);
  std::vector<const Contacts*> parts;
  parts.reserve(kept.size());
  run.counts.resize(static_cast<Eigen::Index>(kept.size()));
  for (std::size_t i = 0; i < kept.size(); ++i) {
    parts.push_back(&kept[i]);
    run.counts(static_cast<Eigen::Index>(i)) = kept[i].size();
  }
  run.contacts = concatenate(parts);
  return run;
}

}  // namespace bhgrasp
