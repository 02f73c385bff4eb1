// Python bindings of bhgrasp._core: thin wrappers, no logic.  Input checks that a user can trip live in Python
// (bhgrasp/sim/compiled.py and each kernel's Python caller); the checks here only keep a wrong call from reading out
// of bounds.  Models cross the boundary serialised: pin.Model.saveToString() / pin.GeometryModel.saveToString().
#include <nanobind/nanobind.h>

#include "bindings.hpp"

NB_MODULE(_core, m) {
  m.doc() =
      "bhgrasp's compiled core: the simulation step and the grasp kinematics on Pinocchio's and coal's C++ API, the "
      "internal-force QP on proxsuite's.";
  bhgrasp::bind_simulation(m);
  bhgrasp::bind_dynamics(m);
  bhgrasp::bind_grasp(m);
  bhgrasp::bind_loop(m);
}
