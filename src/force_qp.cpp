// The internal-force QP: see force_qp.hpp.  solve() mirrors bhgrasp.grasp.forces.ContactForceQP.solve line for line;
// the comments and the module docstring there explain the problems and the state machine.
#include "force_qp.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/Cholesky>
#include <proxsuite/proxqp/dense/dense.hpp>

namespace bhgrasp {

namespace {

using Problem = proxsuite::proxqp::dense::QP<double>;
using MatRef = proxsuite::proxqp::dense::MatRef<double>;
using VecRef = proxsuite::proxqp::dense::VecRef<double>;
using proxsuite::proxqp::InitialGuessStatus;
using proxsuite::proxqp::QPSolverOutput;

constexpr const char* kSolved = "PROXQP_SOLVED";
constexpr const char* kPrimalInfeasible = "PROXQP_PRIMAL_INFEASIBLE";

// QPSolverOutput's Python names (proxsuite's bindings export the enum under them).
const char* status_name(QPSolverOutput status) {
  switch (status) {
    case QPSolverOutput::PROXQP_SOLVED: return kSolved;
    case QPSolverOutput::PROXQP_MAX_ITER_REACHED: return "PROXQP_MAX_ITER_REACHED";
    case QPSolverOutput::PROXQP_PRIMAL_INFEASIBLE: return kPrimalInfeasible;
    case QPSolverOutput::PROXQP_SOLVED_CLOSEST_PRIMAL_FEASIBLE: return "PROXQP_SOLVED_CLOSEST_PRIMAL_FEASIBLE";
    case QPSolverOutput::PROXQP_DUAL_INFEASIBLE: return "PROXQP_DUAL_INFEASIBLE";
    case QPSolverOutput::PROXQP_NOT_RUN: return "PROXQP_NOT_RUN";
  }
  return "PROXQP_NOT_RUN";
}

// The Python constructor proxsuite.proxqp.dense.QP(size, 6, rows): its defaults spelled out.
Problem make(Eigen::Index size, Eigen::Index rows) {
  using proxsuite::proxqp::DenseBackend;
  using proxsuite::proxqp::HessianType;
  return Problem(size, 6, rows, false, HessianType::Dense, DenseBackend::Automatic);
}

// _make: the settings of every problem.
void configure(Problem& qp, double tolerance, double primal_infeasibility, int max_iter, int max_iter_in) {
  auto& settings = qp.settings;
  settings.eps_abs = tolerance;
  settings.eps_rel = 0.0;
  settings.check_duality_gap = true;  // without the gap test the forces are only within ~3e-7 N of the optimum
  settings.eps_duality_gap_abs = tolerance;
  settings.eps_duality_gap_rel = ForceQPConstants::duality_gap_rel;
  settings.eps_primal_inf = primal_infeasibility;
  settings.verbose = false;
  settings.max_iter = max_iter;
  settings.max_iter_in = max_iter_in;
}

}  // namespace

struct ContactForceQP::Solvers {
  Problem qp, check, nearest;
};

ContactForceQP::ContactForceQP(int n_contacts, double mu, const ConstRows& pyramid, double inscribed,
                               double min_normal_force, double tolerance, int max_iter, int max_iter_in)
    : n_(n_contacts), facets_(static_cast<int>(pyramid.rows())), mu_(mu), inscribed_(inscribed),
      min_normal_force_(min_normal_force), tolerance_(tolerance) {
  if (n_ < 1 || facets_ < 1 || pyramid.cols() != 3 || max_iter < 1 || max_iter_in < 1)
    throw std::invalid_argument("ContactForceQP: n_contacts >= 1, a (facets, 3) pyramid and iteration limits >= 1");
  const Eigen::Index size = 3 * n_, rows = n_ * (facets_ + 1);
  const double inf = std::numeric_limits<double>::infinity();
  inequality_.setZero(rows, size);
  lower_.setConstant(rows, -inf);
  upper_.setZero(rows);
  for (Eigen::Index i = 0; i < n_; ++i) {
    inequality_.block(i * facets_, 3 * i, facets_, 3) = pyramid;
    const Eigen::Index row = n_ * facets_ + i;
    inequality_(row, 3 * i + 2) = 1.0;
    lower_[row] = min_normal_force_;
    upper_[row] = inf;
  }
  hessian_.setIdentity(size, size);
  solvers_.reset(new Solvers{make(size, rows), make(size, rows), make(size + 6, rows)});
  configure(solvers_->qp, tolerance, ForceQPConstants::primal_infeasibility, max_iter, max_iter_in);
  // eps_primal_inf < 0: the certificate test never fires
  configure(solvers_->check, tolerance, -1.0, ForceQPConstants::check_iter * max_iter, max_iter_in);
  // the nearest problem in x = (f, e): H = diag(I, W I), [S G, -I] x = S w, the same rows on f
  configure(solvers_->nearest, tolerance, -1.0, max_iter, max_iter_in);
  nearest_hessian_.setZero(size + 6, size + 6);
  nearest_hessian_.diagonal().head(size).setOnes();
  nearest_hessian_.diagonal().tail(6).setConstant(ForceQPConstants::nearest_weight);
  nearest_inequality_.setZero(rows, size + 6);
  nearest_inequality_.leftCols(size) = inequality_;
  rows_.setOnes();
  grasp_map_.setZero(6, size);
  equality_.setZero(6, size);
  nearest_equality_.setZero(6, size + 6);
  gradient_.setZero(size);
  nearest_gradient_.setZero(size + 6);
  warm_x_.setZero(size);
  warm_y_.setZero(6);
  warm_z_.setZero(rows);
  nearest_.setZero(size);
  x_.setZero(size);
  pyramid_values_.setZero(n_ * facets_);
  result_.forces.setZero(n_, 3);
  result_.wrench_error.setZero();
  active_.reserve(static_cast<std::size_t>(rows));
  active_side_.reserve(static_cast<std::size_t>(rows));
  system_.setZero(6 + size, size);  // 6 + k <= 3n rows: more make M M^T singular
  gram_.setZero(6 + size, 6 + size);
  bounds_.setZero(6 + size);
  lambda_.setZero(6 + size);
  residual_.setZero(6 + size);
  values_.setZero(rows);
  active_forces_.setZero(size);
  active_tolerance_ = std::max(ForceQPConstants::active_tolerance, 10.0 * tolerance);
}

ContactForceQP::~ContactForceQP() = default;

bool ContactForceQP::holds(const ConstRows& grasp) const {
  return has_grasp_map_ && grasp.rows() == 6 && grasp.cols() == 3 * n_ && grasp == grasp_map_;
}

void ContactForceQP::set_grasp_map(const ConstRows& grasp, double torque_scale) {
  if (grasp.rows() != 6 || grasp.cols() != 3 * n_)
    throw std::invalid_argument("ContactForceQP.set_grasp_map: the grasp map must be (6, 3n)");
  grasp_map_ = grasp;  // scale the torque rows so that they weigh like the force rows
  rows_ << 1.0, 1.0, 1.0, Eigen::Vector3d::Constant(1.0 / torque_scale);
  equality_ = rows_.asDiagonal() * grasp_map_;
  nearest_equality_.leftCols(3 * n_) = equality_;
  nearest_equality_.rightCols(6) = -Eigen::Matrix<double, 6, 6>::Identity();  // -0.0 off the diagonal, as -np.eye
  has_grasp_map_ = true;
}

// _run: one bounded solve of (hessian, gradient, equality, b_, inequality, lower_, upper_).
template <class Solver>
ContactForceQP::Run ContactForceQP::run(Solver& qp, Warm warm, const Rows& hessian, const Eigen::VectorXd& gradient,
                                        const Rows& equality, const Rows& inequality) {
  if (warm == Warm::scratch) {
    qp.settings.initial_guess = InitialGuessStatus::EQUALITY_CONSTRAINED_INITIAL_GUESS;
    qp.init(MatRef(hessian), VecRef(gradient), MatRef(equality), VecRef(b_), MatRef(inequality), VecRef(lower_),
            VecRef(upper_));
    qp.solve();
  } else {  // same H, C and bounds; A too, even unchanged: its refactorisation halves the warm iterations
    const bool explicit_point = warm == Warm::point;
    qp.settings.initial_guess =
        explicit_point ? InitialGuessStatus::WARM_START : InitialGuessStatus::WARM_START_WITH_PREVIOUS_RESULT;
    qp.update(proxsuite::nullopt, VecRef(gradient), MatRef(equality), VecRef(b_), proxsuite::nullopt,
              proxsuite::nullopt, proxsuite::nullopt, false);
    if (explicit_point)
      qp.solve(VecRef(warm_x_), VecRef(warm_y_), VecRef(warm_z_));
    else
      qp.solve();
  }
  const auto& info = qp.results.info;
  const bool finite = qp.results.x.allFinite();
  const char* status = finite ? status_name(info.status) : "PROXQP_NOT_FINITE";
  return {status, finite && info.status == QPSolverOutput::PROXQP_SOLVED, static_cast<int>(info.iter)};
}

const ForceResult& ContactForceQP::solve(const Vector6& wrench, const ConstVector& desired) {
  const Eigen::Index size = 3 * n_;
  if (!has_grasp_map_ || desired.size() != size)
    throw std::invalid_argument("ContactForceQP.solve: set_grasp_map first, and desired forces of size 3n");
  b_ = rows_.cwiseProduct(wrench);
  gradient_ = -desired;
  int iterations = 0;
  bool have_nearest = false, doubtful = true;
  if (!infeasible_ && has_active_ && active_set_forces(desired))  // the last active set still holds: no QP
    return result(wrench, active_forces_, kSolved, 0);
  if (infeasible_) {  // the last call was infeasible: the nearest problem first, it is likely the answer
    iterations = nearest_forces(desired, doubtful);
    have_nearest = true;
    if (!doubtful) return result(wrench, nearest_, kPrimalInfeasible, iterations);
  }
  Problem& qp = solvers_->qp;
  const Run first = run(qp, warm_, hessian_, gradient_, equality_, inequality_);
  iterations += first.iterations;
  x_ = qp.results.x;
  if (first.solved) remember_active(x_, qp.results.z);
  const char* status = first.status;
  bool solved = first.solved;
  Warm warm = solved ? Warm::previous : Warm::scratch;
  if (!solved && !have_nearest) {
    iterations += nearest_forces(desired, doubtful);
    have_nearest = true;
  }
  if (!solved && doubtful) {  // maybe a fake certificate: the QP from scratch without the test
    Problem& check = solvers_->check;
    const Run second = run(check, Warm::scratch, hessian_, gradient_, equality_, inequality_);
    iterations += second.iterations;
    x_ = check.results.x;
    solved = second.solved;
    if (solved) {  // the next cycle starts the QP from here, not from its own failed iterate
      status = second.status;
      warm = Warm::point;
      warm_x_ = x_;
      warm_y_ = check.results.y;
      warm_z_ = check.results.z;
      remember_active(x_, warm_z_);
    }
  }
  warm_ = solved ? warm : Warm::scratch;
  infeasible_ = !solved;
  has_active_ = has_active_ && solved;
  return result(wrench, solved ? x_ : nearest_, status, iterations);
}

// _remember_active: the rows at a bound with a nonzero multiplier in a solved call (proxsuite's z: > 0 upper,
// < 0 lower), the active set the next call tries first.
void ContactForceQP::remember_active(const Eigen::VectorXd& forces, const Eigen::VectorXd& multipliers) {
  values_.noalias() = inequality_ * forces;
  active_.clear();
  active_side_.clear();
  for (Eigen::Index i = 0; i < values_.size(); ++i) {
    const double z = multipliers[i];
    if (z == 0.0) continue;
    const double bound = z > 0.0 ? upper_[i] : lower_[i];
    if (std::abs(values_[i] - bound) <= active_tolerance_) {
      active_.push_back(i);
      active_side_.push_back(z > 0.0 ? 1.0 : -1.0);
    }
  }
  has_active_ = 6 + static_cast<Eigen::Index>(active_.size()) <= 3 * n_;  // else M M^T is singular
}

// _active_set_forces: min 1/2 |f - f_d|^2 with A f = b and the remembered rows at their bounds, M f = r for
// M = [A; C_K]: f = f_d - M^T lambda, (M M^T) lambda = M f_d - r (Cholesky, in place; refused when a diagonal entry
// of its factor is below FULL_RANK times the largest: a redundant row, e.g. two contacts' G of rank 5).  Accepted
// only with its
// proof of optimality, the QP's own tolerance: M f = r and every row within its bounds to eps_abs, and each
// multiplier of the right sign (>= -eps_abs towards its bound).  Then it is the QP's optimum.  The warm start is
// left as it is: the next proxsuite solve starts from proxsuite's own last result, however many calls ago.
bool ContactForceQP::active_set_forces(const ConstVector& desired) {
  const Eigen::Index size = 3 * n_, k = static_cast<Eigen::Index>(active_.size()), m = 6 + k;
  auto system = system_.topRows(m);
  system.topRows(6) = equality_;
  bounds_.head(6) = b_;
  for (Eigen::Index j = 0; j < k; ++j) {
    const Eigen::Index row = active_[static_cast<std::size_t>(j)];
    system.row(6 + j) = inequality_.row(row);
    bounds_[6 + j] = active_side_[static_cast<std::size_t>(j)] > 0.0 ? upper_[row] : lower_[row];
  }
  Eigen::Ref<Eigen::MatrixXd> gram = gram_.topLeftCorner(m, m);
  gram.noalias() = system * system.transpose();
  Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> cholesky(gram);  // in place: no allocation
  const auto pivots = cholesky.matrixLLT().diagonal();  // M of full row rank, not only in round-off
  if (cholesky.info() != Eigen::Success || !(pivots.minCoeff() >= ForceQPConstants::full_rank * pivots.maxCoeff()))
    return false;
  auto lambda = lambda_.head(m);
  lambda.noalias() = system * desired;
  lambda -= bounds_.head(m);
  cholesky.solveInPlace(lambda);
  auto& forces = active_forces_;
  forces = desired;
  forces.noalias() -= system.transpose() * lambda;
  if (!forces.allFinite()) return false;
  auto residual = residual_.head(m);
  residual.noalias() = system * forces;
  residual -= bounds_.head(m);
  if (residual.cwiseAbs().maxCoeff() > tolerance_) return false;
  values_.noalias() = inequality_ * forces;
  for (Eigen::Index i = 0; i < values_.size(); ++i)
    if (values_[i] > upper_[i] + tolerance_ || values_[i] < lower_[i] - tolerance_) return false;
  for (Eigen::Index j = 0; j < k; ++j)
    if (active_side_[static_cast<std::size_t>(j)] * lambda[6 + j] < -tolerance_) return false;
  return true;
}

// _nearest_forces: the admissible forces into nearest_, and whether the QP may be feasible after all.
int ContactForceQP::nearest_forces(const ConstVector& desired, bool& doubtful) {
  const Eigen::Index size = 3 * n_;
  nearest_gradient_.head(size) = -desired;
  nearest_gradient_.tail(6).setZero();
  Problem& qp = solvers_->nearest;
  const Run outcome = run(qp, warm_nearest_ ? Warm::previous : Warm::scratch, nearest_hessian_, nearest_gradient_,
                          nearest_equality_, nearest_inequality_);
  warm_nearest_ = outcome.solved;
  nearest_ = qp.results.x.head(size);
  if (!outcome.solved) admissible(nearest_);
  miss_.noalias() = equality_ * nearest_;
  miss_ -= b_;
  const double error = miss_.norm();
  doubtful = error <= ForceQPConstants::doubtful_error * std::max(1.0, (nearest_ - desired).norm());
  return outcome.iterations;
}

// _admissible: unconverged forces moved into the pyramids' inscribed cones and above f_min (NaN -> f_min).
void ContactForceQP::admissible(Eigen::Ref<Eigen::VectorXd> forces) const {
  for (Eigen::Index i = 0; i < n_; ++i) {
    double* f = forces.data() + 3 * i;
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(f[k])) f[k] = 0.0;
    f[2] = std::max(f[2], min_normal_force_);
    const double tangential = std::hypot(f[0], f[1]);
    const double limit = inscribed_ * f[2];
    const double factor = tangential > limit ? limit / std::max(tangential, 1e-300) : 1.0;
    f[0] *= factor;
    f[1] *= factor;
  }
}

