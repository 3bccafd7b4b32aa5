// Readers and writers: exact round trips, hand-computed decodings, invalid-pixel counts and
// every malformed-file case named in the scene-format contract.

#include <solo/core/atomic_file.h>
#include <solo/core/error.h>
#include <solo/core/image_io.h>

#include "test_support.h"

#include <cmath>
#include <limits>

namespace fs = std::filesystem;
using solo::test::TempDir;

namespace {

// A depth ramp with no symmetry, so flips and transposes show up.
cv::Mat rampDepth(int width, int height) {
  cv::Mat d(height, width, CV_32F);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) d.at<float>(y, x) = 0.5f + 0.37f * x + 11.3f * y;
  return d;
}

std::string messageOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const solo::InputError& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace

TEST(DepthRoundTrip, FloatFormatsAreExact) {
  TempDir dir;
  const cv::Mat depth = rampDepth(7, 5);
  for (const char* name : {"d.exr", "d.tif", "d.pfm", "d.npy"}) {
    SCOPED_TRACE(name);
    solo::writeDepth(dir / name, depth);
    solo::DepthReadStats stats;
    solo::ImageFileInfo info;
    const cv::Mat back = solo::readDepth(dir / name, 0.0, &stats, &info);
    ASSERT_EQ(back.size(), depth.size());
    EXPECT_EQ(cv::norm(back, depth, cv::NORM_INF), 0.0);
    EXPECT_EQ(stats.valid, 35);
    EXPECT_EQ(stats.invalid(), 0);
    EXPECT_FLOAT_EQ(stats.min_m, 0.5f);
    EXPECT_FLOAT_EQ(stats.max_m, 0.5f + 0.37f * 6 + 11.3f * 4);
    EXPECT_EQ(info.width, 7);
    EXPECT_EQ(info.height, 5);
  }
}

TEST(DepthRoundTrip, Png16QuantisesToTheScaleAndKeepsInvalid) {
  TempDir dir;
  cv::Mat depth = rampDepth(6, 4);
  depth.at<float>(1, 2) = 0.f;                 // invalid stays invalid
  depth.at<float>(2, 3) = 0.001f;              // below one code: stored as code 1, not 0
  depth.at<float>(3, 5) = 1000.f;              // beyond 65535 / 256 m: saturates
  const double scale = 1.0 / 256.0;
  solo::writeDepth(dir / "d.png", depth, scale);
  const solo::ImageFileInfo info = solo::probeImage(dir / "d.png");
  EXPECT_EQ(info.pixel_type, "uint16");
  EXPECT_EQ(info.channels, 1);
  solo::DepthReadStats stats;
  const cv::Mat back = solo::readDepth(dir / "d.png", scale, &stats);
  EXPECT_EQ(stats.zero, 1);
  EXPECT_EQ(stats.valid, 23);
  EXPECT_EQ(back.at<float>(1, 2), 0.f);
  EXPECT_FLOAT_EQ(back.at<float>(2, 3), static_cast<float>(scale));
  EXPECT_FLOAT_EQ(back.at<float>(3, 5), static_cast<float>(65535 * scale));
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 6; ++x) {
      if (depth.at<float>(y, x) > 0.01f && depth.at<float>(y, x) < 200.f) {
        EXPECT_NEAR(back.at<float>(y, x), depth.at<float>(y, x), scale / 2 + 1e-6);
      }
    }
}

TEST(DepthRoundTrip, MillimetrePngUsesTheGivenScale) {
  TempDir dir;
  cv::Mat codes(2, 3, CV_16U);
  codes.at<uint16_t>(0, 0) = 1500;  // 1.5 m
  codes.at<uint16_t>(0, 1) = 0;
  codes.at<uint16_t>(0, 2) = 65535;
  codes.at<uint16_t>(1, 0) = 1;
  codes.at<uint16_t>(1, 1) = 2;
  codes.at<uint16_t>(1, 2) = 3;
  solo::writeImage(dir / "mm.png", codes);
  const cv::Mat d = solo::readDepth(dir / "mm.png", 0.001);
  EXPECT_FLOAT_EQ(d.at<float>(0, 0), 1.5f);
  EXPECT_FLOAT_EQ(d.at<float>(0, 1), 0.f);
  EXPECT_FLOAT_EQ(d.at<float>(0, 2), 65.535f);
  EXPECT_FLOAT_EQ(d.at<float>(1, 2), 0.003f);
}

