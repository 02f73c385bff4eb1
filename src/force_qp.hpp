// The internal-force QP of the grasp laws: contact forces f that exert an object wrench w inside the friction
// pyramids, closest to desired forces f_d, or the nearest admissible forces when none do, on proxsuite's C++ API.
//
// The Python twin is bhgrasp.grasp.forces.ContactForceQP (its module docstring states the QP, the nearest problem,
// the check of a doubtful infeasibility certificate, the warm starts, the last active set's optimum tried first and
// the iteration bound); solve() mirrors its state machine line for line, named alike, with the same three proxsuite
// dense problems and settings.  tests/test_force_qp_twin.py checks both agree cycle by cycle.  Forces in contact
// frames (t1, t2, n) [N].
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Core>

namespace bhgrasp {

using Rows = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;  // as batch.hpp's
using Vector6 = Eigen::Matrix<double, 6, 1>;

// The constants of bhgrasp/grasp/_force_qp.py (the bindings expose them; the twin test asserts they are equal).
struct ForceQPConstants {
  static constexpr double nearest_weight = 1e4;         // NEAREST_WEIGHT, W of the nearest problem
  static constexpr double primal_infeasibility = 1e-6;  // PRIMAL_INFEASIBILITY, eps_primal_inf of the QP
  static constexpr double doubtful_error = 0.1;         // DOUBTFUL_ERROR
  static constexpr double duality_gap_rel = 1e-12;      // DUALITY_GAP_REL
  static constexpr double feasible_residual = 1e-6;     // FEASIBLE_RESIDUAL
  static constexpr double admissible_tolerance = 1e-7;  // ADMISSIBLE_TOLERANCE [N]
  static constexpr int check_iter = 4;                  // ContactForceQP.CHECK_ITER
  static constexpr double active_tolerance = 1e-8;      // ACTIVE_TOLERANCE [N], a solved row at its bound (or 10 eps)
  static constexpr double full_rank = 1e-6;             // FULL_RANK, least / largest diagonal of M M^T's factor L
};

// One solve (bhgrasp.grasp.forces.ContactForceResult, same fields in the same order).
struct ForceResult {
  Rows forces;                   // (n, 3) [N], inside the pyramids and normal bounds
  bool feasible = false;         // the wrench is met
  double wrench_residual = 0.0;  // |G f - w| [N, N m]
  double cone_violation = 0.0;   // max_i |f_t,i| - mu f_n,i [N], exact cone
  double normal_margin = 0.0;    // min_i f_n,i - f_min [N]
  const char* status = "PROXQP_NOT_RUN";  // proxsuite's status name for the QP itself, or PROXQP_NOT_FINITE
  int iterations = 0;            // proxsuite's (inner) iterations summed over the solves of the call
  Vector6 wrench_error;          // G f - w
};

class ContactForceQP {
 public:
  using ConstVector = Eigen::Ref<const Eigen::VectorXd>;
  using ConstRows = Eigen::Ref<const Rows>;

  // n contacts, friction coefficient mu, `pyramid` the (facets, 3) rows of bhgrasp.grasp.cones.friction_pyramid,
  // `inscribed` = mu cos(pi / facets) (the inscribed cone of _admissible), f_min [N], proxsuite's eps_abs, and the
  // outer and inner iteration limits.  Everything is allocated here; solve() allocates nothing of its own.
  ContactForceQP(int n_contacts, double mu, const ConstRows& pyramid, double inscribed, double min_normal_force,
                 double tolerance, int max_iter, int max_iter_in);
  ~ContactForceQP();
  ContactForceQP(const ContactForceQP&) = delete;
  ContactForceQP& operator=(const ContactForceQP&) = delete;

  // Whether `grasp` (6, 3n) equals, entry for entry, the grasp map last set (the twin's np.array_equal test).
  bool holds(const ConstRows& grasp) const;
  // A new grasp map and its torque scale r (bhgrasp.grasp.quality.default_torque_scale): the rows of S G f = S w.
  void set_grasp_map(const ConstRows& grasp, double torque_scale);
  // The forces for wrench w (6,) [N, N m] closest to `desired` f_d (3n,), for the grasp map last set.  The result
  // lives in this object until the next call.  Sizes are checked (std::invalid_argument); values are not.
  const ForceResult& solve(const Vector6& wrench, const ConstVector& desired);

  int n_contacts() const { return n_; }

 private:
  enum class Warm { scratch, previous, point };  // the twin's warm: False, True, a primal-dual point (x, y, z)
  struct Run {
    const char* status;
    bool solved;
    int iterations;
  };
  struct Solvers;  // the three proxsuite problems (force_qp.cpp), kept out of this header

  template <class Problem>
  Run run(Problem& qp, Warm warm, const Rows& hessian, const Eigen::VectorXd& gradient, const Rows& equality,
          const Rows& inequality);
  int nearest_forces(const ConstVector& desired, bool& doubtful);  // into nearest_; returns iterations
  bool active_set_forces(const ConstVector& desired);  // the last active set's optimum into active_forces_
  void remember_active(const Eigen::VectorXd& forces, const Eigen::VectorXd& multipliers);
  void admissible(Eigen::Ref<Eigen::VectorXd> forces) const;
  const ForceResult& result(const Vector6& wrench, const Eigen::VectorXd& forces, const char* status,
                            int iterations);

  int n_, facets_;
  double mu_, inscribed_, min_normal_force_, tolerance_;
  std::unique_ptr<Solvers> solvers_;
  Rows hessian_, inequality_, nearest_hessian_, nearest_inequality_;  // H, C and their nearest-problem forms
  Eigen::VectorXd lower_, upper_;
  bool has_grasp_map_ = false;
  Rows grasp_map_, equality_, nearest_equality_;  // G, A = S G, [S G, -I]
  Vector6 rows_;                                  // diag(S)
  Vector6 b_;                                     // S w
  Eigen::VectorXd gradient_, nearest_gradient_;   // -f_d, (-f_d, 0)
  Warm warm_ = Warm::scratch;
  bool warm_nearest_ = false, infeasible_ = false;
  Eigen::VectorXd warm_x_, warm_y_, warm_z_;  // the check's solution, the QP's next start
  Eigen::VectorXd nearest_, x_;               // the nearest problem's forces, the QP's (or the check's) x
  Vector6 miss_;                              // A f - b of the nearest forces
  Eigen::VectorXd pyramid_values_;            // C_pyramid f
  // the active set of the last solved call: rows of C at a bound, and the bound (+1 upper, -1 lower)
  std::vector<Eigen::Index> active_;
  std::vector<double> active_side_;
  bool has_active_ = false;
  double active_tolerance_ = 0.0;              // max(ACTIVE_TOLERANCE, 10 eps_abs)
  Eigen::VectorXd active_forces_;              // the active set's forces
  Rows system_;                                // [A; C_active] (6 + k, 3n)
  Eigen::MatrixXd gram_;                       // its Gram matrix, factorised in place
  Eigen::VectorXd bounds_, lambda_, residual_;  // [b; bounds], the multipliers, M f - [b; bounds]
  Eigen::VectorXd values_;                       // C f
  ForceResult result_;
};

}  // namespace bhgrasp
