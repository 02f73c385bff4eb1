// Contact detection and matching: see engine.hpp.  Each function mirrors the Python function of the same name in
// bhgrasp/sim/contact.py (ContactEngine); the comments there explain the geometry.
#include <algorithm>
#include <cmath>
#include <limits>

#include <coal/collision.h>
#include <coal/contact_patch.h>
#include <coal/distance.h>
#include <coal/shape/geometric_shapes.h>
#include <pinocchio/collision/coal-pinocchio-conversions.hpp>

#include "engine.hpp"
#include "kernels.hpp"
#include "narrowphase.hpp"

namespace bhgrasp {
namespace {

// Point i of a contact patch in the world frame: coal's ContactPatch::getPoint, with the same arithmetic, without its
// COAL_ASSERT, which in a release build of coal still constructs a std::logic_error (its message on the heap) per call.
Vector3 patch_point(const coal::ContactPatch& patch, std::size_t i) {
  coal::Vec3s point(0, 0, 0);
  point.head<2>() = patch.points()[i];
  point = patch.tf.transform(point);
  return point;
}

// Whether every contact of a query has a finite depth within max_depth (contact.py _converged: EPA converged).
bool converged(const coal::CollisionResult& result, double max_depth) {
  for (std::size_t i = 0; i < result.numContacts(); ++i)
    if (!(std::abs(result.getContact(i).penetration_depth) <= max_depth)) return false;
  return true;
}

}  // namespace

// The separating-axis test of two boxes (Gottschalk, Lin and Manocha, "OBBTree", SIGGRAPH 1996): the axes of each box
// and the nine cross products of an axis of one with an axis of the other.  On a unit axis n the gap between the
// boxes' projections, |t . n| - (the two half extents along n), is at most their distance.  Cross products of
// (nearly) parallel axes are left out (dividing by their small length would amplify round-off): fewer axes can only
// lower the gap.  A placement that is not finite gives NaN, which skips nothing.
double box_separation(const Vector3& half_a, const pinocchio::SE3& placement_a, const Vector3& half_b,
                      const pinocchio::SE3& placement_b) {
  const Matrix3 axes = placement_a.rotation().transpose() * placement_b.rotation();  // b's axes in a's frame
  const Vector3 t = placement_a.rotation().transpose() * (placement_b.translation() - placement_a.translation());
  if (!axes.allFinite() || !t.allFinite()) return std::numeric_limits<double>::quiet_NaN();
  const Matrix3 spread = axes.cwiseAbs();
  double gap = -std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    gap = std::max(gap, std::abs(t[i]) - half_a[i] - spread.row(i).dot(half_b));
    gap = std::max(gap, std::abs(t.dot(axes.col(i))) - spread.col(i).dot(half_a) - half_b[i]);
  }
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const Vector3 axis = Vector3::Unit(i).cross(axes.col(j));  // in a's frame
      const double length = axis.norm();
      if (length < 1e-6) continue;
      const double extent_b = half_b[0] * std::abs(axis.dot(axes.col(0))) +
                              half_b[1] * std::abs(axis.dot(axes.col(1))) + half_b[2] * std::abs(axis.dot(axes.col(2)));
      gap = std::max(gap, (std::abs(t.dot(axis)) - axis.cwiseAbs().dot(half_a) - extent_b) / length);
    }
  }
  return gap;
}

