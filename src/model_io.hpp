// Pinocchio models across the Python/C++ boundary: the text serialisations of pin.Model.saveToString() and
// pin.GeometryModel.saveToString(), read back here.  Boost's serialisation of every joint type is compiled in
// model_io.cpp and model_convert.cpp alone (each file that included <pinocchio/serialization.hpp> spent ~30 s and
// ~1 GB compiling it).
#pragma once

#include <string>

#include <pinocchio/multibody/fwd.hpp>

namespace bhgrasp {

// The model written by pin.Model.saveToString().
pinocchio::Model model_from_text(const std::string& text);

// The same model with every mimic joint made an independent joint (its own coordinate, the limits of the joint it
// mimicked mapped through the coupling): the twin in which the coupling is a constraint, and a form that serialises
// whole (Pinocchio 4.1 does not write a mimic joint's extended sizes, see model_io.cpp).  Joint and frame indexes
// are unchanged.
std::string independent_model_text(const std::string& text);

// The geometry written by pin.GeometryModel.saveToString(), or by bhgrasp/sim/geometry_text.py (its convex shapes
// ahead of it: convex_shapes.hpp).
pinocchio::GeometryModel geometry_from_text(const std::string& text);

}  // namespace bhgrasp
