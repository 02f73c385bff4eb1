// The compiled simulation step of bhgrasp: contact detection (coal), the spring-damper + stick-slip contact law,
// and the implicit, semi-implicit and RK4 integrators of bhgrasp.sim.Simulator, on Pinocchio's C++ API.
//
// The Python engine (bhgrasp/sim/python_engine.py, contact.py, contact_law.py) is the readable reference: every
// function here mirrors one there, named alike, and tests/test_compiled.py steps both in lockstep.  Units SI, world
// frame; arrays of points are (m, 3) row-major, as NumPy's.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include <coal/collision_data.h>
#include <pinocchio/geometry.hpp>
#include <pinocchio/multibody.hpp>

#include "decompositions.hpp"
#include "options.hpp"
#include "part_jacobian.hpp"
#include "scene_parts.hpp"

namespace bhgrasp {

using Points = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;  // (m, 3)
using Indices = Eigen::Matrix<std::int64_t, Eigen::Dynamic, 1>;
using Flags = Eigen::Matrix<bool, Eigen::Dynamic, 1>;

// What a run carries from one step to the next about its contacts (bhgrasp.data.contacts.ContactMemory).
struct Memory {
  Indices pair;
  Points local_b;
  Points displacement;
  Flags sliding;
};

// The contacts of one instant (bhgrasp.data.contacts.ContactSet).
struct Contacts {
  Indices pair;
  Points point, normal;
  Vector depth, friction;
  Points displacement;  // tangential spring displacement at the start of the step [m]
  Vector weight;        // 1 / (points in the patch)
  Points local_b;       // points in body b's joint frame [m]
  Points force;         // on body b [N]
  Flags sticking, was_sliding;
  Eigen::Index size() const { return pair.size(); }
  void resize(Eigen::Index m);
};

// Why a step was declared diverged (0: it was not); Python raises SimulationDiverged with these.
struct Divergence {
  // 1 position not finite, 2 velocity not finite, 3 speed above max_speed, 4 depth above max_penetration,
  // 5 coordinate beyond max_coordinate
  int kind = 0;
  int index = -1;     // the first offending coordinate (-1: a contact depth)
  double value = 0.0; // what it held
};

struct StepResult {
  Vector q, v;
  Contacts contacts;
  Memory memory;
  Vector drive;  // hand joint torques the drive delivered [N m]
  Vector load;   // drive less the hand links' own inertial torques M a [N m] (what a clutch passes)
  Divergence divergence;
};

class PartSystem;
class Narrowphase;

// The largest gap [m] between the projections of two boxes (half sides [m], placements in the world) onto the 15
// axes of the separating-axis test: a lower bound of their distance; <= 0 when no axis separates them.
double box_separation(const Vector3& half_a, const pinocchio::SE3& placement_a, const Vector3& half_b,
                      const pinocchio::SE3& placement_b);

class Engine {
 public:
  // `model` and `geometry`: Pinocchio's text serialisations (Model.saveToString, GeometryModel.saveToString).
  Engine(const std::string& model, const std::string& geometry, Settings settings);
  ~Engine();

  // Advance dt from (q, v) with hand joint torques tau_hand [N m] (or nv generalized forces: hand torques, then
  // external forces on the objects' coordinates); max_speed/max_penetration bound divergence.
  StepResult step(const Vector& q, const Vector& v, const Vector& tau_hand, const Drive& drive, const Memory& memory,
                  double max_speed, double max_penetration);

  // The contacts at q, matched to memory (runs forward kinematics).
  Contacts detect(const Vector& q, const Memory& memory);

  // Hand-joint gravity torques G(q) [N m], (nv_hand,) (runs its own pass; for batched controllers).
  Vector gravity(const Vector& q);

  // Translational world-aligned Jacobians of frames at q, rows 3 f .. 3 f + 2 for frame f: (3 n, nv_hand).
  Matrix frame_jacobians(const Vector& q, const std::vector<int>& frames);

  // Whether contact detection keeps one coal solver between queries (the default with the coal it was checked
  // against) or, as the reference it is tested against, lets coal::collide make one per query; the contacts are the
  // same to the bit.  Not to be changed while another thread steps this engine.
  bool kept_solver() const;
  void set_kept_solver(bool kept);

  // Whether a pair of boxes is skipped when an axis of the separating-axis test holds them apart (box_separation;
  // the default); off, as the reference it is tested against, the narrow phase asks coal.  The same contacts.
  bool box_axes = true;
  std::int64_t box_axes_skipped = 0;  // the pairs it skipped, since the engine was made

  int nq() const { return model_.nq; }
  int nv() const { return model_.nv; }

 private:
  struct Parts {  // linear_parts: f0 and D of the normal law alone and with the stick spring
    Points f0, f0_stick;
    std::vector<Matrix3> gains, gains_stick;
  };
  struct Passive {
    Vector torque, stiffness, damping;
  };
  struct Acceleration {
    Vector acceleration;
    Contacts contacts;
    Points displacement;
    Vector drive, load;
  };

