// The headers nearly every file of the core includes, parsed once per build (CMake's target_precompile_headers):
// Eigen, Pinocchio's model, data, geometry and the algorithms the core calls, coal's collision types.  Parsing them
// cost each of the ~16 files 12-14 s of its compile; a file still includes what it uses, so it builds without this.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/LU>
#include <Eigen/SVD>

#include <coal/collision.h>
#include <coal/collision_data.h>
#include <coal/contact_patch.h>
#include <coal/shape/geometric_shapes.h>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/algorithm/jacobian.hpp>
#include <pinocchio/algorithm/joint-configuration.hpp>
#include <pinocchio/algorithm/kinematics.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/geometry.hpp>
#include <pinocchio/multibody.hpp>
