#include "sensing.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace bhgrasp {

FingerSums finger_contacts(const ConstIndices& finger, Eigen::Index fingers, const ConstPoints& points,
                           const ConstPoints& normals, const ConstPoints& forces) {
  FingerSums sums;
  FingerWork work;
  finger_contacts_into(finger, fingers, points, normals, forces, sums, work);
  return sums;
}

void finger_contacts_into(const ConstIndices& finger, Eigen::Index fingers, const ConstPoints& points,
                          const ConstPoints& normals, const ConstPoints& forces, FingerSums& sums, FingerWork& work) {
  const Eigen::Index m = finger.size();
  if (points.rows() != m || normals.rows() != m || forces.rows() != m || fingers < 0)
    throw std::invalid_argument("finger, points, normals and forces must have one row per contact");
  sums.force.setZero(fingers, 3);
  sums.normal_force.setZero(fingers);
  sums.normal.setZero(fingers, 3);
  sums.count.setZero(fingers);
  sums.point.setZero(fingers, 3);
  sums.strongest.setConstant(fingers, -1);
  Vector& weight_sum = work.weight_sum;
  Vector& best = work.best;
  Points& pressing_normal = work.pressing_normal;
  Points& plain_normal = work.plain_normal;
  weight_sum.setZero(fingers);
  best.setConstant(fingers, -1.0);
  pressing_normal.setZero(fingers, 3);
  plain_normal.setZero(fingers, 3);
  for (Eigen::Index k = 0; k < m; ++k) {
    const Eigen::Index f = finger[k];
    if (f < 0) continue;
    if (f >= fingers) throw std::invalid_argument("a contact's finger index is out of range");
    const double component = forces.row(k).dot(normals.row(k));  // n . f
    const double weight = std::max(component, 0.0);
    sums.force.row(f) += forces.row(k);
    sums.normal_force[f] += component;
    sums.count[f] += 1;
    weight_sum[f] += weight;
    pressing_normal.row(f) += weight * normals.row(k);
    plain_normal.row(f) += normals.row(k);
    sums.point.row(f) += weight * points.row(k);
    if (weight > best[f]) {  // strict: the first of equal weights, as numpy.argmax
      best[f] = weight;
      sums.strongest[f] = k;
    }
  }
  for (Eigen::Index f = 0; f < fingers; ++f) {
    if (sums.count[f] == 0) continue;
    const bool pressing = weight_sum[f] > 0.0;
    const Eigen::RowVector3d mean = pressing ? pressing_normal.row(f) : plain_normal.row(f);
    const double norm = mean.norm();
    if (norm > 0.0) sums.normal.row(f) = mean / norm;
    if (pressing) {
      sums.point.row(f) /= weight_sum[f];
    } else {
      sums.point.row(f).setZero();
      sums.strongest[f] = -1;
    }
  }
}

namespace {

Eigen::Matrix3d skew(const Eigen::Vector3d& x) {
  Eigen::Matrix3d result;
  result << 0.0, -x.z(), x.y(), x.z(), 0.0, -x.x(), -x.y(), x.x(), 0.0;
  return result;
}

}  // namespace

Eigen::Matrix<double, 6, 7, Eigen::RowMajor> object_regressor(const Eigen::Matrix3d& rotation,
                                                               const Eigen::Vector3d& omega,
                                                               const Eigen::Matrix<double, 6, 1>& v_r,
                                                               const Eigen::Matrix<double, 6, 1>& a_r,
                                                               const Eigen::Vector3d& gravity) {
  static constexpr int kEntries[6][2] = {{0, 0}, {0, 1}, {0, 2}, {1, 1}, {1, 2}, {2, 2}};  // I_xx, I_xy, ... I_zz
  Eigen::Matrix<double, 6, 7, Eigen::RowMajor> regressor = Eigen::Matrix<double, 6, 7, Eigen::RowMajor>::Zero();
  regressor.block<3, 1>(0, 0) = a_r.head<3>() - gravity;
  const Eigen::Vector3d w = v_r.tail<3>(), alpha = a_r.tail<3>();
  const Eigen::Matrix3d omega_skew = skew(omega), w_skew = skew(w);
  const Eigen::Vector3d omega_w = omega_skew * w;
  for (int k = 0; k < 6; ++k) {
    Eigen::Matrix3d basis = Eigen::Matrix3d::Zero();
    basis(kEntries[k][0], kEntries[k][1]) = basis(kEntries[k][1], kEntries[k][0]) = 1.0;
    const Eigen::Matrix3d inertia = rotation * basis * rotation.transpose();  // R B_k R^T
    // I_k alpha + (omega x I_k w - I_k (omega x w) + w x I_k omega) / 2
    const Eigen::Vector3d coriolis = omega_skew * (inertia * w) - inertia * omega_w + w_skew * (inertia * omega);
    regressor.block<3, 1>(3, k + 1) = inertia * alpha + 0.5 * coriolis;
  }
  return regressor;
}

Eigen::Matrix3d contact_frame(const Eigen::RowVector3d& normal, double switch_x) {
  const double length = std::sqrt(normal.dot(normal));
  const Eigen::RowVector3d unit = normal / length;
  const Eigen::RowVector3d axis =
      std::abs(unit.x()) > switch_x ? Eigen::RowVector3d::UnitY() : Eigen::RowVector3d::UnitX();
  Eigen::RowVector3d t1 = axis - axis.dot(unit) * unit;
  t1 /= std::sqrt(t1.dot(t1));
  Eigen::Matrix3d frame;
  frame.col(0) = t1.transpose();
  frame.col(2) = unit.transpose();
  frame(0, 1) = unit.y() * t1.z() - unit.z() * t1.y();
  frame(1, 1) = unit.z() * t1.x() - unit.x() * t1.z();
  frame(2, 1) = unit.x() * t1.y() - unit.y() * t1.x();
  return frame;
}

Points contact_frames(const Points& normals, double zero_length, double switch_x, Eigen::Index& zero) {
  const Eigen::Index m = normals.rows();
  Points frames(3 * m, 3);
  zero = -1;
  for (Eigen::Index i = 0; i < m; ++i) {
    const Eigen::RowVector3d normal = normals.row(i);
    if (std::sqrt(normal.dot(normal)) < zero_length && zero < 0) zero = i;
    frames.middleRows<3>(3 * i) = contact_frame(normal, switch_x);
  }
  return frames;
}

}  // namespace bhgrasp
