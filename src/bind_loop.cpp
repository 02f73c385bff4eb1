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

  // the arrays are views of the run's (kept alive by them)
  nb::class_<LoopRun>(m, "LoopRun")
      .def_ro("steps", &LoopRun::steps).def_ro("stop", &LoopRun::stop).def_ro("status", &LoopRun::status)
      .def_ro("diverged_at", &LoopRun::diverged_at)
      .def_ro("t", &LoopRun::t).def_ro("q", &LoopRun::q).def_ro("v", &LoopRun::v).def_ro("u", &LoopRun::u)
      .def_ro("drive", &LoopRun::drive).def_ro("log", &LoopRun::log)
      .def_ro("contacts", &LoopRun::contacts).def_ro("counts", &LoopRun::counts).def_ro("last", &LoopRun::last);

  m.def("run_closed_loop", &run_closed_loop, "engine"_a, "controller"_a, "drive"_a, "q"_a, "v"_a, "contacts"_a,
        "memory"_a, "t"_a, "dt"_a, "steps"_a, "until"_a, "limit"_a, "max_speed"_a, "max_penetration"_a,
        nb::call_guard<nb::gil_scoped_release>(),
        "Up to `steps` steps of `engine` under `controller` in one call (closed_loop.hpp): a LoopRun.");
}

}  // namespace bhgrasp
