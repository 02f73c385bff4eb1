// What a run records of its steps' contacts, assembled once at the end of the run (bhgrasp/sim/recorder.py).
#pragma once

#include <vector>

#include "engine.hpp"

namespace bhgrasp {

// The contacts of many steps, one after the other (rows of parts[0], then parts[1], ...).
Contacts concatenate(const std::vector<const Contacts*>& parts);

}  // namespace bhgrasp
