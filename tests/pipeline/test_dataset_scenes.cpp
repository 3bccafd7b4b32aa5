// `solo scenes`: datasets as they come (docs/datasets.md). Tiny Cityscapes, KITTI and ACDC folders
// made from synthetic data: the walk's manifests load with the right depth, camera and labels,
// frames without depth are reported, bad roots and splits get clear errors; and one batch converts
// the Cityscapes folder with the night images in its own layout.

#include <solo/core/error.h>
#include <solo/core/image_io.h>
#include <solo/core/scene.h>
#include <solo/pipeline/dataset_scenes.h>

#include "test_support.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <string>

namespace fs = std::filesystem;
using solo::test::readText;
using solo::test::runSolo;
using solo::test::TempDir;
using solo::test::writeText;

namespace {

constexpr int kWidth = 64, kHeight = 32;
constexpr double kFocalPx = 60, kBaselineM = 0.2;

// The true depth of the synthetic street: sky in the top 4 rows (no disparity), a wall at 20 m
// down to the horizon, then a road 1.5 m below the camera.
double trueDepthM(int y) {
  if (y < 4) return 0;
  if (y <= 17) return 20;
  return kFocalPx * 1.5 / (y - 15.5);
}

// Cityscapes' disparity encoding of a depth: p = disparity * 256 + 1, 0 = none.
cv::Mat disparityOf(int height, int width) {
  cv::Mat p(height, width, CV_16U, cv::Scalar(0));
  for (int y = 0; y < height; ++y)
    if (trueDepthM(y) > 0) p.row(y).setTo(std::lround(256 * kBaselineM * kFocalPx / trueDepthM(y)) + 1);
  return p;
}

// One Cityscapes frame: the day image, and (with `stereo`) its disparity and camera, plus gtFine.
void writeCityscapesFrame(const fs::path& root, const std::string& split, const std::string& city,
                          const std::string& id, bool stereo) {
  const fs::path where = fs::path(split) / city;
  for (const char* folder : {"leftImg8bit", "disparity", "camera", "gtFine"}) fs::create_directories(root / folder / where);
  cv::Mat day(kHeight, kWidth, CV_8UC3, cv::Scalar(110, 110, 105));  // road
  day.rowRange(4, 18).setTo(cv::Scalar(140, 100, 80));                 // wall
  day.rowRange(0, 4).setTo(cv::Scalar(120, 160, 220));                 // sky
  cv::Mat instances(kHeight, kWidth, CV_16U, cv::Scalar(7));
  instances.rowRange(4, 18).setTo(11);
  instances.rowRange(0, 4).setTo(23);
  instances(cv::Rect(20, 20, 10, 6)).setTo(26000);
  day(cv::Rect(20, 20, 10, 6)).setTo(cv::Scalar(180, 20, 20));
  cv::Mat labels = instances.clone();
  labels(cv::Rect(20, 20, 10, 6)).setTo(26);
  solo::writeImage(root / "leftImg8bit" / where / (id + "_leftImg8bit.png"), day);
  solo::writeImage(root / "gtFine" / where / (id + "_gtFine_instanceIds.png"), instances);
  solo::writeImage(root / "gtFine" / where / (id + "_gtFine_labelIds.png"), labels);
  if (!stereo) return;
  solo::writeImage(root / "disparity" / where / (id + "_disparity.png"), disparityOf(kHeight, kWidth));
  writeText(root / "camera" / where / (id + "_camera.json"),
            R"({"extrinsic": {"baseline": 0.2, "pitch": 0.0, "roll": 0.0, "yaw": 0.0, "x": 1.7, "y": 0.0, "z": 1.2},
                "intrinsic": {"fx": 60.0, "fy": 60.0, "u0": 31.5, "v0": 15.5}})");
}

// Two train frames with stereo, one val frame without.
fs::path writeCityscapes(const TempDir& dir) {
  const fs::path root = dir / "cityscapes";
  writeCityscapesFrame(root, "train", "aachen", "aachen_000000_000019", true);
  writeCityscapesFrame(root, "train", "aachen", "aachen_000001_000019", true);
  writeCityscapesFrame(root, "val", "lindau", "lindau_000000_000019", false);
  return root;
}

std::string walkError(const solo::DatasetScenesOptions& options) {
  try {
    solo::findDatasetFrames(options);
  } catch (const solo::InputError& e) {
    return e.what();
  }
  return "walked";
}

std::string quoted(const fs::path& p) { return "\"" + p.string() + "\""; }

}  // namespace

