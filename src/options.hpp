// The option structs the Python side fills for the compiled engine, each declared once: one field list per struct
// declares its members (value-initialised: the defaults live in Python, which fills every field), binds them
// (def_rw) and lists them as the class's FIELDS, which bhgrasp/sim/native_options.py checks when it fills one (a
// field added here and not filled there is an error naming it, not a silent zero).
#pragma once

#include <array>
#include <type_traits>
#include <vector>

#include <Eigen/Core>

namespace bhgrasp {

using Vector = Eigen::VectorXd;
using Matrix = Eigen::MatrixXd;
using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;  // NumPy's layout
using Vector3 = Eigen::Vector3d;
using Matrix3 = Eigen::Matrix3d;
using IntList = std::vector<int>;
using FingerJoints = std::array<int, 3>;  // one hand joint index per finger F1, F2, F3

// A member's value before Python fills it: zero, empty or false (fixed-size Eigen types too, which `{}` leaves
// uninitialised).
template <class T>
T initial() {
  if constexpr (std::is_base_of_v<Eigen::EigenBase<T>, T>) {
    if constexpr (T::SizeAtCompileTime != Eigen::Dynamic) return T::Zero();
  }
  return T{};
}

#define BHGRASP_DECLARE(type, name) type name = initial<type>();

// The contact force law (bhgrasp.sim.contact_law.SpringDamper): k [N/m] (Hunt-Crossley [N/m^e]), c [N s/m], k_t
// [N/m], c_t [N s/m], the Hunt-Crossley normal law and its exponent e, the tanh friction law and its v_s [m/s], and
// the radius [m] within which contacts match last step's on body b.
#define BHGRASP_CONTACT_LAW(X)                                                                                  \
  X(double, stiffness) X(double, damping) X(double, tangential_stiffness) X(double, tangential_damping)        \
  X(bool, hunt_crossley) X(double, exponent) X(bool, tanh_friction) X(double, slip_velocity)                   \
  X(double, match_radius)
struct ContactLaw {
  BHGRASP_CONTACT_LAW(BHGRASP_DECLARE)
};

// One collision pair (bhgrasp.sim.scene.CollisionPair): geometry indices, the joints carrying the bodies (0: the
// world or the fixed palm), the pair's Coulomb coefficient; forces act on body b along the normal from a to b.
#define BHGRASP_PAIR(X) X(int, geom_a) X(int, geom_b) X(int, joint_a) X(int, joint_b) X(double, friction)
struct Pair {
  BHGRASP_PAIR(BHGRASP_DECLARE)
};

// A free body's first angular velocity coordinate in v, principal axes (columns, body frame) and moments [kg m^2],
// for the implicit-midpoint gyroscopic torque (bhgrasp.sim.scene_layout.SceneLayout.spinning_bodies).
#define BHGRASP_SPINNING(X) X(int, angular) X(Matrix3, axes) X(Vector3, moments)
struct Spinning {
  BHGRASP_SPINNING(BHGRASP_DECLARE)
};

// Every pair's collision and contact-patch queries (coal's CollisionRequest and ContactPatchRequest of the scene's
// geometry data; bhgrasp.sim.contact): GJK/EPA tolerance, and the looser one of the retry (contact.py's
// _NARROW_TOLERANCE and _FALLBACK_TOLERANCE).
#define BHGRASP_QUERY(X)                                                                                        \
  X(int, num_max_contacts) X(double, security_margin) X(double, break_distance) X(double, tolerance)            \
  X(double, fallback_tolerance) X(int, max_num_patch) X(int, num_samples_curved_shapes) X(double, patch_tolerance)
struct Query {
  BHGRASP_QUERY(BHGRASP_DECLARE)
};

// Everything fixed for a simulator (bhgrasp.sim.settings.SimulatorSettings and the scene's layout): dt [s], the
// integrator (0 implicit, 1 semi-implicit, 2 RK4), the hand's sizes and joint limits [rad], its stops [N m/rad,
// N m s/rad], the largest |q_i| [m or rad], the springs of spring-mounted objects [N/m, N s/m] and their
// coordinates, the free bodies, the pairs, the contact law, the pairs' query, and whether the implicit step solves
// its velocity system by parts (part_system.hpp) or as one dense matrix.
#define BHGRASP_SETTINGS(X)                                                                                     \
  X(double, dt) X(int, integrator) X(int, nq_hand) X(int, nv_hand) X(Vector, lower) X(Vector, upper)            \
  X(double, limit_stiffness) X(double, limit_damping) X(double, max_coordinate) X(Vector, joint_stiffness)      \
  X(Vector, joint_damping) X(IntList, spring_q) X(IntList, spring_v) X(std::vector<Spinning>, spinning)         \
  X(std::vector<Pair>, pairs) X(ContactLaw, law) X(Query, query) X(bool, sparse)
struct Settings {
  BHGRASP_SETTINGS(BHGRASP_DECLARE)
};

// The actuation of one step (bhgrasp.sim.engine.DriveTerms): T (nv_hand, n_driven) with v_hand = T w, the passive +
// drive damping [N m s/rad], Coulomb joint friction [N m], and the drive's own damping, (nv_hand,) each.
#define BHGRASP_DRIVE(X) X(Matrix, transmission) X(Vector, joint_damping) X(Vector, friction) X(Vector, motor_damping)
struct Drive {
  BHGRASP_DRIVE(BHGRASP_DECLARE)
};

// The BH8-280's drive (bhgrasp.sim.actuation.BarrettActuation): hand joint indices of the spreads and of each
// finger's proximal and distal joints, the motor : joint ratios, the motor torque clip [N m] (when `saturate`), the
// TorqueSwitch's breakaway torque [N m], the motor damping [N m s/rad], the worms' forward efficiency and
// self-locking, per hand joint the passive damping, Coulomb friction and lower limit, and the joints driven directly
// by inputs 4, 5, ... (e.g. a wrist mount's; none on a bare hand).
#define BHGRASP_BARRETT(X)                                                                                      \
  X(int, nv_hand) X(int, spread_first) X(int, spread_second) X(FingerJoints, proximal) X(FingerJoints, distal)  \
  X(double, spread_ratio) X(double, proximal_ratio) X(double, distal_ratio) X(double, distal_alone_ratio)       \
  X(double, max_motor_torque) X(double, breakaway_torque) X(double, motor_damping) X(double, efficiency)         \
  X(bool, saturate) X(bool, self_locking) X(Vector, damping) X(Vector, friction) X(Vector, lower)        \
  X(IntList, direct)
struct Barrett {
  BHGRASP_BARRETT(BHGRASP_DECLARE)
};

}  // namespace bhgrasp