TEST(DepthStats, CountsZeroNanInfAndNegativeSeparately) {
  TempDir dir;
  cv::Mat raw(1, 8, CV_32F);
  const float values[8] = {2.f, 0.f, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                           -std::numeric_limits<float>::infinity(), -3.f, 1000.f, 0.5f};
  for (int i = 0; i < 8; ++i) raw.at<float>(0, i) = values[i];
  for (const char* name : {"raw.exr", "raw.npy", "raw.pfm"}) {
    SCOPED_TRACE(name);
    solo::writeImage(dir / name, raw);
    solo::DepthReadStats s;
    const cv::Mat d = solo::readDepth(dir / name, 0.0, &s);
    EXPECT_EQ(s.valid, 3);
    EXPECT_EQ(s.zero, 1);
    EXPECT_EQ(s.nan, 1);
    EXPECT_EQ(s.inf, 2);
    EXPECT_EQ(s.negative, 1);
    EXPECT_EQ(s.min_m, 0.5);
    EXPECT_EQ(s.max_m, 1000.0);
    for (int i : {1, 2, 3, 4, 5}) EXPECT_EQ(d.at<float>(0, i), 0.f) << "invalid pixels read as 0";
  }
}

TEST(DepthStats, ScaleAppliesToFloatFilesWhenGiven) {
  TempDir dir;
  cv::Mat mm(1, 2, CV_32F);
  mm.at<float>(0, 0) = 2500.f;
  mm.at<float>(0, 1) = 10.f;
  solo::writeImage(dir / "mm.exr", mm);
  const cv::Mat d = solo::readDepth(dir / "mm.exr", 0.001);
  EXPECT_FLOAT_EQ(d.at<float>(0, 0), 2.5f);
  EXPECT_FLOAT_EQ(d.at<float>(0, 1), 0.01f);
}

TEST(Npy, ReadsFloat64Uint16AndInt64) {
  TempDir dir;
  cv::Mat f64(3, 2, CV_64F);
  for (int i = 0; i < 6; ++i) f64.at<double>(i / 2, i % 2) = 0.25 * (i + 1);
  solo::writeImage(dir / "f64.npy", f64);
  const cv::Mat d = solo::readDepth(dir / "f64.npy", 0.0);
  EXPECT_EQ(d.type(), CV_32F);
  EXPECT_FLOAT_EQ(d.at<float>(2, 1), 1.5f);

  cv::Mat u16(2, 2, CV_16U, cv::Scalar(512));
  solo::writeImage(dir / "u16.npy", u16);
  EXPECT_FLOAT_EQ(solo::readDepth(dir / "u16.npy", 1.0 / 256).at<float>(1, 1), 2.f);

  // Hand-made int64 label file: numpy's default integer type.
  const std::string header = "{'descr': '<i8', 'fortran_order': False, 'shape': (1, 2), }";
  std::string padded = header + std::string(128 - 10 - header.size() - 1, ' ') + "\n";
  std::string file = std::string("\x93NUMPY\x01\x00", 8);
  file.push_back(static_cast<char>(padded.size()));
  file.push_back('\0');
  file += padded;
  const int64_t labels[2] = {26001, 7};
  file.append(reinterpret_cast<const char*>(labels), sizeof labels);
  solo::test::writeText(dir / "labels.npy", file);
  const cv::Mat l = solo::readLabels(dir / "labels.npy");
  EXPECT_EQ(l.type(), CV_32S);
  EXPECT_EQ(l.at<int>(0, 0), 26001);
  EXPECT_EQ(l.at<int>(0, 1), 7);
}

