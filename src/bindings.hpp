// The binding families of bhgrasp._core, one file each (bind_*.cpp), called in this order by NB_MODULE in
// bindings.cpp: a family's signatures name the classes bound before it.  Every family includes the same STL casters
// (a missing one fails only at run time, when a value of its type crosses).
#pragma once

#include <nanobind/nanobind.h>

namespace bhgrasp {

void bind_simulation(nanobind::module_& m);  // bind_simulation.cpp
void bind_dynamics(nanobind::module_& m);    // bind_dynamics.cpp
void bind_grasp(nanobind::module_& m);       // bind_grasp.cpp
void bind_loop(nanobind::module_& m);        // bind_loop.cpp

}  // namespace bhgrasp
