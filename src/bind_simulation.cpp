// Bindings of the simulation family: the option structs (bound from their field lists in options.hpp), the contact
// memory and contacts, one step's result, the Engine and the Batch, the recorder's concatenate, the model text.
#include <nanobind/eigen/dense.h>
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/array.h>
#include <nanobind/stl/pair.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/vector.h>

#include "batch.hpp"
#include "engine.hpp"
#include "model_io.hpp"
#include "options.hpp"
#include "recording.hpp"

#include "bindings.hpp"

namespace nb = nanobind;
using namespace nb::literals;

// An option struct of options.hpp bound from its field list: a default constructor, each field read-write, and the
// tuple FIELDS of their names (bhgrasp/sim/native_options.py fills every one of them).
#define BHGRASP_DEF_RW(type, name) .def_rw(#name, &Self::name)
#define BHGRASP_NAME(type, name) #name,
#define BHGRASP_BIND_OPTIONS(module, Struct, FIELDS)                                                \
  [&] {                                                                                             \
    using Self = Struct;                                                                            \
    nb::class_<Self> options(module, #Struct);                                                      \
    options.def(nb::init<>()) FIELDS(BHGRASP_DEF_RW);                                               \
    options.attr("FIELDS") = nb::cast(std::vector<std::string>{FIELDS(BHGRASP_NAME)});              \
  }()

namespace bhgrasp {
namespace {

using ReadOnly = nb::ndarray<const double, nb::numpy, nb::ndim<1>, nb::c_contig>;

// A read-only NumPy view of `vector` (its owner kept alive by the reference_internal policy of the property).
ReadOnly read_only(const Vector& vector) {
  const std::size_t shape[1] = {static_cast<std::size_t>(vector.size())};
  return ReadOnly(vector.data(), 1, shape);
}

}  // namespace

void bind_simulation(nb::module_& m) {
  BHGRASP_BIND_OPTIONS(m, ContactLaw, BHGRASP_CONTACT_LAW);
  BHGRASP_BIND_OPTIONS(m, Pair, BHGRASP_PAIR);
  BHGRASP_BIND_OPTIONS(m, Query, BHGRASP_QUERY);
  BHGRASP_BIND_OPTIONS(m, Spinning, BHGRASP_SPINNING);
  BHGRASP_BIND_OPTIONS(m, Settings, BHGRASP_SETTINGS);
  BHGRASP_BIND_OPTIONS(m, Drive, BHGRASP_DRIVE);
  BHGRASP_BIND_OPTIONS(m, Barrett, BHGRASP_BARRETT);

  nb::class_<Memory>(m, "Memory")
      .def(nb::init<>())
      .def("__init__",
           [](Memory* memory, Indices pair, Points local_b, Points displacement, Flags sliding) {
             const Eigen::Index n = pair.size();
             if (local_b.rows() != n || displacement.rows() != n || sliding.size() != n)
               throw std::invalid_argument("memory arrays of different lengths");
             new (memory) Memory{std::move(pair), std::move(local_b), std::move(displacement), std::move(sliding)};
           },
           "pair"_a, "local_b"_a, "displacement"_a, "sliding"_a)
      .def_ro("pair", &Memory::pair).def_ro("local_b", &Memory::local_b)
      .def_ro("displacement", &Memory::displacement).def_ro("sliding", &Memory::sliding)
      .def("__len__", [](const Memory& memory) { return memory.pair.size(); });

  nb::class_<Contacts>(m, "Contacts")
      .def_ro("pair", &Contacts::pair).def_ro("point", &Contacts::point)
      .def_ro("normal", &Contacts::normal).def_ro("depth", &Contacts::depth)
      .def_ro("friction", &Contacts::friction).def_ro("displacement", &Contacts::displacement)
      .def_ro("weight", &Contacts::weight).def_ro("local_b", &Contacts::local_b)
      .def_ro("force", &Contacts::force).def_ro("sticking", &Contacts::sticking)
      .def_ro("was_sliding", &Contacts::was_sliding)
      .def("__len__", &Contacts::size);
  m.def(
      "box_separation",
      [](const Vector3& half_a, const Matrix& pose_a, const Vector3& half_b, const Matrix& pose_b) {
        if (pose_a.rows() != 4 || pose_a.cols() != 4 || pose_b.rows() != 4 || pose_b.cols() != 4)
          throw std::invalid_argument("box poses must be 4 x 4 homogeneous matrices");
        const pinocchio::SE3 placement_a{Eigen::Matrix4d(pose_a)}, placement_b{Eigen::Matrix4d(pose_b)};
        return box_separation(half_a, placement_a, half_b, placement_b);
      },
      "half_a"_a, "pose_a"_a, "half_b"_a, "pose_b"_a,
      "The separating-axis gap [m] of two boxes (half sides, world poses): a lower bound of their distance.");
  m.def("independent_model_text", &independent_model_text, "model"_a,
        "pin.Model.saveToString() of the model with every mimic joint made an independent joint (bhgrasp.model.couplings).");
  m.def("concatenate", &concatenate, "parts"_a, "The contacts of many steps as one Contacts (rows in order).");


  nb::class_<Divergence>(m, "Divergence")
      .def_ro("kind", &Divergence::kind).def_ro("index", &Divergence::index)
      .def_ro("value", &Divergence::value);

  // q and v read-only: they become a state's arrays, views of this result's (a state is a value)
  nb::class_<StepResult>(m, "StepResult")
      .def_prop_ro("q", [](const StepResult& result) { return read_only(result.q); }, nb::rv_policy::reference_internal)
      .def_prop_ro("v", [](const StepResult& result) { return read_only(result.v); }, nb::rv_policy::reference_internal)
      .def_ro("contacts", &StepResult::contacts).def_ro("memory", &StepResult::memory)
      .def_ro("drive", &StepResult::drive).def_ro("load", &StepResult::load)
      .def_ro("divergence", &StepResult::divergence);

  nb::class_<Engine>(m, "Engine")
      .def(nb::init<const std::string&, const std::string&, Settings>(), "model"_a, "geometry"_a, "settings"_a)
      .def("step", &Engine::step, "q"_a, "v"_a, "tau_hand"_a, "drive"_a, "memory"_a, "max_speed"_a,
           "max_penetration"_a, nb::call_guard<nb::gil_scoped_release>())
      .def("detect", &Engine::detect, "q"_a, "memory"_a)
      .def_prop_rw("kept_solver", &Engine::kept_solver, &Engine::set_kept_solver)
      .def_rw("box_axes", &Engine::box_axes)
      .def_ro("box_axes_skipped", &Engine::box_axes_skipped)
      .def_prop_ro("nq", &Engine::nq)
      .def_prop_ro("nv", &Engine::nv);

  nb::class_<BarrettDrive>(m, "BarrettDrive")
      .def(nb::init<const Barrett&>(), "barrett"_a)
      .def_prop_ro("inputs", &BarrettDrive::inputs)
      .def(
          "step",
          [](const BarrettDrive& drive, Engine& engine, const Vector& q, const Vector& v, const Vector& u,
             const Vector& extra, Modes modes, const Memory& memory, double max_speed, double max_penetration) {
            StepResult result = drive.step(engine, q, v, u, extra, modes, memory, max_speed, max_penetration);
            return std::make_pair(std::move(result), modes);
          },
          "engine"_a, "q"_a, "v"_a, "u"_a, "extra"_a, "modes"_a, "memory"_a, "max_speed"_a, "max_penetration"_a,
          nb::call_guard<nb::gil_scoped_release>(),
          "One step of `engine` under motor inputs u and extra torques in `modes`: (StepResult, the modes after).");

  nb::class_<Batch>(m, "Batch")
      .def(nb::init<const std::string&, const std::string&, const Settings&, int>(), "model"_a, "geometry"_a,
           "settings"_a, "size"_a)
      .def_prop_ro("size", &Batch::size)
      .def("set_state", &Batch::set_state, "env"_a, "q"_a, "v"_a, "memory"_a)
      .def("step", &Batch::step, "tau_hand"_a, "drive"_a, "max_speed"_a, "max_penetration"_a, "threads"_a,
           nb::call_guard<nb::gil_scoped_release>())
      .def_prop_ro("q", [](const Batch& batch) { return Rows(batch.q()); })
      .def_prop_ro("v", [](const Batch& batch) { return Rows(batch.v()); })
      .def("memory", [](const Batch& batch, int env) { return Memory(batch.memory(env)); }, "env"_a)
      .def("contacts", [](const Batch& batch, int env) { return Contacts(batch.contacts(env)); }, "env"_a)
      .def("divergence", [](const Batch& batch, int env) { return Divergence(batch.divergence(env)); }, "env"_a)
      .def("set_barrett", &Batch::set_barrett, "barrett"_a)
      .def("set_modes", &Batch::set_modes, "env"_a, "modes"_a)
      .def("modes", &Batch::modes, "env"_a)
      .def("step_barrett", &Batch::step_barrett, "u"_a, "max_speed"_a, "max_penetration"_a, "threads"_a,
           nb::call_guard<nb::gil_scoped_release>())
      .def(
          "rollout",
          [](Batch& batch, const Rows& inputs, int steps, bool barrett, const Drive& drive, double max_speed,
             double max_penetration, int threads, bool record) {
            Rows q_record, v_record;
            {
              nb::gil_scoped_release release;
              batch.rollout(inputs, steps, barrett, drive, max_speed, max_penetration, threads, record, q_record,
                            v_record);
            }
            return std::make_pair(std::move(q_record), std::move(v_record));
          },
          "inputs"_a, "steps"_a, "barrett"_a, "drive"_a, "max_speed"_a, "max_penetration"_a, "threads"_a, "record"_a)
      .def("gravity", &Batch::gravity, "threads"_a, nb::call_guard<nb::gil_scoped_release>())
      .def("frame_jacobians", &Batch::frame_jacobians, "frames"_a, "threads"_a,
           nb::call_guard<nb::gil_scoped_release>());
}

}  // namespace bhgrasp
