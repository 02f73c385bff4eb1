// The SMC-adaptive grasp law of thesis (5.46)-(5.60) in one call per control cycle, on the grasp kernels' C++ API.
//
// The Python twin is SMCAdaptiveGrasp with engine="python" (bhgrasp/controllers/adaptive_grasp.py, on
// ObjectGraspController in bhgrasp/controllers/grasping.py; their docstrings state the maths); sense() and grasp()
// mirror ObjectGraspController.__call__ and SMCAdaptiveGrasp.grasp_torques line for line, named alike, through the
// same kernels: finger_contacts and contact_frame (sensing.cpp), GraspKinematics (grasp.cpp), object_regressor,
// ContactForceQP (force_qp.cpp) and HandDynamics (dynamics.cpp).  tests/test_smc_law_twin.py holds the two in
// lockstep.  A minimum-jerk pose reference can be sampled in the grasp call (pose_path.cpp; grasp_free_body_on_path);
// any other reference, the hold pose, the clock and the approach branch stay in Python.  Units SI, world frame.
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Core>

#include "dynamics.hpp"
#include "force_qp.hpp"
#include "grasp.hpp"
#include "pose_path.hpp"
#include "sensing.hpp"

namespace bhgrasp {

using Vector7 = Eigen::Matrix<double, 7, 1>;

// What grasp() returns: ok, or the check of the Python twin that would have raised.
enum LawStatus : int {
  ok = 0,
  bad_normal = 1,            // a touching finger's normal is zero or not finite (contact_frames raises)
  grasp_map_not_finite = 2,  // G is not finite (ContactForceQP.solve raises)
  wrench_not_finite = 3,     // the wrench is not finite (ContactForceQP.solve raises)
  torque_not_finite = 4,     // the torques are not finite (ObjectGraspController.__call__ raises)
};

class SMCAdaptiveLaw {
 public:
  using ConstVector = Eigen::Ref<const Eigen::VectorXd>;

  // The hand's kinematics and dynamics kernels (shared with the hand's other users, kept alive by the caller) and
  // its number of fingers F.  Nothing else is allocated until configure().
  SMCAdaptiveLaw(GraspKinematics& kinematics, HandDynamics& dynamics, int fingers);
  SMCAdaptiveLaw(const SMCAdaptiveLaw&) = delete;
  SMCAdaptiveLaw& operator=(const SMCAdaptiveLaw&) = delete;

  // The gains of SMCAdaptiveGrasp (k_f of size nv), the QP's arguments as ContactForceQP takes them (mu: the
  // design mu, GraspOptions.design_mu), whether the grip follows the measured load (a friction margin is set), and
  // bhgrasp.grasp.frames' ZERO_NORMAL and TANGENT_SWITCH; then reset().
  void configure(double rho, const Vector6& k_o, const Vector7& object_adaptation, double force_gain,
                 double force_integral, const ConstVector& k_f, bool normal_only, double squeeze, bool grip_reflex,
                 const Eigen::Vector3d& gravity, const Vector7& initial_estimate, double mu, const Rows& pyramid,
                 double inscribed, double min_normal_force, double tolerance, int max_iter, int max_iter_in,
                 double zero_length, double switch_x);
  // SMCAdaptiveGrasp.reset: the estimate from its initial value, no force integrals, no QPs, no infeasible cycle.
  void reset();
  // The hand's base placement (world <- model) and the gravity in the model frame (Hand._model_gravity).
  void set_base(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation, const Eigen::Vector3d& gravity);

  // The contacts by finger (ContactSensing.fingers) of the rows `finger` (-1: none), `joint` (the Pinocchio joint of
  // each row's hand link), points, normals and forces (m, 3); returns the number of touching fingers.
  int sense(const ConstIndices& finger, const ConstIndices& joint, const ConstPoints& points,
            const ConstPoints& normals, const ConstPoints& forces);
  // sense() on a step's contacts as the engine returned them: each row's finger and joint by its collision pair
  // (`finger_of_pair`, `joint_of_pair`: one entry per pair of the scene; std::invalid_argument on a pair beyond them).
  int sense_contacts(const Contacts& contacts, const ConstIndices& finger_of_pair, const ConstIndices& joint_of_pair);

