#include "solo/core/version.h"

#include "solo_config.h"

#include <CGAL/version.h>
#include <Eigen/Core>
#include <OpenImageIO/oiioversion.h>
#include <OpenMesh/Core/System/config.h>
#include <ceres/version.h>
#include <opencv2/core/version.hpp>

#define SOLO_STR2(x) #x
#define SOLO_STR(x) SOLO_STR2(x)

namespace solo {

std::string soloVersion() { return SOLO_VERSION; }

std::vector<std::pair<std::string, std::string>> geometryDependencyVersions() {
  const unsigned om = OM_VERSION;
  return {
      {"Eigen", SOLO_STR(EIGEN_WORLD_VERSION) "." SOLO_STR(EIGEN_MAJOR_VERSION) "." SOLO_STR(EIGEN_MINOR_VERSION)},
      {"OpenCV", CV_VERSION},
      {"OpenImageIO", OIIO_VERSION_STRING},
      {"Ceres", CERES_VERSION_STRING},
      {"CGAL", CGAL_VERSION_STR},
      {"OpenMesh", std::to_string((om >> 16) & 0xff) + "." + std::to_string((om >> 8) & 0xff) + "." +
                       std::to_string(om & 0xff)},
  };
}

}  // namespace solo