TEST(Npy, RejectsTruncatedBigEndianAndFortranFiles) {
  TempDir dir;
  solo::writeImage(dir / "ok.npy", rampDepth(16, 16));
  const auto full = fs::file_size(dir / "ok.npy");
  solo::test::writeTruncatedCopy(dir / "ok.npy", dir / "short.npy", full - 100);
  EXPECT_NE(messageOf([&] { solo::readDepth(dir / "short.npy", 0); }).find("truncated .npy data"), std::string::npos);

  std::string bytes = solo::test::readText(dir / "ok.npy");
  std::string big = bytes;
  big.replace(big.find("'<f4'"), 5, "'>f4'");
  solo::test::writeText(dir / "big.npy", big);
  EXPECT_NE(messageOf([&] { solo::readDepth(dir / "big.npy", 0); }).find("big-endian"), std::string::npos);

  std::string fortran = bytes;
  fortran.replace(fortran.find("False"), 5, "True ");
  solo::test::writeText(dir / "fortran.npy", fortran);
  EXPECT_NE(messageOf([&] { solo::readDepth(dir / "fortran.npy", 0); }).find("Fortran"), std::string::npos);
}

TEST(Normals, Png8DecodesWithTheContractFormula) {
  TempDir dir;
  cv::Mat codes(1, 3, CV_8UC3);
  codes.at<cv::Vec3b>(0, 0) = {255, 128, 0};   // (1, 1/255, -1) before renormalising
  codes.at<cv::Vec3b>(0, 1) = {0, 0, 0};       // invalid
  codes.at<cv::Vec3b>(0, 2) = {128, 128, 0};   // (1/255, 1/255, -1): unit within 8-bit precision
  solo::writeImage(dir / "n.png", codes);
  solo::NormalReadStats s;
  const cv::Mat n = solo::readNormals(dir / "n.png", &s);
  const double x = 1.0, y = 128.0 / 255.0 * 2.0 - 1.0, z = -1.0, len = std::sqrt(x * x + y * y + z * z);
  EXPECT_NEAR(n.at<cv::Vec3f>(0, 0)[0], x / len, 1e-6);
  EXPECT_NEAR(n.at<cv::Vec3f>(0, 0)[1], y / len, 1e-6);
  EXPECT_NEAR(n.at<cv::Vec3f>(0, 0)[2], z / len, 1e-6);
  EXPECT_EQ(n.at<cv::Vec3f>(0, 1), cv::Vec3f(0, 0, 0));
  EXPECT_EQ(s.valid, 2);
  EXPECT_EQ(s.invalid, 1);
  EXPECT_EQ(s.renormalised, 1) << "only the first normal is far from unit length";
}

TEST(Normals, Png16RoundTripWithinQuantisation) {
  TempDir dir;
  cv::Mat n(4, 5, CV_32FC3);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 5; ++x) {
      cv::Vec3f v(0.3f * (x - 2), 0.2f * (y - 1.5f), -1.f);
      n.at<cv::Vec3f>(y, x) = v / cv::norm(v);
    }
  n.at<cv::Vec3f>(0, 0) = {0, 0, 0};
  solo::writeNormals(dir / "n.png", n);
  solo::NormalReadStats s;
  const cv::Mat back = solo::readNormals(dir / "n.png", &s);
  EXPECT_EQ(s.invalid, 1);
  EXPECT_EQ(s.valid, 19);
  EXPECT_EQ(s.renormalised, 0);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 5; ++x) {
      if (x == 0 && y == 0) continue;
      const cv::Vec3d a = n.at<cv::Vec3f>(y, x), b = back.at<cv::Vec3f>(y, x);
      const double angle = std::atan2(cv::norm(a.cross(b)), a.dot(b));  // exact near 0, unlike acos
      EXPECT_LT(angle, 1e-4) << "angle error at " << x << "," << y;
    }
}

