#include "recording.hpp"

namespace bhgrasp {

Contacts concatenate(const std::vector<const Contacts*>& parts) {
  Eigen::Index total = 0;
  for (const Contacts* part : parts) total += part->size();
  Contacts all;
  all.resize(total);
  Eigen::Index row = 0;
  for (const Contacts* part : parts) {
    const Eigen::Index m = part->size();
    all.pair.segment(row, m) = part->pair;
    all.point.middleRows(row, m) = part->point;
    all.normal.middleRows(row, m) = part->normal;
    all.depth.segment(row, m) = part->depth;
    all.friction.segment(row, m) = part->friction;
    all.displacement.middleRows(row, m) = part->displacement;
    all.weight.segment(row, m) = part->weight;
    all.local_b.middleRows(row, m) = part->local_b;
    all.force.middleRows(row, m) = part->force;
    all.sticking.segment(row, m) = part->sticking;
    all.was_sliding.segment(row, m) = part->was_sliding;
    row += m;
  }
  return all;
}

}  // namespace bhgrasp
