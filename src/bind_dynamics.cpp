// Bindings of the dynamics family: the hand's Slotine-Li and contact torques, a finger's workspace terms, the
// object regressor, a pose path, the wrist servo of a mounted hand.
#include <nanobind/eigen/dense.h>
#include <nanobind/nanobind.h>
#include <nanobind/stl/array.h>
#include <nanobind/stl/pair.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/vector.h>

#include "dynamics.hpp"
#include "pose_path.hpp"
#include "smc_law.hpp"
#include "workspace.hpp"
#include "wrist_servo.hpp"

#include "bindings.hpp"

namespace nb = nanobind;
using namespace nb::literals;

namespace bhgrasp {

namespace {

using Rows6 = Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor>;

// A pose path's moves from one list per field (PosePath's segments, in time order).
std::vector<PoseMove> moves_from_fields(const std::vector<Eigen::Matrix3d>& rotations,
                                 const std::vector<Eigen::Vector3d>& translations, const Rows6& offsets,
                                 const std::vector<double>& durations, const std::vector<double>& delays) {
  const std::size_t n = rotations.size();
  if (translations.size() != n || static_cast<std::size_t>(offsets.rows()) != n || durations.size() != n ||
      delays.size() != n)
    throw std::invalid_argument("one rotation, translation, offset, duration and delay per move");
  std::vector<PoseMove> moves;
  for (std::size_t i = 0; i < n; ++i)
    moves.push_back({rotations[i], translations[i], offsets.row(static_cast<Eigen::Index>(i)).transpose(),
                     durations[i], delays[i]});
  return moves;
}

}  // namespace

void bind_dynamics(nb::module_& m) {
  nb::class_<HandDynamics>(m, "HandDynamics")
      .def(nb::init<const std::string&>(), "model"_a)
      .def(
          "inverse_dynamics",
          [](HandDynamics& kernel, const Eigen::Vector3d& gravity, const HandDynamics::ConstVector& q,
             const HandDynamics::ConstVector& v, const HandDynamics::ConstVector& a) -> Eigen::VectorXd {
            return kernel.inverse_dynamics(gravity, q, v, a);  // a copy: the kernel's is overwritten
          },
          "gravity"_a, "q"_a, "v"_a, "a"_a)
      .def(
          "slotine_li_torque",
          [](HandDynamics& kernel, const Eigen::Vector3d& gravity, const HandDynamics::ConstVector& q,
             const HandDynamics::ConstVector& v, const HandDynamics::ConstVector& v_r,
             const HandDynamics::ConstVector& a_r) -> Eigen::VectorXd {
            return kernel.slotine_li_torque(gravity, q, v, v_r, a_r);  // a copy: the kernel's is overwritten
          },
          "gravity"_a, "q"_a, "v"_a, "v_r"_a, "a_r"_a)
      .def(
          "contact_torques",
          [](HandDynamics& kernel, const Eigen::Matrix3d& base_rotation, const Eigen::Vector3d& base_translation,
             const HandDynamics::ConstVector& q, const std::vector<int>& joints, const HandDynamics::ConstRows& points,
             const HandDynamics::ConstRows& forces) -> Eigen::VectorXd {
            return kernel.contact_torques(base_rotation, base_translation, q, joints, points, forces);  // a copy
          },
          "base_rotation"_a, "base_translation"_a, "q"_a, "joints"_a, "points"_a, "forces"_a)
      .def_prop_ro("nv", &HandDynamics::nv);

  nb::class_<PosePath>(m, "PosePath")
      .def(
          "__init__",
          [](PosePath* path, const std::vector<Eigen::Matrix3d>& rotations,
             const std::vector<Eigen::Vector3d>& translations, const Rows6& offsets,
             const std::vector<double>& durations, const std::vector<double>& delays) {
            new (path) PosePath(moves_from_fields(rotations, translations, offsets, durations, delays));
          },
          "rotations"_a, "translations"_a, "offsets"_a, "durations"_a, "delays"_a)
      .def(
          "sample",
          [](const PosePath& path, double t) {
            Eigen::Matrix3d rotation;
            Eigen::Vector3d position;
            Vector6 twist, derivative;
            path.at(t, rotation, position, twist, derivative);
            return std::make_tuple(rotation, position, twist, derivative);
          },
          "t"_a, "(rotation (3, 3), position (3,), world twist (6,), its derivative (6,)) at t [s]");

  nb::class_<WristServo>(m, "WristServo")
      .def(
          "__init__",
          [](WristServo* servo, const std::string& model, const Eigen::Vector3d& gravity,
             const std::vector<Eigen::Matrix3d>& rotations, const std::vector<Eigen::Vector3d>& translations,
             const Rows6& offsets, const std::vector<double>& durations, const std::vector<double>& delays,
             const Eigen::Matrix3d& origin_rotation, const Eigen::Vector3d& origin_translation, const Vector6& kp,
             const Vector6& kd, bool hold_fingers, double finger_kp, double finger_kd) {
            new (servo)
                WristServo(model, gravity, moves_from_fields(rotations, translations, offsets, durations, delays),
                           origin_rotation, origin_translation, kp, kd, hold_fingers, finger_kp, finger_kd);
          },
          "model"_a, "gravity"_a, "rotations"_a, "translations"_a, "offsets"_a, "durations"_a, "delays"_a,
          "origin_rotation"_a, "origin_translation"_a, "kp"_a, "kd"_a, "hold_fingers"_a, "finger_kp"_a, "finger_kd"_a)
      .def(
          "torques",
          [](WristServo& servo, double t, double held, const Eigen::Ref<const Eigen::VectorXd>& q,
             const Eigen::Ref<const Eigen::VectorXd>& v) {
            const Eigen::VectorXd& tau = servo.torques(t, held, q, v);
            return std::make_tuple(Eigen::VectorXd(tau), Vector6(servo.mount_reference()), Vector6(servo.mount_error()));
          },
          "t"_a, "held"_a, "q"_a, "v"_a,
          "(joint torques, the reference c_d, the error c - c_d) at t [s]; held: where the path stopped (NaN: never)")
      .def(
          "reference",
          [](const WristServo& servo, double t, double held) {
            Vector6 c, c_dot, c_dd;
            servo.reference(t, held, c, c_dot, c_dd);
            return std::make_tuple(c, c_dot, c_dd);
          },
          "t"_a, "held"_a)
      .def("reset", &WristServo::reset)
      .def("hold", &WristServo::hold, "fingers"_a);

  nb::class_<WorkspaceTerms>(m, "WorkspaceTerms")  // the fields of bhgrasp.controllers._workspace_terms._Workspace
      .def_ro("singular", &WorkspaceTerms::singular).def_ro("position", &WorkspaceTerms::position)
      .def_ro("jacobian", &WorkspaceTerms::jacobian).def_ro("basis", &WorkspaceTerms::basis)
      .def_ro("task_jacobian", &WorkspaceTerms::task_jacobian).def_ro("mass", &WorkspaceTerms::mass)
      .def_ro("coriolis", &WorkspaceTerms::coriolis).def_ro("gravity", &WorkspaceTerms::gravity)
      .def("torque", &fingertip_torque, "velocity"_a, "x_d"_a, "xd_d"_a, "xdd_d"_a, "kp"_a, "kv"_a);
  nb::class_<FingerDynamics>(m, "FingerDynamics")
      .def(nb::init<const std::string&, const std::vector<int>&, const std::vector<std::vector<int>>&>(), "model"_a,
           "frames"_a, "indices"_a)
      // copies out as writable arrays in NumPy's layout (the kernel's own are overwritten by its next call), in the
      // order of bhgrasp.controllers._workspace_terms._finger_terms_python
      .def(
          "compute",
          [](FingerDynamics& kernel, int finger, const Eigen::Vector3d& gravity, const FingerDynamics::ConstVector& q,
             const FingerDynamics::ConstVector& v) {
            const FingerTerms& terms = kernel.compute(finger, gravity, q, v);
            return std::make_tuple(terms.positions, terms.jacobian, terms.mass, terms.gravity, terms.velocity,
                                   terms.bias);
          },
          "finger"_a, "gravity"_a, "q"_a, "v"_a)
      .def("workspace", &FingerDynamics::workspace, nb::rv_policy::copy, "finger"_a, "gravity"_a, "rotation"_a,
           "translation"_a, "q"_a, "v"_a)
      .def_prop_ro("nv", &FingerDynamics::nv);

  m.def("object_regressor", &object_regressor, "rotation"_a, "omega"_a, "v_r"_a, "a_r"_a, "gravity"_a,
        "Y_o (6, 7) of bhgrasp.controllers.adaptive_grasp.object_regressor.");
}

}  // namespace bhgrasp
