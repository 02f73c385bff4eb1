// The implicit step: see engine.hpp.  It mirrors bhgrasp/sim/simulator.py (Simulator._implicit, _drive) and the
// active-set helpers of bhgrasp/sim/contact.py; the comments there explain the linearisation.
#include <algorithm>
#include <cmath>

#include <pinocchio/algorithm/jacobian.hpp>
#include <pinocchio/algorithm/rnea.hpp>

#include "engine.hpp"
#include "kernels.hpp"

namespace bhgrasp {

void Engine::implicit_step(const Vector& q, const Vector& v, const Vector& tau, const Drive& drive,
                           const Memory& memory, StepResult& result) {
  const double dt = settings_.dt;
  const int nv = model_.nv, nvh = settings_.nv_hand;
  Contacts contacts = detect(q, memory);
  pinocchio::computeJointJacobians(model_, data_, ConstRef(q));
  const Matrix mass = mass_matrix(q);
  Vector bias = pinocchio::nonLinearEffects(model_, data_, ConstRef(q), ConstRef(v));
  implicit_gyroscopic(v, bias);
  const Passive joint = passive(q, v, drive);
  const Vector implicit_damping = dt * joint.stiffness + joint.damping;
  Matrix matrix = mass;
  matrix.diagonal() += dt * implicit_damping;
  const Vector rhs = mass * v + dt * (tau - bias + joint.torque);
  const Matrix full = transmission(drive);
  const Eigen::Index m = contacts.size();
  Vector v_next;
  Vector contact_torque = Vector::Zero(nv);
  Points displacement = Points::Zero(m, 3);
  std::vector<int> status;
  if (m == 0) {
    v_next = reduced_solve(full, matrix, rhs);
  } else {
    std::vector<Matrix> jacobian;
    jacobians(contacts, jacobian);
    Points start_velocity(m, 3), relative(m, 3), forces(m, 3), slide, new_slide;
    for (Eigen::Index i = 0; i < m; ++i) start_velocity.row(i) = jacobian[static_cast<std::size_t>(i)] * v;
    const Parts parts = linear_parts(contacts);
    start_status(contacts, parts, start_velocity, status, slide);
    Flags may_stick(m);
    for (Eigen::Index i = 0; i < m; ++i) may_stick[i] = status[static_cast<std::size_t>(i)] == 2;
    std::vector<int> new_status;
    Points f0(m, 3);
    std::vector<Matrix3> gains(static_cast<std::size_t>(m));
    for (int pass = 0; pass < 8; ++pass) {
      // linearise: f(v+) = f0 - D J v+ in each contact's status
      Matrix matrix_c = matrix;
      Vector rhs_c = rhs;
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
        matrix_c.noalias() += dt * (jac.transpose() * (gains[s] * jac));
        rhs_c.noalias() += dt * (jac.transpose() * row(f0, i));
      }
      v_next = reduced_solve(full, matrix_c, rhs_c);
      for (Eigen::Index i = 0; i < m; ++i) {
        const auto s = static_cast<std::size_t>(i);
        relative.row(i) = jacobian[s] * v_next;
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
      slide = new_slide;
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
    contacts.force = forces;
    for (Eigen::Index i = 0; i < m; ++i) {
      contacts.sticking[i] = status[static_cast<std::size_t>(i)] == 1;
      contact_torque.noalias() += jacobian[static_cast<std::size_t>(i)].transpose() * row(forces, i);
    }
  }
  Flags sliding(m);
  for (Eigen::Index i = 0; i < m; ++i) sliding[i] = status[static_cast<std::size_t>(i)] == 2;
  // drive: M a + bias - contact - passive + implicit terms, less the motor's own damping (simulator.py: _drive)
  const Vector delivered = (mass * ((v_next - v) / dt) + (bias - contact_torque - joint.torque) +
                            implicit_damping.cwiseProduct(v_next)).head(nvh);
  result.drive = delivered - drive.motor_damping.cwiseProduct(v_next.head(nvh));
  result.q = integrate(q, v_next * dt);
  result.v = v_next;
  result.memory = Memory{contacts.pair, contacts.local_b, displacement, sliding};
  result.contacts = std::move(contacts);
}

}  // namespace bhgrasp