TEST(DatasetScenes, CityscapesFramesGetManifestsWithTheirDisparityAsDepth) {
  TempDir dir;
  solo::DatasetScenesOptions options;
  options.root = writeCityscapes(dir);
  options.output_folder = dir / "manifests";
  const solo::DatasetScenesResult result = solo::writeDatasetScenes(options);

  ASSERT_EQ(result.manifests.size(), 2u);
  EXPECT_EQ(result.walk.splits, (std::vector<std::string>{"train", "val"}));
  ASSERT_EQ(result.walk.skipped.size(), 1u) << "the val frame has no disparity";
  EXPECT_EQ(result.walk.skipped[0].image.filename(), "lindau_000000_000019_leftImg8bit.png");
  EXPECT_NE(result.walk.skipped[0].reason.find("no disparity"), std::string::npos) << result.walk.skipped[0].reason;
  const fs::path manifest = dir / "manifests/train/aachen/aachen_000000_000019_leftImg8bit.scene.json";
  EXPECT_EQ(result.manifests[0], manifest);
  EXPECT_EQ(readText(result.list).find("train/aachen/aachen_000000_000019_leftImg8bit.scene.json\n") == std::string::npos,
            false)
      << readText(result.list);

  const nlohmann::json j = nlohmann::json::parse(readText(manifest));
  EXPECT_EQ(j["name"], "train/aachen/aachen_000000_000019_leftImg8bit");
  EXPECT_EQ(j["depth"]["disparity"], true);

  const solo::Scene s = solo::loadScene(manifest);
  EXPECT_EQ(s.width(), kWidth);
  EXPECT_EQ(s.image.at<cv::Vec3f>(0, 0), s.image.at<cv::Vec3f>(0, 1)) << "the dataset's image, read in place";
  EXPECT_EQ(s.manifest.image, options.root / "leftImg8bit/train/aachen/aachen_000000_000019_leftImg8bit.png");
  EXPECT_DOUBLE_EQ(s.camera.fx, 60.0);
  EXPECT_FALSE(s.camera_is_default);
  EXPECT_EQ(s.depth_stats.zero, 4 * kWidth) << "the sky has no disparity";
  const cv::Mat p = disparityOf(kHeight, kWidth);
  for (const int y : {4, 10, 17, 18, 25, 31}) {
    const double stored = p.at<uint16_t>(y, 7);
    EXPECT_EQ(s.depth_m.at<float>(y, 7), static_cast<float>(kBaselineM * kFocalPx / ((stored - 1) / 256.0))) << y;
    EXPECT_NEAR(s.depth_m.at<float>(y, 7), trueDepthM(y), 0.01 * trueDepthM(y)) << y;
  }
  EXPECT_EQ(s.instances.at<int>(22, 22), 26000);
  EXPECT_EQ(s.labels.at<int>(22, 22), 26);
}

TEST(DatasetScenes, ADepthFolderReplacesTheDisparityAndNamesWhatIsMissing) {
  TempDir dir;
  solo::DatasetScenesOptions options;
  options.root = writeCityscapes(dir);
  options.depth_folder = dir / "mono";
  fs::create_directories(dir / "mono/val/lindau");
  fs::create_directories(dir / "mono/train/aachen");
  // A monocular network's float metres, by day image stem (.npy) or by frame id (.pfm).
  solo::writeImage(dir / "mono/val/lindau/lindau_000000_000019_leftImg8bit.npy",
                   cv::Mat(kHeight, kWidth, CV_32F, cv::Scalar(7.5f)));
  solo::writeImage(dir / "mono/train/aachen/aachen_000001_000019.pfm", cv::Mat(kHeight, kWidth, CV_32F, cv::Scalar(9.f)));
  const solo::DatasetWalk walk = solo::findDatasetFrames(options);
  ASSERT_EQ(walk.frames.size(), 2u);
  EXPECT_EQ(walk.frames[0].name, "train/aachen/aachen_000001_000019_leftImg8bit");
  EXPECT_EQ(walk.frames[1].name, "val/lindau/lindau_000000_000019_leftImg8bit");
  ASSERT_EQ(walk.skipped.size(), 1u);
  EXPECT_NE(walk.skipped[0].reason.find("mono/train/aachen/aachen_000000_000019_leftImg8bit.{npy,exr,pfm,tif,tiff}"),
            std::string::npos)
      << walk.skipped[0].reason;

  options.output_folder = dir / "m";
  const solo::DatasetScenesResult result = solo::writeDatasetScenes(options);
  const solo::Scene val = solo::loadScene(result.manifests[1]);
  EXPECT_FLOAT_EQ(val.depth_m.at<float>(3, 3), 7.5f);
  EXPECT_TRUE(val.camera_is_default) << "the val frame has no camera file";
  const solo::Scene train = solo::loadScene(result.manifests[0]);
  EXPECT_FLOAT_EQ(train.depth_m.at<float>(0, 0), 9.f);
  EXPECT_DOUBLE_EQ(train.camera.fx, 60.0) << "the Cityscapes camera is kept with another depth";
}

