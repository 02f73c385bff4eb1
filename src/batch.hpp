// Batched rollouts: N copies of one scene stepped together by the compiled engine (bhgrasp.sim.batch).
//
// Each environment owns an Engine (its own Pinocchio and coal data) and its contact memory, so environments never
// share state; a step runs them on a few threads, each environment on one thread, with the same arithmetic as a
// single Engine::step (results do not depend on the thread count).  The threads are kept between calls (a fork()ed
// copy of a batch makes its own).  A rollout steps every environment through a sequence of inputs in one call, each
// environment's steps on one thread with no meeting between steps.  Environments whose step diverges are frozen and
// reported; the others go on.  Calls that step or evaluate run one at a time (a second thread's call waits).
#pragma once

#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "barrett.hpp"
#include "engine.hpp"
#include "worker_pool.hpp"

namespace bhgrasp {

using Rows = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

class Batch {
 public:
  Batch(const std::string& model, const std::string& geometry, const Settings& settings, int size);
  ~Batch();
  Batch(const Batch&) = delete;
  Batch& operator=(const Batch&) = delete;

  int size() const { return static_cast<int>(engines_.size()); }

  // Set environment env's state (scene q, v) and contact memory; clears its divergence.
  void set_state(int env, const Vector& q, const Vector& v, const Memory& memory);

  // One step of every environment that has not diverged: tau_hand (N, nv_hand) [N m].
  void step(const Rows& tau_hand, const Drive& drive, double max_speed, double max_penetration, int threads);

  // Barrett hands: the model (its 27 x 8 mode drives are built here), each environment's modes (TorqueSwitch, worm
  // locks), and one
  // step from motor inputs u (N, 4) [N m]: torques and drive in each environment's modes, then its mode update.
  void set_barrett(const Barrett& barrett);
  void set_modes(int env, const Modes& modes);
  const Modes& modes(int env) const { return modes_.at(static_cast<std::size_t>(env)); }
  void step_barrett(const Rows& u, double max_speed, double max_penetration, int threads);

  // Open-loop rollouts: `steps` steps of every environment that has not diverged, environment i's inputs of step k
  // in inputs.row(i).segment(k * n, n) (inputs (N, steps * n)) or held (inputs (N, n)); n = nv_hand torques (step's
  // drive) or 4 motor torques (Barrett, when barrett is true).  When record is true, q_record and v_record hold the
  // state after every step, (N, steps * nq) and (N, steps * nv); an environment that diverges repeats its last good
  // state.  The same arithmetic as `steps` calls of step or step_barrett.  An engine that throws (a drive of the wrong
  // size) leaves the environments at different steps.
  void rollout(const Rows& inputs, int steps, bool barrett, const Drive& drive, double max_speed,
               double max_penetration, int threads, bool record, Rows& q_record, Rows& v_record);

  const Rows& q() const { return q_; }  // (N, nq)
  const Rows& v() const { return v_; }  // (N, nv)
  const Memory& memory(int env) const { return memories_.at(static_cast<std::size_t>(env)); }
  const Contacts& contacts(int env) const { return contacts_.at(static_cast<std::size_t>(env)); }
  const Divergence& divergence(int env) const { return divergences_.at(static_cast<std::size_t>(env)); }

  // Kernels for vectorised controllers at the current states: hand gravity torques (N, nv_hand) [N m] and the
  // world-aligned translational Jacobians of frames, (N, 3 n_frames * nv_hand) row-major per environment.
  Rows gravity(int threads);
  Rows frame_jacobians(const std::vector<int>& frames, int threads);

 private:
  // One step of environment env from its inputs: joint torques through drive, or the Barrett motors' when barrett.
  void advance(int env, const Vector& input, bool barrett, const Drive& drive, double max_speed,
               double max_penetration);
  void parallel_for(int n, int threads, const std::function<void(int)>& body);  // on the kept threads

  std::vector<std::unique_ptr<Engine>> engines_;
  std::vector<Memory> memories_;
  std::vector<Contacts> contacts_;
  std::vector<Divergence> divergences_;
  Rows q_, v_;
  int nv_hand_ = 0;
  std::unique_ptr<BarrettDrive> barrett_;  // (null: no Barrett model)
  std::vector<Modes> modes_;
  std::unique_ptr<WorkerPool> pool_;  // (null until a call asks for more than one thread)
  std::mutex calls_;                  // one parallel_for at a time
};

}  // namespace bhgrasp
