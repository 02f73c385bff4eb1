// model_from_text (see model_io.hpp); the other conversions are model_convert.cpp.
#include "model_io.hpp"

#include <boost/variant/get.hpp>
#include <pinocchio/multibody/model.hpp>
#include <pinocchio/serialization.hpp>

namespace bhgrasp {

namespace {

// Pinocchio 4.1 writes a mimic joint's mimicking joint, scaling and offset but not the sizes of its extended
// configuration and tangent spaces (nqExtended, nvExtended: read back as -1), and every algorithm then reads past
// its vectors (a segmentation fault; pickle.loads(pickle.dumps(model)) in Python has the same defect).  Rebuilding
// each mimic joint from what was written restores them; the indexes are set as Pinocchio's own loader sets them.
void restore_mimic_joints(pinocchio::Model& model) {
  using Mimic = pinocchio::JointModelMimic;
  for (auto& joint : model.joints) {
    const Mimic* read = boost::get<Mimic>(&joint.toVariant());
    if (read == nullptr) continue;
    Mimic rebuilt(read->jmodel(), read->scaling(), read->offset());
    rebuilt.setMimicIndexes(read->jmodel().id(), read->idx_q(), read->idx_v(), read->jmodel().idx_vExtended());
    rebuilt.setIndexes(read->id(), 0, 0, read->idx_vExtended());
    joint = rebuilt;
  }
}

}  // namespace

pinocchio::Model model_from_text(const std::string& text) {
  pinocchio::Model model;
  model.loadFromString(text);
  restore_mimic_joints(model);
  return model;
}

}  // namespace bhgrasp
