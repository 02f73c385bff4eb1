// Python bindings of bhgrasp._core: thin wrappers, no logic; argument checks stay in Python.
// Models cross the boundary serialized: pin.Model.saveToString() / pin.GeometryModel.saveToString().

#include <string>
#include <tuple>

#include <nanobind/eigen/dense.h>
#include <nanobind/nanobind.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>

#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/geometry.hpp>
#include <pinocchio/multibody.hpp>
#include <pinocchio/serialization.hpp>

namespace nb = nanobind;

namespace {

pinocchio::Model load_model(const std::string& model_text) {
    pinocchio::Model model;
    model.loadFromString(model_text);
    return model;
}

std::tuple<int, int, int> model_sizes(const std::string& model_text, const std::string& geometry_text) {
    const pinocchio::Model model = load_model(model_text);
    pinocchio::GeometryModel geometry;
    geometry.loadFromString(geometry_text);
    return {model.nq, model.nv, static_cast<int>(geometry.ngeoms)};
}

// Joint-space inertia matrix M(q) [kg m^2], both triangles, as pin.crba returns it.
Eigen::MatrixXd mass_matrix(const std::string& model_text, const Eigen::Ref<const Eigen::VectorXd>& q) {
    const pinocchio::Model model = load_model(model_text);
    pinocchio::Data data(model);
    // ConfigVectorType = Eigen::Ref<const Eigen::VectorXd>: the instantiation precompiled in libpinocchio_default.
    pinocchio::crba(model, data, q);
    data.M.triangularView<Eigen::StrictlyLower>() = data.M.transpose().triangularView<Eigen::StrictlyLower>();
    return data.M;
}

}  // namespace

NB_MODULE(_core, m) {
    m.doc() = "bhgrasp's compiled core (Pinocchio in C++).";
    m.def("model_sizes", &model_sizes, nb::arg("model"), nb::arg("geometry"),
          "(nq, nv, ngeoms) of a pin.Model and a pin.GeometryModel given as their saveToString() texts.");
    m.def("mass_matrix", &mass_matrix, nb::arg("model"), nb::arg("q"),
          "Joint-space inertia matrix M(q) [kg m^2] (CRBA, symmetric) of a pin.Model given as saveToString() text.");
}
