# Every dependency is a Debian 12 package installed by tools/setup.sh.
# Order and modes matter (measured, see docs/building.md):
#  - OpenImageIO's config needs the openimageio-tools package;
#  - CGAL puts its own Find modules on the module path, so OpenMesh and TBB are
#    looked up in CONFIG mode after it;
#  - hole fairing needs CGAL's Eigen support target.
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(OpenCV 4 REQUIRED COMPONENTS core imgproc imgcodecs ximgproc)
find_package(OpenImageIO CONFIG REQUIRED)
find_package(Ceres REQUIRED)
find_package(embree 3 REQUIRED)
find_package(CGAL REQUIRED)
include(CGAL_Eigen3_support)
find_package(OpenMesh CONFIG REQUIRED)
find_package(TBB CONFIG REQUIRED)
find_package(CLI11 CONFIG REQUIRED)
find_package(nlohmann_json 3 CONFIG REQUIRED)
if(SOLO_BUILD_TESTS)
  find_package(GTest CONFIG REQUIRED)
  # libtiff (libtiff-dev) writes the synthetic DNG files of the raw gray-card tests.
  find_package(TIFF REQUIRED)
endif()
if(SOLO_BUILD_BENCHMARKS)
  find_package(benchmark CONFIG REQUIRED)
endif()