  // Work arrays, kept from step to step so that a step allocates only the arrays it returns.  Each is sized by the
  // first step that uses it; arrays with a row or an entry per contact only grow and hold at least as many as the step
  // has contacts (the rest are stale).  No value is carried from one step to the next.
  struct Work {
    // detect: the candidate points before the depth test; one patch's points, one array per patch size (so that
    // point_depths' centroid sums exactly the patch's points) and depths
    std::vector<std::int64_t> pair;
    std::vector<Vector3> point, normal;
    std::vector<double> depth, weight, patch_depths;
    std::vector<Points> patch_points;
    // broad_phase: the candidate pairs; the sweep's geometries in order, their bounding spheres' world centres and
    // lowest points along the sweep's axis
    std::vector<int> candidate, order;
    std::vector<double> low;
    std::vector<Vector3> centre;
    // joint space (implicit_step, step)
    Vector tau, bias, implicit_damping, rhs, rhs_c, v_next, contact_torque, product, acceleration, delivered;
    Vector increment;
    Matrix mass, matrix, matrix_c, transmission;
    Passive passive;
    // contacts (implicit_step): relative point Jacobians, one contact's J v and D J, the active set
    std::vector<Matrix> jacobian;
    Vector velocity;
    Eigen::Matrix<double, 3, Eigen::Dynamic> gain_jacobian;
    Parts parts;
    Points start_velocity, relative, forces, slide, new_slide, f0;
    std::vector<Matrix3> gains;
    std::vector<int> status, new_status;
    Flags may_stick;
    // the implicit step by parts (settings_.sparse): the parts' blocks of M and of A = M + dt (dt K + C), their first
    // velocities, the contacts' Jacobians by parts
    std::vector<Matrix> mass_blocks, system_blocks;
    std::vector<Eigen::Index> part_first;
    std::vector<PartJacobian> part_jacobian;
    // reduced_solve
    Eigen::LLT<Matrix> cholesky;
    Matrix half, reduced;
    Vector right, reduced_solution;
  };

  void broad_phase(std::vector<int>& result);
  void point_depths(int pair, const Points& points, const Vector3& normal, std::vector<double>& depths);
  double signed_distance(int geom, const Vector3& point);
  void recall(Contacts& contacts, const Memory& memory) const;
  void jacobians(const Contacts& contacts, std::vector<Matrix>& result);
  void part_jacobians(const Contacts& contacts, std::vector<PartJacobian>& result);
  template <class Add>
  void point_jacobians(const Contacts& contacts, Eigen::Index i, Add add);  // detect.cpp
  void mass_times(const Vector& x, Vector& result) const;  // M x, dense or by parts as the step runs
  void linear_parts(const Contacts& contacts, Parts& parts) const;
  void start_status(const Contacts& contacts, const Parts& parts, const Points& start_velocity,
                    std::vector<int>& status, Points& slide) const;
  void classify(const Contacts& contacts, const Points& forces, const std::vector<int>& status,
                const Points& start_velocity, const Points& relative, const Flags& may_stick,
                std::vector<int>& new_status, Points& slide) const;
  void contact_forces(Contacts& contacts, const Points& velocity, Points& displacement) const;
  void passive(const Vector& q, const Vector& v, const Drive& drive, Passive& result) const;
  void mass_matrix(const Vector& q, Matrix& mass);
  void transmission(const Drive& drive, Matrix& full) const;
  void reduced_solve(const Matrix& transmission, const Matrix& matrix, const Vector& rhs, Vector& solution);
  void implicit_gyroscopic(const Vector& v, Vector& bias) const;
  Vector increment_rate(const Vector& increment, const Vector& v) const;
  void implicit_step(const Vector& q, const Vector& v, const Vector& tau, const Drive& drive, const Memory& memory,
                     StepResult& result);
  Acceleration acceleration(const Vector& q, const Vector& v, const Vector& tau, const Matrix& transmission,
                            const Drive& drive, const Memory& memory, bool gyroscopic);
  Vector integrate(const Vector& q, const Vector& v) const;

  pinocchio::Model model_;  // the whole scene's: its layout and integration; its dynamics run on parts_
  SceneParts parts_;
  std::unique_ptr<PartSystem> system_;  // the velocity system by parts (settings_.sparse)
  pinocchio::GeometryModel geometry_;
  pinocchio::GeometryData geometry_data_;
  Settings settings_;
  coal::CollisionRequest request_;
  coal::CollisionRequest fallback_request_;  // coal's default tolerance, for an EPA that stopped short
  coal::ContactPatchRequest patch_request_;
  coal::CollisionResult result_;  // one pair's, cleared before each query
  coal::ContactPatchResult patch_result_;
  std::unique_ptr<Narrowphase> narrowphase_;  // coal::collide on a kept solver (narrowphase.hpp)
  std::shared_ptr<coal::CollisionGeometry> probe_;
  std::vector<double> bound_radius_;  // per geometry: radius [m] of a sphere about bound_centre_ holding the shape
  std::vector<Vector3> bound_centre_; // in the geometry's frame; radius inf: unbounded (half-spaces)
  std::vector<const coal::Box*> box_;  // per geometry: its box, or null (another shape, or a box with a swept sphere)
  double box_slack_ = 0.0;             // [m] the gap beyond the security margin that skips two boxes (engine.cpp)
  static constexpr int kSweepFrom = 128;  // pairs from which the broad phase sweeps (fewer: every pair is tested)
  // per geometry g: (geometry h > g, pair index) of its pairs with bounded geometries after it, sorted
  std::vector<std::vector<std::pair<int, int>>> partners_;
  std::vector<int> always_;                         // the pairs of an unbounded shape
  double sweep_margin_ = 0.0;                       // [m] the security margin, and a hair
  Work work_;
};

}  // namespace bhgrasp