TEST(Normals, FloatNonUnitAreRenormalisedAndCounted) {
  TempDir dir;
  cv::Mat n(1, 4, CV_32FC3);
  n.at<cv::Vec3f>(0, 0) = {0, 0, -2};   // renormalised
  n.at<cv::Vec3f>(0, 1) = {0, 0.6f, -0.8f};  // unit already
  n.at<cv::Vec3f>(0, 2) = {0, 0, 0};    // invalid
  n.at<cv::Vec3f>(0, 3) = {0, 0, 0.5f}; // renormalised
  solo::writeImage(dir / "n.exr", n);
  solo::NormalReadStats s;
  const cv::Mat back = solo::readNormals(dir / "n.exr", &s);
  EXPECT_EQ(s.valid, 3);
  EXPECT_EQ(s.invalid, 1);
  EXPECT_EQ(s.renormalised, 2);
  EXPECT_EQ(back.at<cv::Vec3f>(0, 0), cv::Vec3f(0, 0, -1));
  EXPECT_EQ(back.at<cv::Vec3f>(0, 3), cv::Vec3f(0, 0, 1));
}

TEST(Labels, Uint16CityscapesIdsRoundTrip) {
  TempDir dir;
  cv::Mat ids(2, 2, CV_16U);
  ids.at<uint16_t>(0, 0) = 26001;
  ids.at<uint16_t>(0, 1) = 7;
  ids.at<uint16_t>(1, 0) = 33999;
  ids.at<uint16_t>(1, 1) = 0;
  solo::writeImage(dir / "ids.png", ids);
  const cv::Mat l = solo::readLabels(dir / "ids.png");
  EXPECT_EQ(l.type(), CV_32S);
  EXPECT_EQ(l.at<int>(0, 0), 26001);
  EXPECT_EQ(l.at<int>(1, 0), 33999);
  EXPECT_EQ(l.at<int>(1, 1), 0);
}

TEST(ColorImage, EightAndSixteenBitScaleToUnitRange) {
  TempDir dir;
  cv::Mat rgb8(1, 1, CV_8UC3, cv::Scalar(255, 51, 0));
  solo::writeImage(dir / "c.png", rgb8);
  cv::Vec3f c = solo::readColorImage(dir / "c.png").at<cv::Vec3f>(0, 0);
  EXPECT_FLOAT_EQ(c[0], 1.f);
  EXPECT_FLOAT_EQ(c[1], 0.2f);
  EXPECT_FLOAT_EQ(c[2], 0.f);
  cv::Mat rgba16(1, 1, CV_16UC4, cv::Scalar(0, 65535, 13107, 65535));
  solo::writeImage(dir / "c16.png", rgba16);
  c = solo::readColorImage(dir / "c16.png").at<cv::Vec3f>(0, 0);
  EXPECT_FLOAT_EQ(c[1], 1.f);
  EXPECT_FLOAT_EQ(c[2], 0.2f);
}

// ------------------------------------------------------------------------ bad input

TEST(BadInput, MissingFileNamesThePath) {
  TempDir dir;
  const std::string m = messageOf([&] { solo::readDepth(dir / "nope.png", 0.001); });
  EXPECT_NE(m.find("nope.png"), std::string::npos);
  EXPECT_NE(m.find("file not found"), std::string::npos);
}

TEST(BadInput, TruncatedPngIsReportedNotHalfRead) {
  TempDir dir;
  cv::Mat noise(64, 64, CV_16U);
  cv::randu(noise, 1, 60000);
  solo::writeImage(dir / "full.png", noise);
  solo::test::writeTruncatedCopy(dir / "full.png", dir / "cut.png", fs::file_size(dir / "full.png") / 2);
  const std::string m = messageOf([&] { solo::readDepth(dir / "cut.png", 0.001); });
  EXPECT_NE(m.find("cut.png"), std::string::npos);
  EXPECT_NE(m.find("truncated or corrupt"), std::string::npos) << m;
}

