// Batched rollouts: see batch.hpp.
#include "batch.hpp"

#include <algorithm>
#include <stdexcept>

namespace bhgrasp {

Batch::Batch(const std::string& model, const std::string& geometry, const Settings& settings, int size)
    : nv_hand_(settings.nv_hand) {
  if (size < 1) throw std::invalid_argument("a batch needs at least one environment");
  for (int i = 0; i < size; ++i) engines_.push_back(std::make_unique<Engine>(model, geometry, settings));
  memories_.resize(static_cast<std::size_t>(size));
  modes_.assign(static_cast<std::size_t>(size), Modes{{0, 0, 0, 0, 0, 0}});
  contacts_.resize(static_cast<std::size_t>(size));
  divergences_.resize(static_cast<std::size_t>(size));
  for (auto& memory : memories_) memory = Memory{Indices(0), Points(0, 3), Points(0, 3), Flags(0)};
  q_ = Rows::Zero(size, engines_[0]->nq());
  v_ = Rows::Zero(size, engines_[0]->nv());
}

void Batch::set_state(int env, const Vector& q, const Vector& v, const Memory& memory) {
  if (env < 0 || env >= size()) throw std::out_of_range("no such environment");
  if (q.size() != q_.cols() || v.size() != v_.cols()) throw std::invalid_argument("q or v of the wrong size");
  q_.row(env) = q.transpose();
  v_.row(env) = v.transpose();
  memories_[static_cast<std::size_t>(env)] = memory;
  contacts_[static_cast<std::size_t>(env)] = Contacts{};
  contacts_[static_cast<std::size_t>(env)].resize(0);
  divergences_[static_cast<std::size_t>(env)] = Divergence{};
}

Batch::~Batch() {
  if (pool_ && !pool_->owned_here()) static_cast<void>(pool_.release());  // a fork's copy: its threads are not here
}

void Batch::parallel_for(int n, int threads, const std::function<void(int)>& body) {
  std::lock_guard<std::mutex> lock(calls_);
  threads = std::max(1, std::min(threads, n));
  if (threads == 1) {
    for (int i = 0; i < n; ++i) body(i);
    return;
  }
  if (pool_ && !pool_->owned_here()) static_cast<void>(pool_.release());  // a fork's copy: let it go, make ours
  if (!pool_ || pool_->threads() != threads) {
    pool_.reset();
    pool_ = std::make_unique<WorkerPool>(threads);
  }
  pool_->run(n, body);
}

void Batch::advance(int env, const Vector& input, bool barrett, const Drive& drive, double max_speed,
                    double max_penetration) {
  const auto e = static_cast<std::size_t>(env);
  if (divergences_[e].kind) return;  // frozen where it diverged
  static const Vector none;
  StepResult result =
      barrett ? barrett_->step(*engines_[e], q_.row(env).transpose(), v_.row(env).transpose(), input, none, modes_[e],
                               memories_[e], max_speed, max_penetration)
              : engines_[e]->step(q_.row(env).transpose(), v_.row(env).transpose(), input, drive, memories_[e],
                                  max_speed, max_penetration);
  divergences_[e] = result.divergence;
  if (result.divergence.kind) return;
  q_.row(env) = result.q.transpose();
  v_.row(env) = result.v.transpose();
  memories_[e] = std::move(result.memory);
  contacts_[e] = std::move(result.contacts);
}

void Batch::step(const Rows& tau_hand, const Drive& drive, double max_speed, double max_penetration, int threads) {
  if (tau_hand.rows() != size() || tau_hand.cols() != nv_hand_)
    throw std::invalid_argument("tau_hand must be (environments, nv_hand)");
  parallel_for(size(), threads, [&](int i) {
    advance(i, tau_hand.row(i).transpose(), false, drive, max_speed, max_penetration);
  });
}

void Batch::rollout(const Rows& inputs, int steps, bool barrett, const Drive& drive, double max_speed,
                    double max_penetration, int threads, bool record, Rows& q_record, Rows& v_record) {
  if (barrett && !barrett_) throw std::logic_error("no Barrett model: call set_barrett first");
  if (steps < 1) throw std::invalid_argument("a rollout needs at least one step");
  const Eigen::Index n = barrett ? 4 : nv_hand_;
  if (inputs.rows() != size() || (inputs.cols() != n && inputs.cols() != steps * n))
    throw std::invalid_argument("inputs must be (environments, inputs) or (environments, steps * inputs)");
  const bool held = inputs.cols() == n && steps > 1;
  const Eigen::Index nq = q_.cols(), nv = v_.cols();
  if (record) {
    q_record.resize(size(), steps * nq);
    v_record.resize(size(), steps * nv);
  } else {
    q_record.resize(0, 0);
    v_record.resize(0, 0);
  }
  parallel_for(size(), threads, [&](int i) {
    Vector input(n);
    for (int k = 0; k < steps; ++k) {
      input = inputs.row(i).segment(held ? 0 : k * n, n).transpose();
      advance(i, input, barrett, drive, max_speed, max_penetration);
      if (record) {
        q_record.row(i).segment(k * nq, nq) = q_.row(i);
        v_record.row(i).segment(k * nv, nv) = v_.row(i);
      }
    }
  });
}

void Batch::set_barrett(const Barrett& barrett) {
  if (barrett.nv_hand != nv_hand_) throw std::invalid_argument("the Barrett model does not fit the scene's hand");
  if (!barrett.direct.empty()) throw std::invalid_argument("a batch runs the Barrett hand's four motors alone");
  barrett_ = std::make_unique<BarrettDrive>(barrett);
}

void Batch::set_modes(int env, const Modes& modes) {
  if (env < 0 || env >= size()) throw std::out_of_range("no such environment");
  for (int k = 0; k < 6; ++k)
    if (modes[k] < 0 || modes[k] > (k < 3 ? 2 : 1))
      throw std::invalid_argument("a TorqueSwitch mode is 0, 1 or 2 and a worm lock 0 or 1");
  modes_[static_cast<std::size_t>(env)] = modes;
}

void Batch::step_barrett(const Rows& u, double max_speed, double max_penetration, int threads) {
  if (!barrett_) throw std::logic_error("no Barrett model: call set_barrett first");
  if (u.rows() != size() || u.cols() != 4) throw std::invalid_argument("u must be (environments, 4) motor torques");
  const Drive unused;
  parallel_for(size(), threads,
               [&](int i) { advance(i, u.row(i).transpose(), true, unused, max_speed, max_penetration); });
}

Rows Batch::gravity(int threads) {
  Rows result(size(), nv_hand_);
  parallel_for(size(), threads, [&](int i) {
    result.row(i) = engines_[static_cast<std::size_t>(i)]->gravity(q_.row(i).transpose()).transpose();
  });
  return result;
}

Rows Batch::frame_jacobians(const std::vector<int>& frames, int threads) {
  const auto n = static_cast<Eigen::Index>(frames.size());
  Rows result(size(), 3 * n * nv_hand_);
  parallel_for(size(), threads, [&](int i) {
    const Matrix jacobians = engines_[static_cast<std::size_t>(i)]->frame_jacobians(q_.row(i).transpose(), frames);
    Eigen::Map<Rows>(result.row(i).data(), 3 * n, nv_hand_) = jacobians;  // (3 n, nv_hand) row-major per env
  });
  return result;
}

}  // namespace bhgrasp