TEST(DatasetScenes, MissingRootsSplitsAndFramesAreClearErrors) {
  TempDir dir;
  solo::DatasetScenesOptions options;
  options.root = dir / "nowhere";
  EXPECT_NE(walkError(options).find("nowhere: not found"), std::string::npos) << walkError(options);

  fs::create_directories(dir / "empty");
  options.root = dir / "empty";
  EXPECT_NE(walkError(options).find("no frame found: looked for " + (dir / "empty/leftImg8bit").string() +
                                    "/<split>/<city>/*_leftImg8bit.png"),
            std::string::npos)
      << walkError(options);

  options.root = writeCityscapes(dir);
  options.split = "test";
  EXPECT_NE(walkError(options).find("no split \"test\" here; the splits are: train, val"), std::string::npos)
      << walkError(options);
  options.split = "val";
  const std::string none = walkError(options);
  EXPECT_NE(none.find("1 frames found but none can be used"), std::string::npos) << none;
  EXPECT_NE(none.find("--depth DIR"), std::string::npos) << none;

  options.dataset = solo::Dataset::Acdc;
  options.split.clear();
  fs::create_directories(dir / "acdc/rgb_anon/fog/train/GOPR0475");
  options.root = dir / "acdc";
  EXPECT_NE(walkError(options).find("--depth: ACDC has no depth maps"), std::string::npos) << walkError(options);
}

TEST(DatasetScenes, KittiRawFramesWithTheirDepthAnnotationsAndCalibration) {
  TempDir dir;
  const fs::path root = dir / "kitti";
  const fs::path drive = root / "2011_09_26/2011_09_26_drive_0001_sync";
  fs::create_directories(drive / "image_02/data");
  fs::create_directories(root / "train/2011_09_26_drive_0001_sync/proj_depth/groundtruth/image_02");
  writeText(root / "2011_09_26/calib_cam_to_cam.txt",
            "S_rect_02: 1.242000e+03 3.750000e+02\n"
            "P_rect_02: 7.215377e+02 0.000000e+00 6.095593e+02 4.485728e+01 0.000000e+00 7.215377e+02 "
            "1.728540e+02 2.163791e-01 0.000000e+00 0.000000e+00 1.000000e+00 2.745884e-03\n");
  for (const char* frame : {"0000000005", "0000000006"})
    solo::writeImage(drive / "image_02/data" / (std::string(frame) + ".png"), cv::Mat(75, 248, CV_8UC3, cv::Scalar(90)));
  // Depth-completion annotations exist for frame 5 only (the first and last 5 frames have none).
  solo::writeImage(root / "train/2011_09_26_drive_0001_sync/proj_depth/groundtruth/image_02/0000000005.png",
                   cv::Mat(75, 248, CV_16U, cv::Scalar(2560)));
  solo::DatasetScenesOptions options;
  options.dataset = solo::Dataset::Kitti;
  options.root = root;
  options.output_folder = dir / "m";
  const solo::DatasetScenesResult result = solo::writeDatasetScenes(options);
  EXPECT_EQ(result.walk.splits, std::vector<std::string>{"train"});
  ASSERT_EQ(result.manifests.size(), 1u);
  ASSERT_EQ(result.walk.skipped.size(), 1u);
  EXPECT_NE(result.walk.skipped[0].reason.find("no depth annotation"), std::string::npos);
  EXPECT_EQ(result.manifests[0], dir / "m/2011_09_26/2011_09_26_drive_0001_sync/image_02/data/0000000005.scene.json");
  const solo::Scene s = solo::loadScene(result.manifests[0]);
  EXPECT_FLOAT_EQ(s.depth_m.at<float>(10, 10), 10.f) << "1/256 m";
  EXPECT_NEAR(s.camera.fx, 721.5377 * 248 / 1242, 1e-9) << "P_rect_02 at S_rect_02 (1242x375), scaled to 248x75";
  EXPECT_EQ(solo::datasetNightImage(solo::Dataset::Kitti, "2011_09_26/d/image_02/data/0000000005", "m.json"),
            fs::path("kitti_raw_night/2011_09_26/d/image_02/data/0000000005.png"));
  options.split = "val";
  EXPECT_NE(walkError(options).find("no split \"val\" here; the splits are: train"), std::string::npos)
      << walkError(options);
}