TEST(BadInput, TruncatedExrIsReported) {
  TempDir dir;
  cv::Mat noise(64, 64, CV_32F);
  cv::randu(noise, 1, 100);
  solo::writeImage(dir / "full.exr", noise);
  solo::test::writeTruncatedCopy(dir / "full.exr", dir / "cut.exr", fs::file_size(dir / "full.exr") / 2);
  const std::string m = messageOf([&] { solo::readDepth(dir / "cut.exr", 0); });
  EXPECT_NE(m.find("cut.exr"), std::string::npos);
  EXPECT_NE(m, "no error");
}

TEST(BadInput, NotAnImage) {
  TempDir dir;
  solo::test::writeText(dir / "text.png", "this is not a png");
  const std::string m = messageOf([&] { solo::readLabels(dir / "text.png"); });
  EXPECT_NE(m.find("text.png"), std::string::npos);
  EXPECT_NE(m.find("cannot read as an image"), std::string::npos) << m;
  solo::test::writeText(dir / "empty.exr", "");
  EXPECT_NE(messageOf([&] { solo::readDepth(dir / "empty.exr", 0); }).find("file is empty"), std::string::npos);
}

TEST(BadInput, WrongBitDepthAndChannelCount) {
  TempDir dir;
  solo::writeImage(dir / "d8.png", cv::Mat(4, 4, CV_8U, cv::Scalar(9)));
  EXPECT_NE(messageOf([&] { solo::readDepth(dir / "d8.png", 0.001); }).find("8-bit depth"), std::string::npos);

  solo::writeImage(dir / "rgb16.png", cv::Mat(4, 4, CV_16UC3, cv::Scalar(9, 9, 9)));
  EXPECT_NE(messageOf([&] { solo::readDepth(dir / "rgb16.png", 0.001); }).find("one channel"), std::string::npos);
  EXPECT_NE(messageOf([&] { solo::readLabels(dir / "rgb16.png"); }).find("one channel"), std::string::npos);

  solo::writeImage(dir / "grey.png", cv::Mat(4, 4, CV_16U, cv::Scalar(9)));
  EXPECT_NE(messageOf([&] { solo::readNormals(dir / "grey.png"); }).find("3 channels"), std::string::npos);
  EXPECT_NE(messageOf([&] { solo::readDepth(dir / "grey.png", 0); }).find("needs a scale"), std::string::npos);

  solo::writeImage(dir / "float_labels.exr", cv::Mat(4, 4, CV_32F, cv::Scalar(3)));
  EXPECT_NE(messageOf([&] { solo::readLabels(dir / "float_labels.exr"); }).find("integers"), std::string::npos);
}

TEST(AtomicWrite, FailedWriteLeavesNoFileAndKeepsTheOldOne) {
  TempDir dir;
  EXPECT_THROW(solo::writeAtomically(dir / "out.png",
                                     [](const fs::path& tmp) {
                                       solo::test::writeText(tmp, "half");
                                       throw std::runtime_error("disk full");
                                     }),
               std::runtime_error);
  EXPECT_TRUE(solo::test::listFolder(dir.path()).empty());

  solo::writeTextAtomically(dir / "keep.txt", "old");
  EXPECT_THROW(solo::writeAtomically(dir / "keep.txt",
                                     [](const fs::path&) { throw std::runtime_error("crash"); }),
               std::runtime_error);
  EXPECT_EQ(solo::test::readText(dir / "keep.txt"), "old");
  EXPECT_EQ(solo::test::listFolder(dir.path()), std::vector<std::string>{"keep.txt"});

  // A writer failure inside the image writer itself (unsupported type) leaves nothing.
  EXPECT_THROW(solo::writeImage(dir / "bad.png", cv::Mat(2, 2, CV_16S)), solo::InputError);
  EXPECT_EQ(solo::test::listFolder(dir.path()), std::vector<std::string>{"keep.txt"});
}
