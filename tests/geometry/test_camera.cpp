#include <solo/core/camera.h>
#include <solo/core/error.h>

#include "test_support.h"

using solo::PinholeCamera;

TEST(Camera, AcdcHalfResolutionKeepsTheCentrePixelCentred) {
  const PinholeCamera c = PinholeCamera::acdc().scaledTo(960, 540);
  EXPECT_DOUBLE_EQ(c.fx, 890.0);
  EXPECT_DOUBLE_EQ(c.fy, 890.0);
  EXPECT_DOUBLE_EQ(c.cx, 479.5);  // (959.5 + 0.5) / 2 - 0.5 = (960 - 1) / 2
  EXPECT_DOUBLE_EQ(c.cy, 269.5);
  EXPECT_EQ(c.width, 960);
  EXPECT_EQ(c.height, 540);
}

TEST(Camera, ScalingPreservesTheRayThroughEveryPixelEdge) {
  // The left edge of pixel 0 (u = -0.5) and the right edge of the last pixel map onto
  // each other at any resolution: the field of view is unchanged.
  const PinholeCamera a{1000, 900, 640.3, 350.7, 1280, 720};
  const PinholeCamera b = a.scaledTo(320, 180);
  for (double edge_a : {-0.5, 1279.5}) {
    const double edge_b = (edge_a + 0.5) * 0.25 - 0.5;
    EXPECT_NEAR((edge_a - a.cx) / a.fx, (edge_b - b.cx) / b.fx, 1e-12);
  }
  const PinholeCamera up = b.scaledTo(1280, 720);
  EXPECT_NEAR(up.cx, a.cx, 1e-12);
  EXPECT_NEAR(up.cy, a.cy, 1e-12);
}

TEST(Camera, BackprojectThenProjectIsIdentity) {
  const PinholeCamera c = PinholeCamera::acdc();
  const Eigen::Vector3d p = c.backproject(100.25, 900.5, 37.0);
  EXPECT_DOUBLE_EQ(p.z(), 37.0);
  EXPECT_NEAR(p.x(), 37.0 * (100.25 - 959.5) / 1780.0, 1e-12);
  const Eigen::Vector2d uv = c.project(p);
  EXPECT_NEAR(uv.x(), 100.25, 1e-9);
  EXPECT_NEAR(uv.y(), 900.5, 1e-9);
}

TEST(Camera, ImpossibleCamerasAreRejectedNamingTheSource) {
  auto message = [](PinholeCamera c) {
    try {
      solo::validateCamera(c, "cam.json");
    } catch (const solo::InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(message({1780, 1780, 959.5, 539.5, 1920, 1080}), "accepted");
  EXPECT_EQ(message({1780, 1780, -900, 1500, 1920, 1080}), "accepted") << "shifted but plausible";
  EXPECT_NE(message({0, 1780, 959.5, 539.5, 1920, 1080}).find("focal lengths must be positive"), std::string::npos);
  EXPECT_NE(message({1780, -5, 959.5, 539.5, 1920, 1080}).find("cam.json"), std::string::npos);
  EXPECT_NE(message({1780, 1780, 5000, 539.5, 1920, 1080}).find("principal point"), std::string::npos);
  EXPECT_NE(message({1780, 1780, 959.5, -600, 1920, 1080}).find("principal point"), std::string::npos);
  EXPECT_NE(message({NAN, 1780, 959.5, 539.5, 1920, 1080}).find("finite"), std::string::npos);
}

TEST(Camera, CityscapesJson) {
  solo::test::TempDir dir;
  solo::test::writeText(dir / "c.json",
                        R"({"extrinsic": {"baseline": 0.209313, "pitch": 0.038, "roll": 0, "yaw": -0.0195,)"
                        R"( "x": 1.7, "y": 0.1, "z": 1.22},)"
                        R"( "intrinsic": {"fx": 2262.52, "fy": 2265.3017905988554, "u0": 1096.98, "v0": 513.137}})");
  const PinholeCamera c = solo::readCityscapesCamera(dir / "c.json");
  EXPECT_DOUBLE_EQ(c.fx, 2262.52);
  EXPECT_DOUBLE_EQ(c.fy, 2265.3017905988554);
  EXPECT_DOUBLE_EQ(c.cx, 1096.98);
  EXPECT_DOUBLE_EQ(c.cy, 513.137);

  solo::test::writeText(dir / "bad.json", R"({"intrinsic": {"fx": "2262", "fy": 1, "u0": 1, "v0": 1}})");
  try {
    solo::readCityscapesCamera(dir / "bad.json");
    FAIL() << "a string focal length was accepted";
  } catch (const solo::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("\"fx\" must be a number"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("bad.json"), std::string::npos);
  }
}