TEST(DatasetScenes, AcdcFramesTakeTheirDepthFromADepthFolderAndLeaveNightOut) {
  TempDir dir;
  const fs::path root = dir / "acdc";
  for (const char* condition : {"fog", "night"}) {
    fs::create_directories(root / "rgb_anon" / condition / "train/GOPR0475");
    fs::create_directories(root / "gt" / condition / "train/GOPR0475");
    solo::writeImage(root / "rgb_anon" / condition / "train/GOPR0475/GOPR0475_frame_000041_rgb_anon.png",
                     cv::Mat(27, 48, CV_8UC3, cv::Scalar(100)));
    solo::writeImage(root / "gt" / condition / "train/GOPR0475/GOPR0475_frame_000041_gt_labelIds.png",
                     cv::Mat(27, 48, CV_8U, cv::Scalar(7)));
  }
  fs::create_directories(dir / "depth/fog/train/GOPR0475");
  solo::writeImage(dir / "depth/fog/train/GOPR0475/GOPR0475_frame_000041_rgb_anon.exr",
                   cv::Mat(27, 48, CV_32F, cv::Scalar(4.f)));
  solo::DatasetScenesOptions options;
  options.dataset = solo::Dataset::Acdc;
  options.root = root;
  options.depth_folder = dir / "depth";
  options.output_folder = dir / "m";
  const solo::DatasetScenesResult result = solo::writeDatasetScenes(options);
  ASSERT_EQ(result.manifests.size(), 1u);
  EXPECT_EQ(result.walk.notes.size(), 1u);
  const solo::Scene s = solo::loadScene(result.manifests[0]);
  EXPECT_EQ(s.labels.at<int>(0, 0), 7);
  EXPECT_TRUE(s.camera_is_default) << "ACDC's own intrinsics are the default camera";
  EXPECT_DOUBLE_EQ(s.camera.fx, 1780.0 * 48 / 1920);
}

TEST(DatasetScenes, OneBatchConvertsACityscapesFolderIntoItsOwnLayout) {
  TempDir dir;
  const fs::path root = writeCityscapes(dir);
  auto r = runSolo("scenes cityscapes " + quoted(root) + " -o " + quoted(dir / "m"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("2 manifests written, 1 frames skipped"), std::string::npos) << r.output;

  const std::string batch = "night --batch " + quoted(dir / "m/scenes.txt") + " -o " + quoted(dir / "out") +
                            " --layout cityscapes --preset draft --min-spp 2 --max-spp 2 --no-optimize --no-solids";
  r = runSolo(batch);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* id : {"aachen_000000_000019", "aachen_000001_000019"}) {
    const fs::path night = dir / "out/leftImg8bit_night/train/aachen" / (std::string(id) + "_leftImg8bit.png");
    ASSERT_TRUE(fs::exists(night)) << night << "\n" << r.output;
    const solo::ImageFileInfo info = solo::probeImage(night);
    EXPECT_EQ(info.width, kWidth);
    EXPECT_EQ(info.height, kHeight);
    EXPECT_TRUE(fs::exists(dir / "out" / ("train__aachen__" + std::string(id) + "_leftImg8bit.report.json")));
  }
  EXPECT_FALSE(fs::exists(dir / "out/train__aachen__aachen_000000_000019_leftImg8bit.png")) << "not flat";
  const nlohmann::json summary = nlohmann::json::parse(readText(dir / "out/batch-summary.json"));
  EXPECT_EQ(summary["layout"], "cityscapes");
  EXPECT_EQ(summary["per_scene"][0]["image"], "leftImg8bit_night/train/aachen/aachen_000000_000019_leftImg8bit.png");

  r = runSolo(batch);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("2 skipped (already done)"), std::string::npos) << "resumes\n" << r.output;

  // A manifest without a frame name cannot be placed: the batch stops before any scene runs.
  writeText(dir / "m/plain.scene.json", R"({"image": "x.png", "depth": "x.exr"})");
  writeText(dir / "list.txt", "m/plain.scene.json\n");
  r = runSolo("night --batch " + quoted(dir / "list.txt") + " -o " + quoted(dir / "out2") + " --layout cityscapes");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("plain.scene.json: no \"name\": --layout cityscapes needs"), std::string::npos) << r.output;
}
