// The compiled step: see engine.hpp.  Each function mirrors the Python function of the same name in
// bhgrasp/sim/python_engine.py (PythonEngine); the comments there explain the physics.  This file holds the set-up, the
// step's dispatch, the explicit integrators' accelerations and the joint-space terms; contact detection is in
// detect.cpp, the contact law in contact_law.cpp, the implicit step in implicit.cpp, the rotation helpers in
// integrators.cpp.
#include "engine.hpp"
#include "model_io.hpp"
#include "narrowphase.hpp"
#include "part_system.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <coal/collision.h>
#include <coal/contact_patch.h>
#include <coal/shape/geometric_shapes.h>

#include "kernels.hpp"

namespace bhgrasp {
namespace {

constexpr double kFrictionVelocity = 1e-3;  // [rad/s] regularisation of Coulomb joint friction (sim/python_engine.py)

}  // namespace

void Contacts::resize(Eigen::Index m) {
  pair.resize(m);
  point.resize(m, 3);
  normal.resize(m, 3);
  depth.resize(m);
  friction.resize(m);
  displacement.setZero(m, 3);
  weight.resize(m);
  local_b.resize(m, 3);
  force.setZero(m, 3);
  sticking.setZero(m);
  was_sliding.setZero(m);
}

Engine::Engine(const std::string& model, const std::string& geometry, Settings settings)
    : settings_(std::move(settings)) {
  if (settings_.sparse && settings_.integrator != 0)
    throw std::invalid_argument("the velocity system by parts (sparse) serves the implicit integrator only");
  if (settings_.sparse) system_ = std::make_unique<PartSystem>();
  narrowphase_ = std::make_unique<Narrowphase>();
  model_ = model_from_text(model);
  geometry_ = geometry_from_text(geometry);
  parts_ = SceneParts(model_, settings_.nv_hand);
  geometry_data_ = pinocchio::GeometryData(geometry_);
  for (const Pair& pair : settings_.pairs) {
    const int n = static_cast<int>(geometry_.ngeoms);
    if (pair.geom_a < 0 || pair.geom_a >= n || pair.geom_b < 0 || pair.geom_b >= n)
      throw std::invalid_argument("a collision pair names a geometry the geometry model lacks");
    if (pair.geom_a == pair.geom_b) throw std::invalid_argument("a collision pair joins a geometry to itself");
    if (pair.joint_a < 0 || pair.joint_a >= model_.njoints || pair.joint_b < 0 || pair.joint_b >= model_.njoints)
      throw std::invalid_argument("a collision pair names a joint the model lacks");
  }
  if (settings_.lower.size() != settings_.nv_hand || settings_.upper.size() != settings_.nv_hand ||
      settings_.joint_stiffness.size() != model_.nv || settings_.joint_damping.size() != model_.nv)
    throw std::invalid_argument("joint limits, stiffness or damping of the wrong size");
  // every pair is asked with the same requests, one pair at a time into the same results
  const Query& query = settings_.query;
  request_.enable_contact = true;
  request_.num_max_contacts = static_cast<std::size_t>(query.num_max_contacts);
  request_.security_margin = query.security_margin;
  request_.break_distance = query.break_distance;
  request_.gjk_tolerance = request_.epa_tolerance = query.tolerance;
  fallback_request_ = request_;
  fallback_request_.gjk_tolerance = fallback_request_.epa_tolerance = query.fallback_tolerance;
  patch_request_ = coal::ContactPatchRequest(static_cast<std::size_t>(query.max_num_patch),
                                             static_cast<std::size_t>(query.num_samples_curved_shapes),
                                             query.patch_tolerance);
  patch_result_ = coal::ContactPatchResult(patch_request_);
  sweep_margin_ = request_.security_margin + 1e-6;  // the broad phase's (detect.cpp): 1e-6 above the test's 1e-9
  // how far apart two boxes must be for coal to find no contact: GJK's distance never falls below the true one, but
  // within its tolerance of touching it may report a contact, so the gap needs the larger tolerance, with room
  box_slack_ = 1e-9 + 10.0 * std::max(query.tolerance, query.fallback_tolerance);
  probe_ = std::make_shared<coal::Sphere>(1e-12);
  for (const auto& object : geometry_.geometryObjects) {  // bounding spheres for the broad phase
    object.geometry->computeLocalAABB();
    const bool bounded = std::isfinite(object.geometry->aabb_radius) && object.geometry->aabb_center.allFinite();
    bound_radius_.push_back(bounded ? object.geometry->aabb_radius : std::numeric_limits<double>::infinity());
    bound_centre_.push_back(bounded ? Vector3(object.geometry->aabb_center) : Vector3::Zero());
    // the boxes of detect.cpp's separating-axis test (not one a swept sphere inflates: the test knows no radius)
    const auto* box = dynamic_cast<const coal::Box*>(object.geometry.get());
    box_.push_back(box != nullptr && box->getSweptSphereRadius() == 0.0 ? box : nullptr);
  }
  partners_.resize(geometry_.ngeoms);
  for (std::size_t k = 0; k < settings_.pairs.size(); ++k) {  // the broad phase's sweep (detect.cpp: broad_phase)
    const Pair& pair = settings_.pairs[k];
    const auto a = static_cast<std::size_t>(pair.geom_a), b = static_cast<std::size_t>(pair.geom_b);
    if (!std::isfinite(bound_radius_[a]) || !std::isfinite(bound_radius_[b])) {
      always_.push_back(static_cast<int>(k));
    } else {
      partners_[std::min(a, b)].emplace_back(static_cast<int>(std::max(a, b)), static_cast<int>(k));
    }
  }
  for (auto& partners : partners_) {
    std::sort(partners.begin(), partners.end());
    for (std::size_t i = 1; i < partners.size(); ++i)
      if (partners[i].first == partners[i - 1].first)
        throw std::invalid_argument("two collision pairs join the same two geometries");
  }
}

Engine::~Engine() = default;

bool Engine::kept_solver() const { return narrowphase_->kept; }
void Engine::set_kept_solver(bool kept) { narrowphase_->kept = kept; }

// ------------------------------------------------------------------ joint space (sim/python_engine.py)
void Engine::passive(const Vector& q, const Vector& v, const Drive& drive, Passive& result) const {
  const int nvh = settings_.nv_hand;
  result.torque.setZero(model_.nv);
  result.stiffness = settings_.joint_stiffness;
  result.damping = settings_.joint_damping;
  for (std::size_t i = 0; i < settings_.spring_v.size(); ++i)
    result.torque[settings_.spring_v[i]] =
        -settings_.joint_stiffness[settings_.spring_v[i]] * q[settings_.spring_q[i]];
  result.damping.head(nvh) += drive.joint_damping;
  if ((drive.friction.array() != 0.0).any()) {
    for (int j = 0; j < nvh; ++j) {
      const double ratio = v[j] / kFrictionVelocity, decay = std::exp(-2.0 * std::abs(ratio));
      const double slope = drive.friction[j] / kFrictionVelocity * (4.0 * decay / ((1.0 + decay) * (1.0 + decay)));
      result.torque[j] += slope * v[j] - drive.friction[j] * std::tanh(ratio);
      result.damping[j] += slope;
    }
  }
  for (int j = 0; j < settings_.nq_hand; ++j) {
    const double stop = std::clamp(q[j], settings_.lower[j], settings_.upper[j]);
    if (stop == q[j]) continue;
    result.torque[j] -= settings_.limit_stiffness * (q[j] - stop);
    result.stiffness[j] += settings_.limit_stiffness;
    result.damping[j] += settings_.limit_damping;
  }
}

void Engine::mass_matrix(const Vector& q, Matrix& mass) {
  parts_.mass_matrix(q, mass);
}

void Engine::mass_times(const Vector& x, Vector& result) const {
  if (!settings_.sparse) {
    result.noalias() = work_.mass * x;
    return;
  }
  result.resize(x.size());
  for (int p = 0; p < parts_.count(); ++p) {
    const Eigen::Index first = parts_.first(p), n = parts_.size(p);
    result.segment(first, n).noalias() = work_.mass_blocks[static_cast<std::size_t>(p)] * x.segment(first, n);
  }
}

void Engine::transmission(const Drive& drive, Matrix& full) const {
  const Eigen::Index rows = drive.transmission.rows(), cols = drive.transmission.cols();
  const Eigen::Index objects = model_.nv - settings_.nv_hand;
  full.setZero(model_.nv, cols + objects);
  full.topLeftCorner(rows, cols) = drive.transmission;
  full.bottomRightCorner(objects, objects).setIdentity();
}

// Solve (T^T A T) w = T^T b and set solution = T w (A symmetric positive definite, T of full column rank).  The
// products that an expression would evaluate into temporaries go to work arrays, with the same arithmetic.
void Engine::reduced_solve(const Matrix& transmission, const Matrix& matrix, const Vector& rhs, Vector& solution) {
  Work& work = work_;
  if (transmission.rows() == transmission.cols() && transmission.isIdentity(0.0)) {  // every coordinate driven
    work.cholesky.compute(matrix);
    if (work.cholesky.info() == Eigen::Success) {
      solution = work.cholesky.solve(rhs);
    } else {
      solution = matrix.partialPivLu().solve(rhs);
    }
    return;
  }
  work.half.noalias() = transmission.transpose() * matrix;
  work.reduced.noalias() = work.half * transmission;  // T^T A T
  work.right.noalias() = transmission.transpose() * rhs;
  work.cholesky.compute(work.reduced);
  if (work.cholesky.info() == Eigen::Success) {
    work.reduced_solution = work.cholesky.solve(work.right);
    solution.noalias() = transmission * work.reduced_solution;
  } else {
    solution = transmission * work.reduced.partialPivLu().solve(work.right);
  }
}

Vector Engine::gravity(const Vector& q) {
  return parts_.hand_gravity(q);
}

Matrix Engine::frame_jacobians(const Vector& q, const std::vector<int>& frames) {
  parts_.compute_joint_jacobians(q);
  Matrix result = Matrix::Zero(3 * static_cast<Eigen::Index>(frames.size()), settings_.nv_hand);
  for (std::size_t f = 0; f < frames.size(); ++f) {
    if (frames[f] < 0 || frames[f] >= static_cast<int>(model_.nframes))
      throw std::invalid_argument("a frame index the model lacks");
    const pinocchio::Frame& frame = model_.frames[static_cast<std::size_t>(frames[f])];
    if (frame.parentJoint == 0) continue;  // fixed in the world: zero rows
    Eigen::Index first = 0;
    const SceneParts::Jacobian& jacobian = parts_.point_jacobian(static_cast<int>(frame.parentJoint), frame.placement,
                                                                 first);
    if (first >= settings_.nv_hand) continue;  // on an object: zero on the hand's columns
    result.block(3 * static_cast<Eigen::Index>(f), first, 3, jacobian.cols()) = jacobian.topRows<3>();
  }
  return result;
}

// ------------------------------------------------------------------ the step
StepResult Engine::step(const Vector& q, const Vector& v, const Vector& tau_hand, const Drive& drive,
                        const Memory& memory, double max_speed, double max_penetration) {
  if (q.size() != model_.nq || v.size() != model_.nv ||
      (tau_hand.size() != settings_.nv_hand && tau_hand.size() != model_.nv))
    throw std::invalid_argument("q, v or tau_hand of the wrong size");
  if (drive.transmission.rows() != settings_.nv_hand || drive.joint_damping.size() != settings_.nv_hand ||
      drive.friction.size() != settings_.nv_hand || drive.motor_damping.size() != settings_.nv_hand)
    throw std::invalid_argument("the drive's transmission, damping or friction has the wrong size");
  Vector& tau = work_.tau;
  tau.setZero(model_.nv);
  tau.head(tau_hand.size()) = tau_hand;  // hand joint torques, or generalized forces on the whole scene
  StepResult result;
  const double dt = settings_.dt;
  if (settings_.integrator == 0) {
    implicit_step(q, v, tau, drive, memory, result);
  } else {
    transmission(drive, work_.transmission);
    const Matrix& full = work_.transmission;
    Acceleration first = acceleration(q, v, tau, full, drive, memory, settings_.integrator == 1);
    if (settings_.integrator == 1) {
      result.v = v + dt * first.acceleration;
      result.q = integrate(q, result.v * dt);
    } else {  // Runge-Kutta-Munthe-Kaas (python_engine.py: _explicit)
      const Vector& k1 = first.acceleration;
      const Vector v2 = v + dt / 2 * k1;
      const Vector q2 = integrate(q, v * dt / 2);
      const Vector rate2 = increment_rate(v * dt / 2, v2);
      const Vector k2 = acceleration(q2, v2, tau, full, drive, memory, false).acceleration;
      const Vector v3 = v + dt / 2 * k2;
      const Vector q3 = integrate(q, rate2 * dt / 2);
      const Vector rate3 = increment_rate(rate2 * dt / 2, v3);
      const Vector k3 = acceleration(q3, v3, tau, full, drive, memory, false).acceleration;
      const Vector v4 = v + dt * k3;
      const Vector q4 = integrate(q, rate3 * dt);
      const Vector rate4 = increment_rate(rate3 * dt, v4);
      const Vector k4 = acceleration(q4, v4, tau, full, drive, memory, false).acceleration;
      result.v = v + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
      result.q = integrate(q, dt / 6 * (v + 2 * rate2 + 2 * rate3 + rate4));
    }
    result.contacts = std::move(first.contacts);
    result.drive = std::move(first.drive);
    result.load = std::move(first.load);
    result.memory = Memory{result.contacts.pair, result.contacts.local_b, first.displacement,
                           (!result.contacts.sticking.array()).matrix()};
  }
  // divergence (python_engine.py: divergence)
  Divergence& divergence = result.divergence;
  const bool finite_q = result.q.allFinite(), finite_v = result.v.allFinite();
  if (!finite_q || !finite_v) {
    const Vector& values = !finite_q ? result.q : result.v;
    Eigen::Index index = 0;
    while (std::isfinite(values[index])) ++index;
    divergence = Divergence{!finite_q ? 1 : 2, static_cast<int>(index), values[index]};
  } else if (model_.nv > 0) {
    Eigen::Index index;
    const double speed = result.v.cwiseAbs().maxCoeff(&index);
    if (!(speed <= max_speed)) divergence = Divergence{3, static_cast<int>(index), speed};
  }
  if (divergence.kind == 0 && result.contacts.size() && result.contacts.depth.maxCoeff() > max_penetration)
    divergence = Divergence{4, -1, result.contacts.depth.maxCoeff()};
  if (divergence.kind == 0 && model_.nq > 0) {
    Eigen::Index index;
    const double largest = result.q.cwiseAbs().maxCoeff(&index);
    if (!(largest <= settings_.max_coordinate)) divergence = Divergence{5, static_cast<int>(index), result.q[index]};
  }
  return result;
}

Engine::Acceleration Engine::acceleration(const Vector& q, const Vector& v, const Vector& tau,
                                          const Matrix& transmission, const Drive& drive, const Memory& memory,
                                          bool gyroscopic) {
  Acceleration result;
  result.contacts = detect(q, memory);
  parts_.compute_joint_jacobians(q);
  passive(q, v, drive, work_.passive);
  const Passive& joint = work_.passive;
  const Vector total = tau + joint.torque - joint.damping.cwiseProduct(v);
  const Eigen::Index m = result.contacts.size();
  Vector generalized = Vector::Zero(model_.nv);
  if (m) {
    std::vector<Matrix>& jacobian = work_.jacobian;
    jacobians(result.contacts, jacobian);
    Points relative(m, 3);
    for (Eigen::Index i = 0; i < m; ++i) relative.row(i) = jacobian[static_cast<std::size_t>(i)] * v;
    contact_forces(result.contacts, relative, result.displacement);
    for (Eigen::Index i = 0; i < m; ++i)
      generalized.noalias() += jacobian[static_cast<std::size_t>(i)].transpose() * row(result.contacts.force, i);
  } else {
    result.displacement.setZero(0, 3);
  }
  mass_matrix(q, work_.mass);
  const Matrix& mass = work_.mass;
  Vector bias;
  parts_.nonlinear_effects(q, v, bias);
  if (gyroscopic) implicit_gyroscopic(v, bias);
  reduced_solve(transmission, mass, total + generalized - bias, result.acceleration);
  const int nvh = settings_.nv_hand;
  const Vector inertial = mass * result.acceleration;
  result.drive = (inertial + bias - generalized - joint.torque + joint.damping.cwiseProduct(v)).head(nvh);
  result.drive -= drive.motor_damping.cwiseProduct(v.head(nvh));
  result.load = result.drive - inertial.head(nvh);
  return result;
}

}  // namespace bhgrasp
