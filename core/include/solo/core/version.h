#pragma once

#include <string>
#include <utility>
#include <vector>

namespace solo {

/// solo's own version, "MAJOR.MINOR.PATCH".
std::string soloVersion();

/// Versions of the libraries the geometry module was built against (compile-time
/// macros): Eigen, OpenCV, OpenImageIO, Ceres, CGAL, OpenMesh.
std::vector<std::pair<std::string, std::string>> geometryDependencyVersions();

}  // namespace solo
