// Bindings of the closed loop: a controller closed on the compiled step for many steps in one call (closed_loop.hpp).
#include <nanobind/eigen/dense.h>
#include <nanobind/nanobind.h>
#include <nanobind/stl/array.h>
#include <nanobind/stl/pair.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/vector.h>

#include "closed_loop.hpp"

#include "bindings.hpp"

namespace nb = nanobind;
using namespace nb::literals;

namespace bhgrasp {
namespace {

using ReadOnlyRows = nb::ndarray<const double, nb::numpy, nb::ndim<2>, nb::c_contig>;

// A read-only NumPy view of `rows` (its owner kept alive by the reference_internal policy of the property).
ReadOnlyRows read_only(const RowMatrix& rows) {
  const std::size_t shape[2] = {static_cast<std::size_t>(rows.rows()), static_cast<std::size_t>(rows.cols())};
  return ReadOnlyRows(rows.data(), 2, shape);
}

}  // namespace

void bind_loop(nb::module_& m) {
  nb::class_<LoopController>(m, "LoopController")
      .def_prop_ro("inputs", &LoopController::inputs)
      .def_prop_ro("log_size", &LoopController::log_size);

  nb::class_<SMCGraspLoop, LoopController>(m, "SMCGraspLoop")
      .def(nb::init<SMCAdaptiveLaw&, const PosePath&, Indices, Indices, Eigen::Index, Eigen::Index, Eigen::Index,
                    Eigen::Index, double>(),
           "law"_a, "path"_a, "finger_of_pair"_a, "joint_of_pair"_a, "nq_hand"_a, "nv_hand"_a, "object_q"_a,
           "object_v"_a, "last_time"_a, nb::keep_alive<1, 2>(), nb::keep_alive<1, 3>())
      .def_prop_ro("last_time", &SMCGraspLoop::last_time);

  nb::class_<ApproachLoop, LoopController>(m, "ApproachLoop")
      .def(nb::init<HandDynamics&, const Eigen::Vector3d&, Vector, RowMatrix, Vector, Vector, double, Indices, Indices,
                    Vector, double, double>(),
           "dynamics"_a, "gravity"_a, "times"_a, "reference"_a, "kp"_a, "kv"_a, "damping"_a, "finger_of_pair"_a,
           "grasping"_a, "arrived"_a, "contact_force"_a, "last_time"_a, nb::keep_alive<1, 2>())
      .def_prop_ro("last_time", &ApproachLoop::last_time);

  // the rows are read-only views of the run's (kept alive by them): a recorder keeps them
  const auto rows = [](RowMatrix LoopRun::* member) {
    return [member](const LoopRun& run) { return read_only(run.*member); };
  };
  const auto view = nb::rv_policy::reference_internal;
  nb::class_<LoopRun>(m, "LoopRun")
      .def_ro("steps", &LoopRun::steps).def_ro("stop", &LoopRun::stop).def_ro("status", &LoopRun::status)
      .def_ro("diverged_at", &LoopRun::diverged_at).def_ro("t", &LoopRun::t)
      .def_prop_ro("q", rows(&LoopRun::q), view).def_prop_ro("v", rows(&LoopRun::v), view)
      .def_prop_ro("u", rows(&LoopRun::u), view).def_prop_ro("drive", rows(&LoopRun::drive), view)
      .def_prop_ro("log", rows(&LoopRun::log), view)
      .def_ro("contacts", &LoopRun::contacts).def_ro("counts", &LoopRun::counts).def_ro("last", &LoopRun::last);

  m.def("run_closed_loop", &run_closed_loop, "engine"_a, "controller"_a, "drive"_a, "q"_a, "v"_a, "contacts"_a,
        "memory"_a, "t"_a, "dt"_a, "steps"_a, "until"_a, "limit"_a, "max_speed"_a, "max_penetration"_a,
        "Up to `steps` steps of `engine` under `controller` in one call (closed_loop.hpp): a LoopRun.");
}

}  // namespace bhgrasp
