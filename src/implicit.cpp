// The implicit step: see engine.hpp.  It mirrors bhgrasp/sim/python_engine.py (PythonEngine._implicit, _drive) and
// the active-set helpers of bhgrasp/sim/contact_law.py; the comments there explain the linearisation.
#include <algorithm>
#include <cmath>

#include "engine.hpp"
#include "kernels.hpp"

namespace bhgrasp {

void Engine::implicit_step(const Vector& q, const Vector& v, const Vector& tau, const Drive& drive,
                           const Memory& memory, StepResult& result) {
  const double dt = settings_.dt;
  const int nv = model_.nv, nvh = settings_.nv_hand;
  // Every array but the result's lives in work_ (no allocation once sized); where an expression would evaluate a
  // product into a temporary, the product goes to a work array first, with the same arithmetic.
  Work& work = work_;
  Contacts contacts = detect(q, memory);
  parts_.compute_joint_jacobians(q);
  mass_matrix(q, work.mass);
  const Matrix& mass = work.mass;
  Vector& bias = work.bias;
  parts_.nonlinear_effects(q, v, bias);
  implicit_gyroscopic(v, bias);
  passive(q, v, drive, work.passive);
  const Passive& joint = work.passive;
  Vector& implicit_damping = work.implicit_damping;
  implicit_damping = dt * joint.stiffness + joint.damping;
  Matrix& matrix = work.matrix;
  matrix = mass;
  matrix.diagonal() += dt * implicit_damping;
  work.product.noalias() = mass * v;
  Vector& rhs = work.rhs;
  rhs = work.product + dt * (tau - bias + joint.torque);
  transmission(drive, work.transmission);
  const Matrix& full = work.transmission;
  const Eigen::Index m = contacts.size();
  Vector& v_next = work.v_next;
  Vector& contact_torque = work.contact_torque;
  contact_torque.setZero(nv);
  Points& displacement = result.memory.displacement;
  displacement.setZero(m, 3);
  std::vector<int>& status = work.status;  // its first m entries
  if (m == 0) {
    reduced_solve(full, matrix, rhs, v_next);
  } else {
    std::vector<Matrix>& jacobian = work.jacobian;
    jacobians(contacts, jacobian);
    Points &start_velocity = work.start_velocity, &relative = work.relative, &forces = work.forces;
    Points &slide = work.slide, &new_slide = work.new_slide, &f0 = work.f0;
    for (Points* array : {&start_velocity, &relative, &forces, &slide, &new_slide, &f0}) reserve_rows(*array, m);
    for (Eigen::Index i = 0; i < m; ++i) {
      work.velocity.noalias() = jacobian[static_cast<std::size_t>(i)] * v;
      start_velocity.row(i) = work.velocity;
    }
    linear_parts(contacts, work.parts);
    const Parts& parts = work.parts;
    start_status(contacts, parts, start_velocity, status, slide);
    Flags& may_stick = work.may_stick;
    reserve_rows(may_stick, m);
    for (Eigen::Index i = 0; i < m; ++i) may_stick[i] = status[static_cast<std::size_t>(i)] == 2;
    std::vector<int>& new_status = work.new_status;
    std::vector<Matrix3>& gains = work.gains;
    gains.resize(static_cast<std::size_t>(m));
    for (int pass = 0; pass < 8; ++pass) {
      // linearise: f(v+) = f0 - D J v+ in each contact's status
      Matrix& matrix_c = work.matrix_c;
      matrix_c = matrix;
      Vector& rhs_c = work.rhs_c;
      rhs_c = rhs;
      for (Eigen::Index i = 0; i < m; ++i) {
        const auto s = static_cast<std::size_t>(i);
        if (status[s] == 1) {
          f0.row(i) = parts.f0_stick.row(i);
          gains[s] = parts.gains_stick[s];
        } else if (status[s] == 2) {
          f0.row(i) = parts.f0.row(i) + slide.row(i);
          gains[s] = parts.gains[s];
        } else {
          f0.row(i).setZero();
          gains[s].setZero();
        }
        const Matrix& jac = jacobian[s];
        work.gain_jacobian.noalias() = gains[s] * jac;
        matrix_c.noalias() += dt * (jac.transpose() * work.gain_jacobian);
        rhs_c.noalias() += dt * (jac.transpose() * row(f0, i));
      }
      reduced_solve(full, matrix_c, rhs_c, v_next);
      for (Eigen::Index i = 0; i < m; ++i) {
        const auto s = static_cast<std::size_t>(i);
        work.velocity.noalias() = jacobian[s] * v_next;
        relative.row(i) = work.velocity;
        forces.row(i) = row(f0, i) - gains[s] * row(relative, i);
      }
      classify(contacts, forces, status, start_velocity, relative, may_stick, new_status, new_slide);
      bool same = new_status == status, any_sliding = false;
      double change = 0.0;
      for (Eigen::Index i = 0; i < m; ++i) {
        if (status[static_cast<std::size_t>(i)] != 2) continue;
        any_sliding = true;
        change = std::max(change, (new_slide.row(i) - slide.row(i)).cwiseAbs().maxCoeff());
      }
      if (same && (!any_sliding || change < 1e-12)) break;
      for (Eigen::Index i = 0; i < m; ++i) may_stick[i] = may_stick[i] && new_status[static_cast<std::size_t>(i)] == 2;
      status = new_status;
      slide.topRows(m) = new_slide.topRows(m);
    }
    // end_displacement: integrated while sticking, on the cone edge when sliding, 0 when off
    for (Eigen::Index i = 0; i < m; ++i) {
      const auto s = static_cast<std::size_t>(i);
      const Vector3 normal = row(contacts.normal, i);
      if (status[s] == 0) {
        forces.row(i).setZero();
        continue;  // displacement 0
      }
      if (status[s] == 2) {
        const Vector3 force = row(forces, i);
        const Vector3 tangent = force - force.dot(normal) * normal;
        displacement.row(i) = -tangent / (contacts.weight[i] * settings_.law.tangential_stiffness);
      } else {
        displacement.row(i) = contacts.displacement.row(i) + dt * tangential(row(relative, i), normal).transpose();
      }
    }
    contacts.force = forces.topRows(m);
    for (Eigen::Index i = 0; i < m; ++i) {
      contacts.sticking[i] = status[static_cast<std::size_t>(i)] == 1;
      contact_torque.noalias() += jacobian[static_cast<std::size_t>(i)].transpose() * row(forces, i);
    }
  }
  Flags& sliding = result.memory.sliding;
  sliding.resize(m);
  for (Eigen::Index i = 0; i < m; ++i) sliding[i] = status[static_cast<std::size_t>(i)] == 2;
  // drive: M a + bias - contact - passive + implicit terms, less the motor's own damping (python_engine.py: _drive)
  work.acceleration = (v_next - v) / dt;
  work.product.noalias() = mass * work.acceleration;
  Vector& delivered = work.delivered;
  delivered = (work.product + (bias - contact_torque - joint.torque) + implicit_damping.cwiseProduct(v_next)).head(nvh);
  result.drive = delivered - drive.motor_damping.cwiseProduct(v_next.head(nvh));
  result.load = result.drive - work.product.head(nvh);  // less the links' inertia (python_engine.py: _drive)
  work.increment = v_next * dt;
  result.q = integrate(q, work.increment);
  result.v = v_next;
  result.memory.pair = contacts.pair;
  result.memory.local_b = contacts.local_b;
  result.contacts = std::move(contacts);
}

}  // namespace bhgrasp
