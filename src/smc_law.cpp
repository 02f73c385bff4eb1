// The SMC-adaptive grasp law: see smc_law.hpp.  sense() and grasp() mirror ObjectGraspController.__call__,
// SMCAdaptiveGrasp.grasp_torques and ObjectGraspController.distribute (bhgrasp/controllers/) line for line.
#include "smc_law.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <pinocchio/spatial/explog.hpp>

namespace bhgrasp {

SMCAdaptiveLaw::SMCAdaptiveLaw(GraspKinematics& kinematics, HandDynamics& dynamics, int fingers)
    : kinematics_(kinematics), dynamics_(dynamics), nv_(kinematics.nv()), fingers_(fingers) {
  if (fingers < 1 || dynamics.nv() != kinematics.nv())
    throw std::invalid_argument("SMCAdaptiveLaw: one finger or more, and kernels of the same hand");
  integral_.setZero(fingers_, 3);
  has_integral_.assign(static_cast<std::size_t>(fingers_), 0);
  qps_.resize(static_cast<std::size_t>(fingers_) + 1);
  touching_.reserve(static_cast<std::size_t>(fingers_));
  joints_.reserve(static_cast<std::size_t>(fingers_));
  points_.setZero(fingers_, 3);
  frames_.setZero(3 * fingers_, 3);
  desired_.resize(3 * fingers_);
  correction_.resize(3 * fingers_);
  measured_.resize(fingers_, 3);
  force_error_.resize(fingers_, 3);
  q_dot_r_.resize(nv_);
  q_dd_r_.resize(nv_);
  s_f_.resize(nv_);
  tau_.resize(nv_);
  k_f_.setZero(nv_);
}

void SMCAdaptiveLaw::configure(double rho, const Vector6& k_o, const Vector7& object_adaptation, double force_gain,
                               double force_integral, const ConstVector& k_f, bool normal_only, double squeeze,
                               bool grip_reflex, const Eigen::Vector3d& gravity, const Vector7& initial_estimate,
                               double mu, const Rows& pyramid, double inscribed, double min_normal_force,
                               double tolerance, int max_iter, int max_iter_in, double zero_length, double switch_x) {
  if (k_f.size() != nv_ || pyramid.cols() != 3 || pyramid.rows() < 1 || max_iter < 1 || max_iter_in < 1)
    throw std::invalid_argument("SMCAdaptiveLaw.configure: k_f of size nv, a (facets, 3) pyramid, iterations >= 1");
  rho_ = rho, k_o_ = k_o, object_adaptation_ = object_adaptation, force_gain_ = force_gain;
  force_integral_ = force_integral, k_f_ = k_f, normal_only_ = normal_only, squeeze_ = squeeze, gravity_ = gravity;
  grip_reflex_ = grip_reflex;
  initial_estimate_ = initial_estimate, mu_ = mu, pyramid_ = pyramid, inscribed_ = inscribed;
  min_normal_force_ = min_normal_force, tolerance_ = tolerance, max_iter_ = max_iter, max_iter_in_ = max_iter_in;
  zero_length_ = zero_length, switch_x_ = switch_x;
  reset();
}

void SMCAdaptiveLaw::reset() {
  estimate_ = initial_estimate_;
  std::fill(has_integral_.begin(), has_integral_.end(), 0);
  for (auto& solver : qps_) solver.reset();
  infeasible_cycles_ = 0;
}

void SMCAdaptiveLaw::set_base(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation,
                              const Eigen::Vector3d& gravity) {
  base_rotation_ = rotation, base_translation_ = translation, model_gravity_ = gravity;
}

ContactForceQP& SMCAdaptiveLaw::qp(int count) {
  auto& solver = qps_[static_cast<std::size_t>(count)];
  if (!solver)  // the twin's ContactForceQP(n, mu, min_normal_force=...) of distribute()
    solver = std::make_unique<ContactForceQP>(count, mu_, pyramid_, inscribed_, min_normal_force_, tolerance_,
                                              max_iter_, max_iter_in_);
  return *solver;
}

int SMCAdaptiveLaw::sense(const ConstIndices& finger, const ConstIndices& joint, const ConstPoints& points,
                          const ConstPoints& normals, const ConstPoints& forces) {
  if (joint.size() != finger.size()) throw std::invalid_argument("finger and joint must have one entry per contact");
  finger_contacts_into(finger, fingers_, points, normals, forces, sums_, work_);
  touching_.clear();
  joints_.clear();
  for (int f = 0; f < fingers_; ++f) {  // ObjectGraspController.touching: the fingers whose contacts press
    const std::int64_t row = sums_.strongest[f];
    if (sums_.count[f] == 0 || row < 0) continue;
    touching_.push_back(f);
    joints_.push_back(static_cast<int>(joint[row]));  // parent_joints of the link that presses hardest
  }
  return static_cast<int>(touching_.size());
}

int SMCAdaptiveLaw::sense_contacts(const Contacts& contacts, const ConstIndices& finger_of_pair,
                                   const ConstIndices& joint_of_pair) {
  if (joint_of_pair.size() != finger_of_pair.size())
    throw std::invalid_argument("finger_of_pair and joint_of_pair must have one entry per collision pair");
  const Eigen::Index rows = contacts.size();
  row_finger_.resize(rows);
  row_joint_.resize(rows);
  for (Eigen::Index row = 0; row < rows; ++row) {
    const std::int64_t pair = contacts.pair[row];
    if (pair < 0 || pair >= finger_of_pair.size()) throw std::invalid_argument("a contact's pair is not the scene's");
    row_finger_[row] = finger_of_pair[pair];
    row_joint_[row] = joint_of_pair[pair];
  }
  return sense(row_finger_, row_joint_, contacts.point, contacts.normal, contacts.force);
}

namespace {

// bhgrasp.grasp.forces._torque_scale: the largest lever |d_i| = ||G_i[3:]||_F / sqrt(2), 1 if every lever is 0.
double torque_scale(const Rows& grasp) {
  double largest = 0.0;
  for (Eigen::Index i = 0; 3 * i < grasp.cols(); ++i)
    largest = std::max(largest, grasp.block<3, 3>(3, 3 * i).squaredNorm());
  const double lever = std::sqrt(largest) / std::sqrt(2.0);
  return lever > 0.0 ? lever : 1.0;
}

}  // namespace

int SMCAdaptiveLaw::grasp_free_body(const ConstVector& q, const ConstVector& v, const Vector7& object_q,
                                    const Vector6& object_v, double dt, const Eigen::Matrix3d& target_rotation,
                                    const Eigen::Vector3d& target_translation, const Vector6& velocity,
                                    const Vector6& acceleration, Eigen::Ref<Eigen::VectorXd> out) {
  // pin.XYZQUATToSE3: Eigen's quaternion (w, x, y, z) to its matrix, not normalised
  const Eigen::Matrix3d rotation =
      Eigen::Quaterniond(object_q[6], object_q[3], object_q[4], object_q[5]).toRotationMatrix();
  // Scene.object_twist: (v, R omega_body), each row of R omega summed left to right, as NumPy's R @ omega is under
  // OpenBLAS's Haswell kernels (CI pins them; its AVX-512 kernels fuse the multiply-adds: round-off apart there)
  Vector6 twist;
  twist.head<3>() = object_v.head<3>();
  for (int row = 0; row < 3; ++row)
    twist[3 + row] = (rotation(row, 0) * object_v[3] + rotation(row, 1) * object_v[4]) + rotation(row, 2) * object_v[5];
  return grasp(q, v, rotation, object_q.head<3>(), twist, dt, target_rotation, target_translation, velocity,
               acceleration, out);
}

int SMCAdaptiveLaw::grasp_free_body_on_path(const ConstVector& q, const ConstVector& v, const Vector7& object_q,
                                            const Vector6& object_v, double dt, const PosePath& path, double t,
                                            Eigen::Ref<Eigen::VectorXd> out) {
  Eigen::Matrix3d rotation;
  Eigen::Vector3d position;
  Vector6 twist, derivative;
  path.at(t, rotation, position, twist, derivative);
  return grasp_free_body(q, v, object_q, object_v, dt, rotation, position, twist, derivative, out);
}

int SMCAdaptiveLaw::grasp(const ConstVector& q, const ConstVector& v, const Eigen::Matrix3d& rotation,
                          const Eigen::Vector3d& translation, const Vector6& twist, double dt,
                          const Eigen::Matrix3d& target_rotation, const Eigen::Vector3d& target_translation,
                          const Vector6& velocity, const Vector6& acceleration, Eigen::Ref<Eigen::VectorXd> out) {
  const auto n = static_cast<Eigen::Index>(touching_.size());
  if (n < 1 || v.size() != nv_ || out.size() != log_size())
    throw std::invalid_argument("SMCAdaptiveLaw.grasp: a touching finger, v of size nv and out of log_size");
  const Eigen::Index F = fingers_;
  // out's blocks, in the order of smc_law.hpp
  auto tau = out.segment(0, nv_);
  auto object_error = out.segment<6>(nv_);
  auto wrench = out.segment<6>(nv_ + 6);
  const Eigen::Index scalars = nv_ + 12;  // feasible, infeasible_cycles, wrench_residual, qp_iterations, cone_margin
  auto commanded = out.segment(nv_ + 17, F);
  auto object_sliding = out.segment<6>(nv_ + 18 + F);
  auto joint_sliding = out.segment(nv_ + 24 + F, nv_);
  auto per_finger_error = out.segment(2 * nv_ + 24 + F, 3 * F);
  auto per_finger_desired = out.segment(2 * nv_ + 24 + 4 * F, 3 * F);
  auto parameters = out.segment<7>(2 * nv_ + 24 + 7 * F);

  // GraspContacts: points and frames of the touching fingers (contact_frames' check first, as the twin's)
  for (Eigen::Index k = 0; k < n; ++k) {
    const int f = touching_[static_cast<std::size_t>(k)];
    const Eigen::RowVector3d normal = sums_.normal.row(f);
    if (!(std::sqrt(normal.dot(normal)) >= zero_length_) || !normal.allFinite()) return bad_normal;
    points_.row(k) = sums_.point.row(f);
    frames_.middleRows<3>(3 * k) = contact_frame(normal, switch_x_);
  }
  // grasp_maps: P, P_dot, G, J_h, J_h^+ about the COM
  const GraspMaps& maps = kinematics_.compute(base_rotation_, base_translation_, q, translation, twist,
                                              points_.topRows(n), frames_.topRows(3 * n), joints_);
  // errors: e = (x - x_d, log(R R_d^T)), e_dot
  object_error.head<3>() = translation - target_translation;
  object_error.tail<3>() = pinocchio::log3((rotation * target_rotation.transpose()).eval());
  const Vector6 velocity_error = twist - velocity;
  const Vector6 v_r = velocity - rho_ * object_error, a_r = acceleration - rho_ * velocity_error;  // (5.46)
  object_sliding = twist - v_r;
  const auto regressor = object_regressor(rotation, twist.tail<3>(), v_r, a_r, gravity_);
  estimate_ -= ((dt * object_adaptation_).array() * (regressor.transpose() * object_sliding).array()).matrix();
  estimate_[0] = std::max(estimate_[0], 1e-3);  // projection: a mass stays positive
  wrench = regressor * estimate_ - k_o_.cwiseProduct(Vector6(object_sliding));
  if (!maps.grasp_map.allFinite()) return grasp_map_not_finite;
  if (!wrench.allFinite()) return wrench_not_finite;

  // distribute: the QP of this contact count, closest to the desired normals (the squeeze, or the grip below)
  ContactForceQP& solver = qp(static_cast<int>(n));
  if (!solver.holds(maps.grasp_map)) solver.set_grasp_map(maps.grasp_map, torque_scale(maps.grasp_map));
  // the measured forces in contact frames, R^T f as rows; with a friction margin the grip follows their tangential
  // load: desired normal max(squeeze, |f_t| / mu), mu the QP's (already less the margin)
  auto desired = desired_.head(3 * n);
  desired.setZero();
  for (Eigen::Index k = 0; k < n; ++k) {
    measured_.row(k).noalias() = sums_.force.row(touching_[static_cast<std::size_t>(k)]) * frames_.middleRows<3>(3 * k);
    desired[3 * k + 2] = squeeze_;
    if (grip_reflex_) {
      const double tangential = std::sqrt(measured_(k, 0) * measured_(k, 0) + measured_(k, 1) * measured_(k, 1));
      const double needed = tangential / mu_;  // np.maximum's: a NaN reading stays NaN, as in the twin
      desired[3 * k + 2] = (needed > squeeze_ || std::isnan(needed)) ? needed : squeeze_;
    }
  }
  const ForceResult& result = solver.solve(Vector6(wrench), desired);
  infeasible_cycles_ += !result.feasible;
  out[scalars] = result.feasible ? 1.0 : 0.0;
  out[scalars + 1] = infeasible_cycles_;
  out[scalars + 2] = result.wrench_residual;
  out[scalars + 3] = result.iterations;
  out[scalars + 4] = -result.cone_violation;
  commanded.setZero();
  const Rows& forces = result.forces;  // F_dc (n, 3), contact frames
  for (Eigen::Index k = 0; k < n; ++k) commanded[touching_[static_cast<std::size_t>(k)]] = forces(k, 2);
  out[nv_ + 17 + F] = static_cast<double>(n);

  // force errors in contact frames, their per-finger integrals (fingers not touching lose theirs)
  per_finger_error.setZero();
  per_finger_desired.setZero();
  std::vector<char>& has = has_integral_;
  for (Eigen::Index k = 0; k < n; ++k) {
    const int f = touching_[static_cast<std::size_t>(k)];
    force_error_.row(k) = forces.row(k) - measured_.row(k);
    if (normal_only_) force_error_.row(k).head<2>().setZero();
    const Eigen::RowVector3d previous = has[static_cast<std::size_t>(f)] ? Eigen::RowVector3d(integral_.row(f))
                                                                        : Eigen::RowVector3d::Zero();
    integral_.row(f) = previous + dt * force_error_.row(k);
    correction_.segment<3>(3 * k) =
        (force_gain_ * force_error_.row(k) + force_integral_ * integral_.row(f)).transpose();
    per_finger_error.segment<3>(3 * f) = force_error_.row(k).transpose();
    per_finger_desired.segment<3>(3 * f) = forces.row(k).transpose();
  }
  std::fill(has.begin(), has.end(), 0);
  for (int f : touching_) has[static_cast<std::size_t>(f)] = 1;

  // (5.57)-(5.59): q_dot_r, q_dd_r, s_f, and (5.58) with the fixed hand model
  q_dot_r_.noalias() = maps.joint_map * v_r;
  q_dot_r_.noalias() += maps.hand_jacobian_pinv * correction_.head(3 * n);
  q_dd_r_.noalias() = maps.joint_map * a_r;
  q_dd_r_.noalias() += maps.joint_map_rate * v_r;
  s_f_ = v - q_dot_r_;
  joint_sliding = s_f_;
  const Eigen::VectorXd& model = dynamics_.slotine_li_torque(model_gravity_, q, v, q_dot_r_, q_dd_r_);
  tau_ = model;
  tau_.noalias() += maps.hand_jacobian.transpose() * Eigen::Map<const Eigen::VectorXd>(forces.data(), 3 * n);
  tau_ -= k_f_.cwiseProduct(s_f_);
  tau = tau_;
  parameters = estimate_;
  return tau_.allFinite() ? ok : torque_not_finite;
}

}  // namespace bhgrasp
