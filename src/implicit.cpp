// The implicit step: see engine.hpp.  It mirrors bhgrasp/sim/python_engine.py (PythonEngine._implicit, _drive) and
// the active-set helpers of bhgrasp/sim/contact_law.py; the comments there explain the linearisation.
#include <algorithm>
#include <cmath>

#include "engine.hpp"
#include "kernels.hpp"
#include "part_system.hpp"

namespace bhgrasp {

void Engine::implicit_step(const Vector& q, const Vector& v, const Vector& tau, const Drive& drive,
                           const Memory& memory, StepResult& result) {
  const double dt = settings_.dt;
  const int nv = model_.nv, nvh = settings_.nv_hand;
  // Every array but the result's lives in work_ (no allocation once sized, but for the sparse factorisation of the solve
  // by parts, made again each step); where an expression would evaluate a
  // product into a temporary, the product goes to a work array first, with the same arithmetic.
  Work& work = work_;
  const bool sparse = settings_.sparse;  // the velocity system by parts (part_system.hpp), or one dense matrix
  Contacts contacts = detect(q, memory);
  parts_.compute_joint_jacobians(q);
  const Matrix& mass = work.mass;
  if (sparse) {
    parts_.mass_blocks(q, work.mass_blocks);
  } else {
    mass_matrix(q, work.mass);
  }
  Vector& bias = work.bias;
  parts_.nonlinear_effects(q, v, bias);
  implicit_gyroscopic(v, bias);
  passive(q, v, drive, work.passive);
  const Passive& joint = work.passive;
  Vector& implicit_damping = work.implicit_damping;
  implicit_damping = dt * joint.stiffness + joint.damping;
  Matrix& matrix = work.matrix;
  if (sparse) {
    const int count = parts_.count();
    work.system_blocks.resize(static_cast<std::size_t>(count));
    work.part_first.resize(static_cast<std::size_t>(count));
    for (int p = 0; p < count; ++p) {
      const auto s = static_cast<std::size_t>(p);
      work.part_first[s] = parts_.first(p);
      work.system_blocks[s] = work.mass_blocks[s];
      work.system_blocks[s].diagonal() += dt * implicit_damping.segment(parts_.first(p), parts_.size(p));
    }
    system_->begin(drive.transmission, work.system_blocks, work.part_first, nv);
  } else {
    matrix = mass;
    matrix.diagonal() += dt * implicit_damping;
  }
  mass_times(v, work.product);
  Vector& rhs = work.rhs;
  rhs = work.product + dt * (tau - bias + joint.torque);
  if (!sparse) transmission(drive, work.transmission);
  const Matrix& full = work.transmission;
  const Eigen::Index m = contacts.size();
  Vector& v_next = work.v_next;
  Vector& contact_torque = work.contact_torque;
  contact_torque.setZero(nv);
  Points& displacement = result.memory.displacement;
  displacement.setZero(m, 3);
  std::vector<int>& status = work.status;  // its first m entries
  std::vector<Matrix>& jacobian = work.jacobian;
  std::vector<PartJacobian>& part_jacobian = work.part_jacobian;
  std::vector<Matrix3>& gains = work.gains;
  if (m == 0) {
    if (sparse) {
      system_->solve(part_jacobian, 0, gains, dt, rhs, v_next);
    } else {
      reduced_solve(full, matrix, rhs, v_next);
    }
  } else {
    if (sparse) {
      part_jacobians(contacts, part_jacobian);
    } else {
      jacobians(contacts, jacobian);
    }
    Points &start_velocity = work.start_velocity, &relative = work.relative, &forces = work.forces;
    Points &slide = work.slide, &new_slide = work.new_slide, &f0 = work.f0;
    for (Points* array : {&start_velocity, &relative, &forces, &slide, &new_slide, &f0}) reserve_rows(*array, m);
    for (Eigen::Index i = 0; i < m; ++i) {
      if (sparse) {
        work.velocity = part_jacobian[static_cast<std::size_t>(i)].times(v);
      } else {
        work.velocity.noalias() = jacobian[static_cast<std::size_t>(i)] * v;
      }
      start_velocity.row(i) = work.velocity;
    }
    linear_parts(contacts, work.parts);
    const Parts& parts = work.parts;
    start_status(contacts, parts, start_velocity, status, slide);
    Flags& may_stick = work.may_stick;
    reserve_rows(may_stick, m);
    for (Eigen::Index i = 0; i < m; ++i) may_stick[i] = status[static_cast<std::size_t>(i)] == 2;
    std::vector<int>& new_status = work.new_status;
    gains.resize(static_cast<std::size_t>(m));
    for (int pass = 0; pass < 8; ++pass) {
      // linearise: f(v+) = f0 - D J v+ in each contact's status
      Matrix& matrix_c = work.matrix_c;
      if (!sparse) matrix_c = matrix;
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
        if (sparse) {
          part_jacobian[s].add_transpose_times(dt * row(f0, i), rhs_c);
          continue;
        }
        const Matrix& jac = jacobian[s];
        work.gain_jacobian.noalias() = gains[s] * jac;
        matrix_c.noalias() += dt * (jac.transpose() * work.gain_jacobian);
        rhs_c.noalias() += dt * (jac.transpose() * row(f0, i));
      }
      if (sparse) {
        system_->solve(part_jacobian, m, gains, dt, rhs_c, v_next);
      } else {
        reduced_solve(full, matrix_c, rhs_c, v_next);
      }
      for (Eigen::Index i = 0; i < m; ++i) {
        const auto s = static_cast<std::size_t>(i);
        if (sparse) {
          work.velocity = part_jacobian[s].times(v_next);
        } else {
          work.velocity.noalias() = jacobian[s] * v_next;
        }
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
      if (sparse) {
        part_jacobian[static_cast<std::size_t>(i)].add_transpose_times(row(forces, i), contact_torque);
      } else {
        contact_torque.noalias() += jacobian[static_cast<std::size_t>(i)].transpose() * row(forces, i);
      }
    }
  }
  Flags& sliding = result.memory.sliding;
  sliding.resize(m);
  for (Eigen::Index i = 0; i < m; ++i) sliding[i] = status[static_cast<std::size_t>(i)] == 2;
  // drive: M a + bias - contact - passive + implicit terms, less the motor's own damping (python_engine.py: _drive)
  work.acceleration = (v_next - v) / dt;
  mass_times(work.acceleration, work.product);
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