// ------------------------------------------------------------------ detection (sim/contact.py: ContactEngine.detect)
Contacts Engine::detect(const Vector& q, const Memory& memory) {
  parts_.forward_kinematics(q);
  parts_.update_geometry_placements(geometry_, geometry_data_);
  // the candidate points, in work arrays (no allocation once they are large enough)
  std::vector<std::int64_t>& pairs = work_.pair;
  std::vector<Vector3> &points = work_.point, &normals = work_.normal;
  std::vector<double> &depths = work_.depth, &weights = work_.weight, &patch_depths = work_.patch_depths;
  pairs.clear();
  points.clear();
  normals.clear();
  depths.clear();
  weights.clear();
  broad_phase(work_.candidate);
  for (const int candidate : work_.candidate) {
    const auto k = static_cast<std::size_t>(candidate);
    const Pair& pair = settings_.pairs[k];
    const auto& shape_a = geometry_.geometryObjects[pair.geom_a].geometry;
    const auto& shape_b = geometry_.geometryObjects[pair.geom_b].geometry;
    const pinocchio::SE3 &placement_a = geometry_data_.oMg[pair.geom_a], &placement_b = geometry_data_.oMg[pair.geom_b];
    const double reach = bound_radius_[pair.geom_a] + bound_radius_[pair.geom_b];
    if (std::isfinite(reach) &&  // broad phase: bounding spheres apart, no contact (the narrow phase would agree)
        (placement_a.act(bound_centre_[pair.geom_a]) - placement_b.act(bound_centre_[pair.geom_b])).norm() >
            reach + request_.security_margin + 1e-9)
      continue;
    const coal::Box* box_a = box_[static_cast<std::size_t>(pair.geom_a)];
    const coal::Box* box_b = box_[static_cast<std::size_t>(pair.geom_b)];
    // two boxes apart along an axis: coal would find no contact either (the Python engine asks it; the same contacts)
    if (box_axes && box_a != nullptr && box_b != nullptr &&
        box_separation(box_a->halfSide, placement_a, box_b->halfSide, placement_b) >
            request_.security_margin + box_slack_) {
      ++box_axes_skipped;
      continue;
    }
    const coal::Transform3s transform_a = pinocchio::toCoalTransform3s(placement_a);
    const coal::Transform3s transform_b = pinocchio::toCoalTransform3s(placement_b);
    coal::CollisionResult& result = result_;
    result.clear();
    if (!narrowphase_->collide(shape_a.get(), transform_a, shape_b.get(), transform_b, request_, result))
      continue;
    // EPA stopped short at the tight tolerance, or at a depth no contact has: ask again at coal's default
    if (!converged(result, std::min(2.0 * std::min(bound_radius_[pair.geom_a], bound_radius_[pair.geom_b]), 1.0))) {
      result.clear();
      if (!narrowphase_->collide(shape_a.get(), transform_a, shape_b.get(), transform_b, fallback_request_, result))
        continue;
    }
    coal::ContactPatchResult& patches = patch_result_;
    coal::computeContactPatch(shape_a.get(), transform_a, shape_b.get(), transform_b, result,
                              patch_request_, patches);
    for (std::size_t p = 0; p < patches.numContactPatches(); ++p) {
      const coal::ContactPatch& patch = patches.getContactPatch(p);
      const auto size = static_cast<Eigen::Index>(patch.size());
      const Vector3 normal = patch.getNormal();
      const auto patch_size = static_cast<std::size_t>(size);
      if (work_.patch_points.size() <= patch_size) work_.patch_points.resize(patch_size + 1);
      Points& patch_points = work_.patch_points[patch_size];
      patch_points.resize(size, 3);  // allocates once per patch size
      for (Eigen::Index i = 0; i < size; ++i) patch_points.row(i) = patch_point(patch, static_cast<std::size_t>(i));
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
    const pinocchio::SE3& placement = parts_.placement(static_cast<int>(pair.joint_b));
    contacts.local_b.row(i) = placement.actInv(points[j]);
    ++i;
  }
  recall(contacts, memory);
  return contacts;
}

// The pairs the narrow phase may find touching, in pair order: every pair of a scene of few pairs; else a sweep over
// the geometries' bounding spheres (each widened by the security margin and a hair) along the world axis their centres
// spread most on, keeping the pairs whose widened spheres meet, and the pairs of an unbounded shape.  Every pair that
// passes the narrow phase's own bounding-sphere test (detect) is kept, and kept pairs are tested in pair order: the
// contacts do not depend on the sweep.  A placement that is not finite (a diverging stage) gets every pair, as before.
void Engine::broad_phase(std::vector<int>& result) {
  result.clear();
  const auto pairs = static_cast<int>(settings_.pairs.size());
  if (pairs < kSweepFrom) {
    for (int k = 0; k < pairs; ++k) result.push_back(k);
    return;
  }
  std::vector<int>& order = work_.order;
  std::vector<double>& low = work_.low;
  std::vector<Vector3>& centre = work_.centre;
  const std::size_t geoms = geometry_.ngeoms;
  low.resize(geoms);
  centre.resize(geoms);
  order.clear();
  Vector3 sum = Vector3::Zero(), squares = Vector3::Zero();
  for (std::size_t g = 0; g < geoms; ++g) {
    if (!std::isfinite(bound_radius_[g])) continue;
    centre[g] = geometry_data_.oMg[g].act(bound_centre_[g]);
    sum += centre[g];
    squares += centre[g].cwiseProduct(centre[g]);
    order.push_back(static_cast<int>(g));
  }
  if (!sum.allFinite() || !squares.allFinite()) {  // no order to sweep in: every pair, as the narrow phase tests them
    for (int k = 0; k < pairs; ++k) result.push_back(k);
    return;
  }
  Eigen::Index axis = 0;  // the axis of the largest spread (sum of squared deviations)
  (squares - sum.cwiseProduct(sum) / std::max<double>(1.0, static_cast<double>(order.size()))).maxCoeff(&axis);
  for (const int g : order) low[static_cast<std::size_t>(g)] = centre[static_cast<std::size_t>(g)][axis] - bound_radius_[static_cast<std::size_t>(g)];
  std::sort(order.begin(), order.end(), [&low](int a, int b) { return low[a] < low[b] || (low[a] == low[b] && a < b); });
  result = always_;
  for (std::size_t i = 0; i < order.size(); ++i) {
    const auto a = static_cast<std::size_t>(order[i]);
    const double reach_a = bound_radius_[a] + sweep_margin_, high = centre[a][axis] + reach_a;
    for (std::size_t j = i + 1; j < order.size() && low[static_cast<std::size_t>(order[j])] <= high; ++j) {
      const auto b = static_cast<std::size_t>(order[j]);
      const double reach = reach_a + bound_radius_[b];
      if ((centre[a] - centre[b]).squaredNorm() > reach * reach) continue;
      const auto first = std::min(a, b);
      const int second = static_cast<int>(std::max(a, b));
      const std::vector<std::pair<int, int>>& partners = partners_[first];
      const auto found = std::lower_bound(partners.begin(), partners.end(), std::make_pair(second, -1));
      if (found != partners.end() && found->first == second) result.push_back(found->second);
    }
  }
  std::sort(result.begin(), result.end());
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
  if (const auto* cylinder = dynamic_cast<const coal::Cylinder*>(shape)) {  // axis along local z
    const double radial = std::sqrt(local.x() * local.x() + local.y() * local.y()) - cylinder->radius;
    const double axial = std::abs(local.z()) - cylinder->halfLength;
    const double outside_radial = std::max(radial, 0.0), outside_axial = std::max(axial, 0.0);
    const double outside = std::sqrt(outside_radial * outside_radial + outside_axial * outside_axial);
    return outside + std::min(std::max(radial, axial), 0.0);
  }
  if (const auto* capsule = dynamic_cast<const coal::Capsule*>(shape)) {  // segment along local z
    const double along = local.z() - std::clamp(local.z(), -capsule->halfLength, capsule->halfLength);
    return std::sqrt(local.x() * local.x() + local.y() * local.y() + along * along) - capsule->radius;
  }
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
  // A step's memory lists its contacts in pair order: each contact's pair is then one run of it, found by bisection
  // (the same entries in the same order as a scan of the whole memory, which an unsorted memory gets).
  const std::int64_t* pairs = memory.pair.data();
  const bool sorted = std::is_sorted(pairs, pairs + old);
  for (Eigen::Index i = 0; i < m; ++i) {
    Eigen::Index nearest = 0, begin = 0, end = old;
    if (sorted) {
      const auto run = std::equal_range(pairs, pairs + old, contacts.pair[i]);
      begin = run.first - pairs;
      end = run.second - pairs;
    }
    double best = std::numeric_limits<double>::infinity();
    bool any_same = false;
    for (Eigen::Index j = begin; j < end; ++j) {
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
      for (Eigen::Index j = begin; j < end; ++j) {
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

// Relative point Jacobians J_b(p) - J_a(p), world-aligned, (3, nv) each, in the first m entries of result (a work
// array that only grows); needs parts_.compute_joint_jacobians at q.
// Contact i's point Jacobians on its bodies' parts, each given to add(first velocity, its 3 rows, sign): body b's (+1,
// a point fixed on it), then body a's (-1), each where its joint is not 0 (the environment or the fixed palm).
template <class Add>
void Engine::point_jacobians(const Contacts& contacts, Eigen::Index i, Add add) {
  const Pair& pair = settings_.pairs[static_cast<std::size_t>(contacts.pair[i])];
  Eigen::Index first = 0;
  if (pair.joint_b) {
    const pinocchio::SE3 placement(Matrix3::Identity(), row(contacts.local_b, i));
    const SceneParts::Jacobian& part = parts_.point_jacobian(static_cast<int>(pair.joint_b), placement, first);
    add(first, part.topRows<3>(), 1.0);
  }
  if (pair.joint_a) {
    const auto joint = static_cast<int>(pair.joint_a);
    const pinocchio::SE3 placement(Matrix3::Identity(), parts_.placement(joint).actInv(row(contacts.point, i)));
    const SceneParts::Jacobian& part = parts_.point_jacobian(joint, placement, first);
    add(first, part.topRows<3>(), -1.0);
  }
}

void Engine::jacobians(const Contacts& contacts, std::vector<Matrix>& result) {
  if (result.size() < static_cast<std::size_t>(contacts.size()))
    result.resize(static_cast<std::size_t>(contacts.size()), Matrix(3, model_.nv));
  for (Eigen::Index i = 0; i < contacts.size(); ++i) {
    Matrix& jacobian = result[static_cast<std::size_t>(i)];
    jacobian.setZero();
    point_jacobians(contacts, i, [&jacobian](Eigen::Index first, const auto& rows, double sign) {
      if (sign > 0) {
        jacobian.middleCols(first, rows.cols()) = rows;
      } else {
        jacobian.middleCols(first, rows.cols()) -= rows;
      }
    });
  }
}

void Engine::part_jacobians(const Contacts& contacts, std::vector<PartJacobian>& result) {
  if (result.size() < static_cast<std::size_t>(contacts.size())) result.resize(static_cast<std::size_t>(contacts.size()));
  for (Eigen::Index i = 0; i < contacts.size(); ++i) {
    PartJacobian& jacobian = result[static_cast<std::size_t>(i)];
    jacobian.count = 0;
    point_jacobians(contacts, i, [&jacobian](Eigen::Index first, const auto& rows, double sign) {
      jacobian.add(first, rows, sign);
    });
  }
}

}  // namespace bhgrasp
