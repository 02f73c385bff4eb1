// The compiled step: see engine.hpp.  Each function mirrors the Python function of the same name in
// bhgrasp/sim/simulator.py (Simulator), bhgrasp/sim/integrators.py or bhgrasp/sim/contact.py (ContactEngine); the
// comments there explain the physics.
#include "engine.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <coal/collision.h>
#include <coal/contact_patch.h>
#include <coal/distance.h>
#include <coal/shape/geometric_shapes.h>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/algorithm/geometry.hpp>
#include <pinocchio/algorithm/jacobian.hpp>
#include <pinocchio/algorithm/joint-configuration.hpp>
#include <pinocchio/algorithm/kinematics.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/collision/coal-pinocchio-conversions.hpp>
#include <pinocchio/serialization.hpp>

namespace bhgrasp {
namespace {

using ConstRef = Eigen::Ref<const Vector>;

constexpr double kFrictionVelocity = 1e-3;  // [rad/s] regularisation of Coulomb joint friction (sim/simulator.py)

// w x I w in the principal axes, I = diag(moments) (sim/integrators.py: gyroscopic_torque).
Vector3 gyroscopic(const Vector3& moments, const Vector3& w) {
  const double a = moments[0], b = moments[1], c = moments[2];
  return Vector3((c - b) * w[1] * w[2], (a - c) * w[2] * w[0], (b - a) * w[0] * w[1]);
}

// The midpoint m of an implicit-midpoint step of torque-free spin, I m + h m x I m = I w
// (sim/integrators.py: spin_midpoint).
Vector3 spin_midpoint(const Vector3& moments, const Vector3& w, double h) {
  const double a = moments[0], b = moments[1], c = moments[2];
  const double w0 = w[0], w1 = w[1], w2 = w[2];
  double m0 = w0, m1 = w1, m2 = w2;
  const double p = h * (c - b), q = h * (a - c), r = h * (b - a);
  for (int iteration = 0; iteration < 30; ++iteration) {
    const double f0 = a * (m0 - w0) + p * m1 * m2;
    const double f1 = b * (m1 - w1) + q * m2 * m0;
    const double f2 = c * (m2 - w2) + r * m0 * m1;
    const double j01 = p * m2, j02 = p * m1, j10 = q * m2, j12 = q * m0, j20 = r * m1, j21 = r * m0;
    const double c0 = b * c - j12 * j21, c1 = j12 * j20 - j10 * c, c2 = j10 * j21 - b * j20;
    const double det = a * c0 + j01 * c1 + j02 * c2;
    const double d0 = (f0 * c0 + j01 * (j12 * f2 - f1 * c) + j02 * (f1 * j21 - b * f2)) / det;
    const double d1 = (a * (f1 * c - j12 * f2) + f0 * c1 + j02 * (j10 * f2 - f1 * j20)) / det;
    const double d2 = (a * (b * f2 - f1 * j21) + j01 * (f1 * j20 - j10 * f2) + f0 * c2) / det;
    m0 -= d0;
    m1 -= d1;
    m2 -= d2;
    if (std::max({std::abs(d0), std::abs(d1), std::abs(d2)}) <=
        1e-16 * (1.0 + std::max({std::abs(m0), std::abs(m1), std::abs(m2)})))
      break;
  }
  return Vector3(m0, m1, m2);
}

Vector3 row(const Points& points, Eigen::Index i) { return points.row(i).transpose(); }

// The tangential part of a vector at normal n.
Vector3 tangential(const Vector3& x, const Vector3& n) { return x - x.dot(n) * n; }

// Solve (T^T A T) w = T^T b and return T w (A symmetric positive definite, T of full column rank).
Vector reduced_solve(const Matrix& transmission, const Matrix& matrix, const Vector& rhs) {
  if (transmission.rows() == transmission.cols() && transmission.isIdentity(0.0)) {  // every coordinate driven
    Eigen::LLT<Matrix> cholesky(matrix);
    if (cholesky.info() == Eigen::Success) return cholesky.solve(rhs);
    return matrix.partialPivLu().solve(rhs);
  }
  const Matrix reduced = transmission.transpose() * matrix * transmission;
  const Vector right = transmission.transpose() * rhs;
  Eigen::LLT<Matrix> cholesky(reduced);
  if (cholesky.info() == Eigen::Success) return transmission * cholesky.solve(right);
  return transmission * reduced.partialPivLu().solve(right);
}

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
  model_.loadFromString(model);
  geometry_.loadFromString(geometry);
  data_ = pinocchio::Data(model_);
  geometry_data_ = pinocchio::GeometryData(geometry_);
  const auto pairs = settings_.pairs.size();
  if (settings_.queries.size() != pairs) throw std::invalid_argument("one query setting per collision pair is needed");
  for (const Pair& pair : settings_.pairs) {
    const int n = static_cast<int>(geometry_.ngeoms);
    if (pair.geom_a < 0 || pair.geom_a >= n || pair.geom_b < 0 || pair.geom_b >= n)
      throw std::invalid_argument("a collision pair names a geometry the geometry model lacks");
    if (pair.joint_a < 0 || pair.joint_a >= model_.njoints || pair.joint_b < 0 || pair.joint_b >= model_.njoints)
      throw std::invalid_argument("a collision pair names a joint the model lacks");
  }
  if (settings_.lower.size() != settings_.nv_hand || settings_.upper.size() != settings_.nv_hand ||
      settings_.joint_stiffness.size() != model_.nv || settings_.joint_damping.size() != model_.nv)
    throw std::invalid_argument("joint limits, stiffness or damping of the wrong size");
  identity_objects_ = Matrix::Identity(model_.nv - settings_.nv_hand, model_.nv - settings_.nv_hand);
  for (const Query& query : settings_.queries) {
    coal::CollisionRequest request;
    request.enable_contact = true;
    request.num_max_contacts = static_cast<std::size_t>(query.num_max_contacts);
    request.security_margin = query.security_margin;
    request.break_distance = query.break_distance;
    request.gjk_tolerance = request.epa_tolerance = query.tolerance;
    requests_.push_back(request);
    patch_requests_.emplace_back(static_cast<std::size_t>(query.max_num_patch),
                                 static_cast<std::size_t>(query.num_samples_curved_shapes), query.patch_tolerance);
    patch_results_.emplace_back(patch_requests_.back());
  }
  results_.resize(pairs);
  probe_ = std::make_shared<coal::Sphere>(1e-12);
  for (const auto& object : geometry_.geometryObjects) {  // bounding spheres for the broad phase
    object.geometry->computeLocalAABB();
    const bool bounded = std::isfinite(object.geometry->aabb_radius) && object.geometry->aabb_center.allFinite();
    bound_radius_.push_back(bounded ? object.geometry->aabb_radius : std::numeric_limits<double>::infinity());
    bound_centre_.push_back(bounded ? Vector3(object.geometry->aabb_center) : Vector3::Zero());
  }
  frame_jacobian_ = pinocchio::Data::Matrix6x::Zero(6, model_.nv);
}

// ------------------------------------------------------------------ detection (sim/contact.py: ContactEngine.detect)
Contacts Engine::detect(const Vector& q, const Memory& memory) {
  pinocchio::updateGeometryPlacements(model_, data_, geometry_, geometry_data_, q);
  std::vector<std::int64_t> pairs;
  std::vector<Vector3> points, normals;
  std::vector<double> depths, weights;
  Points patch_points;
  std::vector<double> patch_depths;
  for (std::size_t k = 0; k < settings_.pairs.size(); ++k) {
    const Pair& pair = settings_.pairs[k];
    const auto& shape_a = geometry_.geometryObjects[pair.geom_a].geometry;
    const auto& shape_b = geometry_.geometryObjects[pair.geom_b].geometry;
    const pinocchio::SE3 &placement_a = geometry_data_.oMg[pair.geom_a], &placement_b = geometry_data_.oMg[pair.geom_b];
    const double reach = bound_radius_[pair.geom_a] + bound_radius_[pair.geom_b];
    if (std::isfinite(reach) &&  // broad phase: bounding spheres apart, no contact (the narrow phase would agree)
        (placement_a.act(bound_centre_[pair.geom_a]) - placement_b.act(bound_centre_[pair.geom_b])).norm() >
            reach + requests_[k].security_margin + 1e-9)
      continue;
    const coal::Transform3s transform_a = pinocchio::toCoalTransform3s(placement_a);
    const coal::Transform3s transform_b = pinocchio::toCoalTransform3s(placement_b);
    coal::CollisionResult& result = results_[k];
    result.clear();
    if (!coal::collide(shape_a.get(), transform_a, shape_b.get(), transform_b, requests_[k], result))
      continue;
    coal::ContactPatchResult& patches = patch_results_[k];
    coal::computeContactPatch(shape_a.get(), transform_a, shape_b.get(), transform_b, result,
                              patch_requests_[k], patches);
    for (std::size_t p = 0; p < patches.numContactPatches(); ++p) {
      const coal::ContactPatch& patch = patches.getContactPatch(p);
      const auto size = static_cast<Eigen::Index>(patch.size());
      const Vector3 normal = patch.getNormal();
      patch_points.resize(size, 3);
      for (Eigen::Index i = 0; i < size; ++i) patch_points.row(i) = patch.getPoint(static_cast<std::size_t>(i));
      patch_depths.clear();
      if (size == 1)
        patch_depths.push_back(-patch.penetration_depth);
      else
        point_depths(static_cast<int>(k), patch_points, normal, patch_depths);
      for (Eigen::Index i = 0; i < size; ++i) {
        pairs.push_back(static_cast<std::int64_t>(k));
        points.push_back(row(patch_points, i));
        normals.push_back(normal);
        depths.push_back(patch_depths[static_cast<std::size_t>(i)]);
        weights.push_back(1.0 / static_cast<double>(size));
      }
    }
  }
  Eigen::Index m = 0;
  for (double depth : depths) m += depth > 0.0;
  Contacts contacts;
  contacts.resize(m);
  Eigen::Index i = 0;
  for (std::size_t j = 0; j < depths.size(); ++j) {
    if (!(depths[j] > 0.0)) continue;
    const Pair& pair = settings_.pairs[static_cast<std::size_t>(pairs[j])];
    contacts.pair[i] = pairs[j];
    contacts.point.row(i) = points[j];
    contacts.normal.row(i) = normals[j];
    contacts.depth[i] = depths[j];
    contacts.friction[i] = pair.friction;
    contacts.weight[i] = weights[j];
    const pinocchio::SE3& placement = data_.oMi[static_cast<std::size_t>(pair.joint_b)];
    contacts.local_b.row(i) = placement.actInv(points[j]);
    ++i;
  }
  recall(contacts, memory);
  return contacts;
}

void Engine::point_depths(int k, const Points& points, const Vector3& normal, std::vector<double>& depths) {
  const Pair& pair = settings_.pairs[static_cast<std::size_t>(k)];
  const Eigen::Index n = points.rows();
  const Eigen::RowVector3d centroid = points.colwise().sum() / static_cast<double>(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    Vector3 inward = (centroid - points.row(i)).transpose();
    inward -= inward.dot(normal) * normal;
    const double length = std::sqrt(inward.squaredNorm());
    const Vector3 offset = inward * (std::min(1e-3, 0.125 * length) / std::max(length, 1e-300));
    const Vector3 near_point = row(points, i) + offset, far_point = row(points, i) + 2 * offset;
    const double near = -(signed_distance(pair.geom_a, near_point) + signed_distance(pair.geom_b, near_point));
    const double far = -(signed_distance(pair.geom_a, far_point) + signed_distance(pair.geom_b, far_point));
    depths.push_back(2 * near - far);
  }
}

double Engine::signed_distance(int geom, const Vector3& point) {
  const pinocchio::SE3& placement = geometry_data_.oMg[static_cast<std::size_t>(geom)];
  const coal::CollisionGeometry* shape = geometry_.geometryObjects[static_cast<std::size_t>(geom)].geometry.get();
  const Vector3 local = placement.rotation().transpose() * (point - placement.translation());
  if (const auto* box = dynamic_cast<const coal::Box*>(shape)) {
    const Vector3 excess = local.cwiseAbs() - box->halfSide;
    return std::sqrt(excess.cwiseMax(0.0).squaredNorm()) + std::min(excess.maxCoeff(), 0.0);
  }
  if (const auto* plane = dynamic_cast<const coal::Halfspace*>(shape)) return local.dot(plane->n) - plane->d;
  if (const auto* sphere = dynamic_cast<const coal::Sphere*>(shape))
    return std::sqrt(local.squaredNorm()) - sphere->radius;
  coal::Transform3s probe_placement;
  probe_placement.setTranslation(point);
  coal::DistanceRequest request;
  coal::DistanceResult result;
  return coal::distance(probe_.get(), probe_placement, shape, pinocchio::toCoalTransform3s(placement), request, result);
}

void Engine::recall(Contacts& contacts, const Memory& memory) const {
  const Eigen::Index m = contacts.size(), old = memory.pair.size();
  contacts.displacement.setZero(m, 3);
  contacts.was_sliding.setZero(m);
  if (old == 0) return;
  const double radius2 = settings_.law.match_radius * settings_.law.match_radius;
  for (Eigen::Index i = 0; i < m; ++i) {
    Eigen::Index nearest = 0;
    double best = std::numeric_limits<double>::infinity();
    bool any_same = false;
    for (Eigen::Index j = 0; j < old; ++j) {
      if (memory.pair[j] != contacts.pair[i]) continue;
      any_same = true;
      const double distance = (contacts.local_b.row(i) - memory.local_b.row(j)).squaredNorm();
      if (distance < best) best = distance, nearest = j;  // the first of equals, as argmin
    }
    Vector3 u = row(memory.displacement, nearest);
    bool sliding = false;
    if (best <= radius2) {
      sliding = memory.sliding[nearest];
    } else if (any_same) {  // a point not reported last step inherits its pair's mean displacement
      Vector3 sum = Vector3::Zero();
      int count = 0;
      for (Eigen::Index j = 0; j < old; ++j) {
        if (memory.pair[j] != contacts.pair[i]) continue;
        sum += row(memory.displacement, j);
        sliding = sliding || memory.sliding[j];
        ++count;
      }
      u = sum / static_cast<double>(count);
    } else {
      u.setZero();
    }
    const Vector3 normal = row(contacts.normal, i);
    const Vector3 projected = tangential(u, normal);  // onto the new tangent plane, keeping its length
    const double length = std::sqrt(u.squaredNorm()), new_length = std::sqrt(projected.squaredNorm());
    contacts.displacement.row(i) = projected * (length / std::max(new_length, 1e-300));
    contacts.was_sliding[i] = sliding;
  }
}

// Relative point Jacobians J_b(p) - J_a(p), world-aligned, (3, nv) each; needs computeJointJacobians at q.
void Engine::jacobians(const Contacts& contacts, std::vector<Matrix>& result) {
  result.assign(static_cast<std::size_t>(contacts.size()), Matrix::Zero(3, model_.nv));
  for (Eigen::Index i = 0; i < contacts.size(); ++i) {
    const Pair& pair = settings_.pairs[static_cast<std::size_t>(contacts.pair[i])];
    Matrix& jacobian = result[static_cast<std::size_t>(i)];
    if (pair.joint_b) {
      const pinocchio::SE3 placement(Matrix3::Identity(), row(contacts.local_b, i));
      frame_jacobian_.setZero();
      pinocchio::getFrameJacobian(model_, data_, static_cast<pinocchio::JointIndex>(pair.joint_b), placement,
                                  pinocchio::LOCAL_WORLD_ALIGNED, frame_jacobian_);
      jacobian = frame_jacobian_.topRows<3>();
    }
    if (pair.joint_a) {
      const auto joint = static_cast<pinocchio::JointIndex>(pair.joint_a);
      const pinocchio::SE3 placement(Matrix3::Identity(), data_.oMi[joint].actInv(row(contacts.point, i)));
      frame_jacobian_.setZero();
      pinocchio::getFrameJacobian(model_, data_, joint, placement, pinocchio::LOCAL_WORLD_ALIGNED, frame_jacobian_);
      jacobian -= frame_jacobian_.topRows<3>();
    }
  }
}

// ------------------------------------------------------------------ force law (sim/contact.py)
Engine::Parts Engine::linear_parts(const Contacts& contacts) const {
  const ContactLaw& law = settings_.law;
  const double dt = settings_.dt;
  const Eigen::Index m = contacts.size();
  Parts parts;
  parts.f0.resize(m, 3);
  parts.f0_stick.resize(m, 3);
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
  return parts;
}

void Engine::start_status(const Contacts& contacts, const Parts& parts, const Points& start_velocity,
                          std::vector<int>& status, Points& slide) const {
  const Eigen::Index m = contacts.size();
  status.assign(static_cast<std::size_t>(m), 1);
  slide.setZero(m, 3);
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
  slide.setZero(m, 3);
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

// Explicit forces on body b at relative point velocities; returns end-of-step displacements (sim/contact.py: forces).
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

// ------------------------------------------------------------------ joint space (sim/simulator.py)
Engine::Passive Engine::passive(const Vector& q, const Vector& v, const Drive& drive) const {
  const int nvh = settings_.nv_hand;
  Passive result{Vector::Zero(model_.nv), settings_.joint_stiffness, settings_.joint_damping};
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
  return result;
}

Matrix Engine::mass_matrix(const Vector& q) {
  pinocchio::crba(model_, data_, ConstRef(q));
  Matrix mass = data_.M;
  mass.triangularView<Eigen::StrictlyLower>() = mass.transpose();
  return mass;
}

Matrix Engine::transmission(const Drive& drive) const {
  const Eigen::Index rows = drive.transmission.rows(), cols = drive.transmission.cols();
  const Eigen::Index objects = identity_objects_.rows();
  Matrix full = Matrix::Zero(model_.nv, cols + objects);
  full.topLeftCorner(rows, cols) = drive.transmission;
  full.bottomRightCorner(objects, objects) = identity_objects_;
  return full;
}

void Engine::implicit_gyroscopic(const Vector& v, Vector& bias) const {
  for (const Spinning& body : settings_.spinning) {
    const Vector3 w = body.axes.transpose() * v.segment<3>(body.angular);
    if ((body.moments[0] == body.moments[1] && body.moments[1] == body.moments[2]) || (w.array() == 0.0).all())
      continue;
    const Vector3 explicit_torque = gyroscopic(body.moments, w);
    const Vector3 middle = spin_midpoint(body.moments, w, 0.5 * settings_.dt);
    bias.segment<3>(body.angular) += body.axes * (gyroscopic(body.moments, middle) - explicit_torque);
  }
}

Vector Engine::increment_rate(const Vector& increment, const Vector& v) const {
  Vector rate = v;
  for (const Spinning& body : settings_.spinning) {
    const Vector3 theta = increment.segment<3>(body.angular), w = v.segment<3>(body.angular);
    const Vector3 half = theta.cross(w);
    rate.segment<3>(body.angular) = w + 0.5 * half + theta.cross(half) / 12.0;
  }
  return rate;
}

Vector Engine::gravity(const Vector& q) {
  return pinocchio::computeGeneralizedGravity(model_, data_, ConstRef(q)).head(settings_.nv_hand);
}

Matrix Engine::frame_jacobians(const Vector& q, const std::vector<int>& frames) {
  pinocchio::computeJointJacobians(model_, data_, ConstRef(q));
  Matrix result(3 * static_cast<Eigen::Index>(frames.size()), settings_.nv_hand);
  for (std::size_t f = 0; f < frames.size(); ++f) {
    if (frames[f] < 0 || frames[f] >= static_cast<int>(model_.nframes))
      throw std::invalid_argument("a frame index the model lacks");
    frame_jacobian_.setZero();
    pinocchio::getFrameJacobian(model_, data_, static_cast<pinocchio::FrameIndex>(frames[f]),
                                pinocchio::LOCAL_WORLD_ALIGNED, frame_jacobian_);
    result.middleRows(3 * static_cast<Eigen::Index>(f), 3) = frame_jacobian_.topLeftCorner(3, settings_.nv_hand);
  }
  return result;
}

Vector Engine::integrate(const Vector& q, const Vector& v) const {
  Vector result(model_.nq);
  pinocchio::integrate(model_, q, v, result);
  return result;
}

// ------------------------------------------------------------------ the step
StepResult Engine::step(const Vector& q, const Vector& v, const Vector& tau_hand, const Drive& drive,
                        const Memory& memory, double max_speed, double max_penetration) {
  if (q.size() != model_.nq || v.size() != model_.nv || tau_hand.size() != settings_.nv_hand)
    throw std::invalid_argument("q, v or tau_hand of the wrong size");
  if (drive.transmission.rows() != settings_.nv_hand || drive.joint_damping.size() != settings_.nv_hand ||
      drive.friction.size() != settings_.nv_hand || drive.motor_damping.size() != settings_.nv_hand)
    throw std::invalid_argument("the drive's transmission, damping or friction has the wrong size");
  Vector tau = Vector::Zero(model_.nv);
  tau.head(settings_.nv_hand) = tau_hand;
  StepResult result;
  const double dt = settings_.dt;
  if (settings_.integrator == 0) {
    implicit_step(q, v, tau, drive, memory, result);
  } else {
    const Matrix full = transmission(drive);
    Acceleration first = acceleration(q, v, tau, full, drive, memory, settings_.integrator == 1);
    if (settings_.integrator == 1) {
      result.v = v + dt * first.acceleration;
      result.q = integrate(q, result.v * dt);
    } else {  // Runge-Kutta-Munthe-Kaas (simulator.py: _explicit)
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
    result.memory = Memory{result.contacts.pair, result.contacts.local_b, first.displacement,
                           (!result.contacts.sticking.array()).matrix()};
  }
  // divergence (simulator.py: _check)
  Divergence& divergence = result.divergence;
  const bool finite_q = result.q.allFinite(), finite_v = result.v.allFinite();
  if (!finite_q || !finite_v) {
    divergence.kind = !finite_q ? 1 : 2;
  } else if (model_.nv > 0) {
    Eigen::Index index;
    const double speed = result.v.cwiseAbs().maxCoeff(&index);
    if (!(speed <= max_speed)) divergence = Divergence{3, static_cast<int>(index), speed};
  }
  if (divergence.kind == 0 && result.contacts.size() && result.contacts.depth.maxCoeff() > max_penetration)
    divergence = Divergence{4, -1, result.contacts.depth.maxCoeff()};
  return result;
}

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

Engine::Acceleration Engine::acceleration(const Vector& q, const Vector& v, const Vector& tau,
                                          const Matrix& transmission, const Drive& drive, const Memory& memory,
                                          bool gyroscopic) {
  Acceleration result;
  result.contacts = detect(q, memory);
  pinocchio::computeJointJacobians(model_, data_, ConstRef(q));
  const Passive joint = passive(q, v, drive);
  const Vector total = tau + joint.torque - joint.damping.cwiseProduct(v);
  const Eigen::Index m = result.contacts.size();
  Vector generalized = Vector::Zero(model_.nv);
  if (m) {
    std::vector<Matrix> jacobian;
    jacobians(result.contacts, jacobian);
    Points relative(m, 3);
    for (Eigen::Index i = 0; i < m; ++i) relative.row(i) = jacobian[static_cast<std::size_t>(i)] * v;
    contact_forces(result.contacts, relative, result.displacement);
    for (Eigen::Index i = 0; i < m; ++i)
      generalized.noalias() += jacobian[static_cast<std::size_t>(i)].transpose() * row(result.contacts.force, i);
  } else {
    result.displacement.setZero(0, 3);
  }
  const Matrix mass = mass_matrix(q);
  Vector bias = pinocchio::nonLinearEffects(model_, data_, ConstRef(q), ConstRef(v));
  if (gyroscopic) implicit_gyroscopic(v, bias);
  result.acceleration = reduced_solve(transmission, mass, total + generalized - bias);
  const int nvh = settings_.nv_hand;
  result.drive = (mass * result.acceleration + bias - generalized - joint.torque + joint.damping.cwiseProduct(v))
                     .head(nvh);
  result.drive -= drive.motor_damping.cwiseProduct(v.head(nvh));
  return result;
}

}  // namespace bhgrasp