// _result: the metrics of the returned forces.
const ForceResult& ContactForceQP::result(const Vector6& wrench, const Eigen::VectorXd& forces, const char* status,
                                          int iterations) {
  ForceResult& out = result_;
  out.forces = Eigen::Map<const Rows>(forces.data(), n_, 3);
  out.wrench_error.noalias() = grasp_map_ * forces;
  out.wrench_error -= wrench;
  out.wrench_residual = std::sqrt(out.wrench_error.dot(out.wrench_error));
  double cone = -std::numeric_limits<double>::infinity(), normal = std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 0; i < n_; ++i) {
    const double* f = forces.data() + 3 * i;
    cone = std::max(cone, std::sqrt(f[0] * f[0] + f[1] * f[1]) - mu_ * f[2]);
    normal = std::min(normal, f[2]);
  }
  out.cone_violation = cone;
  out.normal_margin = normal - min_normal_force_;
  pyramid_values_.noalias() = inequality_.topRows(n_ * facets_) * forces;
  const double pyramid = pyramid_values_.maxCoeff();
  const bool admissible = pyramid <= ForceQPConstants::admissible_tolerance &&
                          out.normal_margin >= -ForceQPConstants::admissible_tolerance;
  out.feasible = admissible && out.wrench_residual <=
                                   ForceQPConstants::feasible_residual * std::max(1.0, std::sqrt(wrench.dot(wrench)));
  out.status = status;
  out.iterations = iterations;
  return out;
}

}  // namespace bhgrasp