  // One grasp cycle for the touching fingers of the last sense() (>= 1): joint state q, v, object pose (rotation,
  // translation of the COM) and twist, dt [s] since the last grasp cycle, the target pose, twist and its rate.
  // Writes `out` (log_size()): tau (nv) | object_error (6) | wrench (6) | feasible | infeasible_cycles |
  // wrench_residual | qp_iterations | cone_margin | commanded_normal (F) | contacts | object_sliding (6) |
  // joint_sliding (nv) | force_error (F, 3) | desired_force (F, 3) | object_parameters (7).  No allocation except
  // a QP's on the first cycle with a contact count (as the twin's dict of QPs).
  int grasp(const ConstVector& q, const ConstVector& v, const Eigen::Matrix3d& rotation,
                  const Eigen::Vector3d& translation, const Vector6& twist, double dt,
                  const Eigen::Matrix3d& target_rotation, const Eigen::Vector3d& target_translation,
                  const Vector6& velocity, const Vector6& acceleration, Eigen::Ref<Eigen::VectorXd> out);

  // grasp() with the object's pose and twist as a simulated scene holds its free body (bhgrasp.sim.scene.Scene's
  // object_pose and object_twist, the same operations): `object_q` = COM position and unit quaternion (x, y, z, w),
  // `object_v` = COM velocity (world-aligned) and angular velocity (body frame).  A state read this way needs no
  // pin.SE3 built in Python per cycle.
  int grasp_free_body(const ConstVector& q, const ConstVector& v, const Vector7& object_q, const Vector6& object_v,
                      double dt, const Eigen::Matrix3d& target_rotation, const Eigen::Vector3d& target_translation,
                      const Vector6& velocity, const Vector6& acceleration, Eigen::Ref<Eigen::VectorXd> out);
  // grasp_free_body() toward the pose of `path` at t [s], with its twist and the twist's rate (PosePath::at).
  int grasp_free_body_on_path(const ConstVector& q, const ConstVector& v, const Vector7& object_q,
                              const Vector6& object_v, double dt, const PosePath& path, double t,
                              Eigen::Ref<Eigen::VectorXd> out);

  Vector7 object_estimate() const { return estimate_; }
  void set_object_estimate(const Vector7& estimate) { estimate_ = estimate; }
  Eigen::Index log_size() const { return 2 * nv_ + 7 * fingers_ + 31; }

 private:
  ContactForceQP& qp(int count);

  GraspKinematics& kinematics_;
  HandDynamics& dynamics_;
  Eigen::Index nv_, fingers_;
  // settings (configure)
  double rho_ = 0.0, force_gain_ = 0.0, force_integral_ = 0.0, squeeze_ = 0.0, mu_ = 0.0, inscribed_ = 0.0;
  double min_normal_force_ = 0.0, tolerance_ = 0.0, zero_length_ = 0.0, switch_x_ = 0.0;
  int max_iter_ = 1, max_iter_in_ = 1;
  bool normal_only_ = true, grip_reflex_ = false;
  Vector6 k_o_ = Vector6::Zero();
  Vector7 object_adaptation_ = Vector7::Zero(), initial_estimate_ = Vector7::Zero();
  Eigen::VectorXd k_f_;
  Eigen::Vector3d gravity_ = Eigen::Vector3d::Zero();
  Rows pyramid_;
  Eigen::Matrix3d base_rotation_ = Eigen::Matrix3d::Identity();
  Eigen::Vector3d base_translation_ = Eigen::Vector3d::Zero(), model_gravity_ = Eigen::Vector3d::Zero();
  // state between cycles
  Vector7 estimate_ = Vector7::Zero();
  Points integral_;                   // (F, 3) eta per finger
  std::vector<char> has_integral_;    // the twin's dict keys: the fingers that touched in the last grasp cycle
  std::vector<std::unique_ptr<ContactForceQP>> qps_;  // by contact count
  int infeasible_cycles_ = 0;
  // the last sense()
  FingerSums sums_;
  FingerWork work_;
  Indices row_finger_, row_joint_;      // sense_contacts: each contact row's finger and joint
  std::vector<int> touching_, joints_;  // touching fingers in hand order, the joint of each one's strongest contact
  // work arrays, sized for F contacts once
  Rows points_, frames_;                          // (F, 3), (3F, 3)
  Eigen::VectorXd desired_, correction_, q_dot_r_, q_dd_r_, s_f_, tau_;
  Points measured_, force_error_;                 // (F, 3)
};

}  // namespace bhgrasp
