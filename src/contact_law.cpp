// The contact force law: see engine.hpp.  Each function mirrors the Python function of the same name in
// bhgrasp/sim/contact_law.py (ContactForces: linear_parts, start_status, classify, forces); the comments there
// explain the physics.
#include <algorithm>
#include <cmath>

#include "engine.hpp"
#include "kernels.hpp"

namespace bhgrasp {

// ------------------------------------------------------------------ force law (sim/contact_law.py)
// The work arrays the implicit step passes here (parts, status, slide) hold at least m rows or entries (they only
// grow, engine.hpp: Work); these functions read and write their first m.
void Engine::linear_parts(const Contacts& contacts, Parts& parts) const {
  const ContactLaw& law = settings_.law;
  const double dt = settings_.dt;
  const Eigen::Index m = contacts.size();
  reserve_rows(parts.f0, m);
  reserve_rows(parts.f0_stick, m);
  parts.gains.resize(static_cast<std::size_t>(m));
  parts.gains_stick.resize(static_cast<std::size_t>(m));
  for (Eigen::Index i = 0; i < m; ++i) {
    const Vector3 normal = row(contacts.normal, i);
    const double depth = contacts.depth[i], weight = contacts.weight[i];
    const Matrix3 outer = normal * normal.transpose();
    double force, gain;
    if (!law.hunt_crossley) {
      force = weight * law.stiffness * depth;
      gain = weight * (law.stiffness * dt + law.damping);
    } else {
      const double power = std::pow(depth, law.exponent);
      force = weight * law.stiffness * power;
      gain = weight * (law.exponent * law.stiffness * std::pow(depth, law.exponent - 1.0) * dt + law.damping * power);
    }
    const auto s = static_cast<std::size_t>(i);
    parts.f0.row(i) = force * normal;
    parts.gains[s] = gain * outer;
    if (!law.tanh_friction) {
      parts.f0_stick.row(i) = parts.f0.row(i) - (weight * law.tangential_stiffness) * contacts.displacement.row(i);
      parts.gains_stick[s] = parts.gains[s] + (weight * (law.tangential_stiffness * dt + law.tangential_damping)) *
                                                  (Matrix3::Identity() - outer);
    } else {
      parts.f0_stick.row(i) = parts.f0.row(i);
      parts.gains_stick[s] = parts.gains[s];
    }
  }
}

void Engine::start_status(const Contacts& contacts, const Parts& parts, const Points& start_velocity,
                          std::vector<int>& status, Points& slide) const {
  const Eigen::Index m = contacts.size();
  status.assign(static_cast<std::size_t>(m), 1);
  slide.topRows(m).setZero();
  if (settings_.law.tanh_friction || !contacts.was_sliding.any()) return;
  for (Eigen::Index i = 0; i < m; ++i) {
    if (!contacts.was_sliding[i]) continue;
    const Vector3 normal = row(contacts.normal, i), velocity = row(start_velocity, i);
    const Vector3 predicted = row(parts.f0, i) - parts.gains[static_cast<std::size_t>(i)] * velocity;
    const double cone = contacts.friction[i] * std::max(predicted.dot(normal), 0.0);
    const Vector3 v_t = tangential(velocity, normal);
    const double speed = std::sqrt(v_t.squaredNorm());
    if (speed > 1e-6 && cone > 0.0) {
      status[static_cast<std::size_t>(i)] = 2;
      slide.row(i) = -v_t * (cone / speed);
    }
  }
}

void Engine::classify(const Contacts& contacts, const Points& forces, const std::vector<int>& status,
                      const Points& start_velocity, const Points& relative, const Flags& may_stick,
                      std::vector<int>& new_status,
                      Points& slide) const {
  const Eigen::Index m = contacts.size();
  new_status.assign(static_cast<std::size_t>(m), 0);
  slide.topRows(m).setZero();
  for (Eigen::Index i = 0; i < m; ++i) {
    const auto s = static_cast<std::size_t>(i);
    const Vector3 normal = row(contacts.normal, i), force = row(forces, i);
    const double normal_force = force.dot(normal);
    const Vector3 tangent = force - normal_force * normal;
    new_status[s] = normal_force > 0.0 ? status[s] : 0;
    const double cone = contacts.friction[i] * std::max(normal_force, 0.0);
    if (settings_.law.tanh_friction) {  // every contact "slides" with the force of its start-of-step slip
      const Vector3 v_t = tangential(row(start_velocity, i), normal);
      const double speed = v_t.norm();
      const double scale = speed > 0 ? std::tanh(speed / settings_.law.slip_velocity) / speed : 0.0;
      slide.row(i) = -(cone * scale) * v_t;
      if (new_status[s] == 1) new_status[s] = 2;
      continue;
    }
    const double magnitude = std::sqrt(tangent.squaredNorm());
    bool sliding = new_status[s] > 0 && (magnitude > cone * (1 + 1e-9) || status[s] == 2);
    const Vector3 v_t = tangential(row(relative, i), normal);
    if (may_stick[i] && status[s] == 2 && new_status[s] > 0 && tangent.dot(v_t) > 0.0) {
      new_status[s] = 1;  // the kinetic friction overshoots: it sticks
      sliding = false;
    }
    if (sliding) {
      new_status[s] = 2;
      slide.row(i) = tangent * (cone / std::max(magnitude, 1e-300));
    }
  }
}

// Explicit forces on body b at relative point velocities; returns end-of-step displacements
// (sim/contact_law.py: forces).
void Engine::contact_forces(Contacts& contacts, const Points& velocity, Points& displacement) const {
  const ContactLaw& law = settings_.law;
  const Eigen::Index m = contacts.size();
  displacement.setZero(m, 3);
  for (Eigen::Index i = 0; i < m; ++i) {
    const Vector3 normal = row(contacts.normal, i), relative = row(velocity, i);
    const double v_n = relative.dot(normal), weight = contacts.weight[i];
    const Vector3 v_t = relative - v_n * normal;
    const double depth_rate = -v_n;
    double f_n = !law.hunt_crossley ? weight * (law.stiffness * contacts.depth[i] + law.damping * depth_rate)
                                    : weight * std::pow(contacts.depth[i], law.exponent) *
                                          (law.stiffness + law.damping * depth_rate);
    f_n = std::max(f_n, 0.0);
    const double cone = contacts.friction[i] * f_n;
    Vector3 f_t;
    bool sticking;
    if (law.tanh_friction) {
      const double speed = v_t.norm();
      const Vector3 direction = speed > 0 ? Vector3(v_t / speed) : Vector3::Zero();
      f_t = -(cone * std::tanh(speed / law.slip_velocity)) * direction;
      sticking = speed < law.slip_velocity;
    } else {
      Vector3 u = row(contacts.displacement, i) + settings_.dt * v_t;
      f_t = -weight * (law.tangential_stiffness * u + law.tangential_damping * v_t);
      const double magnitude = f_t.norm();
      sticking = magnitude <= cone;  // project on the cone: the anchor of a sliding contact follows
      if (!sticking) {
        f_t = cone * (f_t / magnitude);
        u = -f_t / (weight * law.tangential_stiffness);
      }
      displacement.row(i) = u;
    }
    contacts.force.row(i) = f_n * normal + f_t;
    contacts.sticking[i] = sticking;
  }
}

}  // namespace bhgrasp
