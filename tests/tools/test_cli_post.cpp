// `solo post` and `solo fda` end to end: files in, files and reports out, errors named.

#include <solo/core/image_io.h>

#include "test_support.h"

#include <cmath>

using solo::test::runSolo;
using solo::test::TempDir;

namespace {

/// X = Y = Z = 1 / 2^3.25: white E that the default exposure brings to exactly 1.
cv::Mat unitWhiteE(int rows, int cols) { return cv::Mat(rows, cols, CV_32FC3, cv::Scalar::all(std::exp2(-3.25))); }

}  // namespace

TEST(CliPost, WhiteEBecomesWhiteIn8And16BitPngAndLinearExr) {
  TempDir dir;
  solo::writeImage(dir / "render.exr", unitWhiteE(20, 30));
  const std::string in = (dir / "render.exr").string();
  auto r = runSolo("post " + in + " -o " + (dir / "out.png").string() + " --no-noise --no-glare --report " +
                   (dir / "r.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  solo::ImageFileInfo info;
  cv::Mat png = solo::readImageRaw(dir / "out.png", &info);
  EXPECT_EQ(info.pixel_type, "uint8");
  EXPECT_EQ(png.size(), cv::Size(30, 20));
  EXPECT_EQ(cv::norm(png, cv::Mat(png.size(), png.type(), cv::Scalar::all(255)), cv::NORM_INF), 0.0);
  const std::string report = solo::test::readText(dir / "r.json");
  for (const char* key : {"\"glare\"", "\"noise\"", "switched off (no glare)", "\"adaptation\"", "\"write\""})
    EXPECT_NE(report.find(key), std::string::npos) << key;

  r = runSolo("post " + in + " -o " + (dir / "out16.png").string() + " --16bit --no-noise --no-glare");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  png = solo::readImageRaw(dir / "out16.png", &info);
  EXPECT_EQ(info.pixel_type, "uint16");
  EXPECT_EQ(png.at<cv::Vec3f>(3, 4), cv::Vec3f(65535, 65535, 65535));

  r = runSolo("post " + in + " -o " + (dir / "out.exr").string() + " --no-noise --no-glare");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const cv::Mat exr = solo::readImageRaw(dir / "out.exr");
  EXPECT_NEAR(exr.at<cv::Vec3f>(5, 5)[0], 1.0, 1e-3);  // half float
  EXPECT_NEAR(exr.at<cv::Vec3f>(5, 5)[2], 1.0, 1e-3);
}

TEST(CliPost, CameraSettingsAndNoiseAreSeeded) {
  TempDir dir;
  solo::writeImage(dir / "render.exr", unitWhiteE(16, 16) * 0.05);
  const std::string in = (dir / "render.exr").string();
  // f/1: two stops more than the reference camera: 0.05 * 2^2 = 0.2 after exposure.
  auto r = runSolo("post " + in + " -o " + (dir / "cam.exr").string() + " --f-number 1 --no-noise --no-glare");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NEAR(solo::readImageRaw(dir / "cam.exr").at<cv::Vec3f>(8, 8)[1], 0.2, 1e-3);
  for (const char* name : {"a.png", "b.png"})
    ASSERT_EQ(runSolo("post " + in + " -o " + (dir / name).string() + " --seed 5").exit_code, 0);
  ASSERT_EQ(runSolo("post " + in + " -o " + (dir / "c.png").string() + " --seed 6").exit_code, 0);
  const cv::Mat a = solo::readImageRaw(dir / "a.png"), b = solo::readImageRaw(dir / "b.png"),
                c = solo::readImageRaw(dir / "c.png");
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(a, c, cv::NORM_INF), 0.0);
}

TEST(CliPost, BadInputsAreNamed) {
  TempDir dir;
  auto r = runSolo("post " + (dir / "missing.exr").string() + " -o " + (dir / "o.png").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("solo: error: "), std::string::npos);
  EXPECT_NE(r.output.find("missing.exr"), std::string::npos);
  solo::writeImage(dir / "grey.exr", cv::Mat(4, 4, CV_32F, cv::Scalar(0.5)));
  r = runSolo("post " + (dir / "grey.exr").string() + " -o " + (dir / "o.png").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("expected 3 channels"), std::string::npos);
  solo::writeImage(dir / "render.exr", unitWhiteE(4, 4));
  r = runSolo("post " + (dir / "render.exr").string() + " -o " + (dir / "o.png").string() + " --iso 12800");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("solo: error: --iso: "), std::string::npos);
  r = runSolo("post " + (dir / "render.exr").string() + " -o " + (dir / "o.bmp").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("unsupported output format"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir / "o.png"));
}

TEST(CliFda, BetaZeroReproducesTheDayImageAndABandTakesTheNightMean) {
  TempDir dir;
  cv::Mat day(60, 80, CV_8UC3), night(60, 80, CV_8UC3, cv::Scalar(60, 90, 120));
  cv::randu(day, 90, 130);
  solo::writeImage(dir / "day.png", day);
  solo::writeImage(dir / "night.png", night);
  const std::string io = "fda --source " + (dir / "day.png").string() + " --target " + (dir / "night.png").string();
  auto r = runSolo(io + " -o " + (dir / "same.png").string() + " --beta 0");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  cv::Mat same = solo::readImageRaw(dir / "same.png"), day_float;
  day.convertTo(day_float, CV_32FC3);
  EXPECT_EQ(cv::norm(same, day_float, cv::NORM_INF), 0.0);
  r = runSolo(io + " -o " + (dir / "dark.png").string() + " --beta 0.05 --report " + (dir / "r.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const cv::Scalar mean = cv::mean(solo::readImageRaw(dir / "dark.png"));
  // The flat night has only a DC term: the output is the day's detail around the night's
  // mean (nothing clips here), to within the 8-bit rounding.
  EXPECT_NEAR(mean[0], 60, 0.5);
  EXPECT_NEAR(mean[1], 90, 0.5);
  EXPECT_NEAR(mean[2], 120, 0.5);
  EXPECT_NE(solo::test::readText(dir / "r.json").find("band_half_size"), std::string::npos);
  r = runSolo(io + " -o " + (dir / "x.png").string() + " --beta 2");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--beta"), std::string::npos);
}
