// Pinocchio models across the Python/C++ boundary: the text serialisations of pin.Model.saveToString() and
// pin.GeometryModel.saveToString(), read back here.  Boost's serialisation of every joint type is compiled in
// model_io.cpp alone (each file that included <pinocchio/serialization.hpp> spent ~30 s and ~1 GB compiling it).
#pragma once

#include <string>

#include <pinocchio/multibody/fwd.hpp>

namespace bhgrasp {

// The model written by pin.Model.saveToString().
pinocchio::Model model_from_text(const std::string& text);

// The geometry written by pin.GeometryModel.saveToString().
pinocchio::GeometryModel geometry_from_text(const std::string& text);

}  // namespace bhgrasp
