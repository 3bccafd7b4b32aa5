// The solo binary against outputs that would destroy data and inputs that would never end:
// `synth --force` on folders it did not write, full disks, outputs that are inputs, devices,
// FIFOs and folders given as files, headers that claim more than their file holds.

#include <solo/core/image_io.h>

#include <nlohmann/json.hpp>

#include "test_support.h"

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>
#include <chrono>
#include <cstdint>
#include <csignal>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <thread>

namespace fs = std::filesystem;
using solo::test::readText;
using solo::test::runSolo;
using solo::test::TempDir;
using solo::test::writeText;

namespace {

// The peak memory of a run that refuses its input: under 200 MB for the release binary; an
// AddressSanitizer build's shadow memory alone adds about 80 MB to every run.
#if defined(__SANITIZE_ADDRESS__)
constexpr double kRefusalPeak_mb = 300;
#else
constexpr double kRefusalPeak_mb = 200;
#endif

std::string shellQuoted(const fs::path& p) { return "\"" + p.string() + "\""; }
std::string shellQuoted(const std::string& p) { return "\"" + p + "\""; }

struct MeasuredRun {
  int exit_code = -1;
  std::string output;
  double seconds = 0;
  double peak_resident_mb = 0;  ///< of the shell and the solo process it ran
};

/// Runs `shell_prefix; solo arguments` in `folder` with /bin/sh, its output in a file, and
/// measures the wall time and the peak resident memory of the process tree (wait4).
MeasuredRun runMeasured(const fs::path& folder, const std::string& arguments, const std::string& shell_prefix = ":") {
  const fs::path log = folder / ".run.log";
  const std::string command = "cd " + shellQuoted(folder) + " && " + shell_prefix + "; exec \"" + SOLO_BINARY + "\" " +
                              arguments + " > " + shellQuoted(log) + " 2>&1";
  const auto start = std::chrono::steady_clock::now();
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  int status = 0;
  rusage usage{};
  ::wait4(pid, &status, 0, &usage);
  MeasuredRun run;
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  run.peak_resident_mb = usage.ru_maxrss / 1024.0;
  run.output = readText(log);
  fs::remove(log);
  return run;
}

/// Seconds `solo --version` takes: the start-up every run pays (libraries, bundled tables), which
/// grows with the machine's load. A refusal must come within 2 s of it.
double startupSeconds(const fs::path& folder) { return runMeasured(folder, "--version").seconds; }

/// The shell prefix of a full disk: files may grow to 1024 bytes, a larger write fails with
/// EFBIG (SIGXFSZ ignored), as a write to a full file system fails with ENOSPC.
const std::string kFullDisk = "trap '' XFSZ; ulimit -f 2";

/// Names of the entries of `folder`, hidden ones included, the run log excluded.
std::vector<std::string> entries(const fs::path& folder) { return solo::test::listFolder(folder); }

void synth(const fs::path& folder, int seed, const std::string& extra = "") {
  const auto r =
      runSolo("synth -o " + shellQuoted(folder) + " --size 96x54 --seed " + std::to_string(seed) + " " + extra);
  ASSERT_EQ(r.exit_code, 0) << r.output;
}

/// A .npy file of float32 with the given shape text and `data_bytes` zero bytes of data.
std::string npyFile(const std::string& shape, std::size_t data_bytes) {
  const std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': " + shape + ", }\n";
  return std::string("\x93NUMPY\x01\x00", 8) + static_cast<char>(header.size() & 0xff) +
         static_cast<char>(header.size() >> 8) + header + std::string(data_bytes, '\0');
}

int synthSeed(const fs::path& folder) {
  return nlohmann::json::parse(readText(folder / "synth.json"))["seed"].get<int>();
}

}  // namespace

// ------------------------------------------------------------------ synth --force

TEST(CliDataSafety, SynthForceNeverReplacesTheWorkingFolder) {
  TempDir dir;
  writeText(dir / "keep.txt", "mine");
  fs::create_directories(dir / "sub");
  for (const std::string& output : std::vector<std::string>{".", "./", "sub/..", shellQuoted(dir.path())}) {
    const MeasuredRun r = runMeasured(dir.path(), "synth -o " + output + " --force --size 32x32");
    EXPECT_EQ(r.exit_code, 2) << output << "\n" << r.output;
    EXPECT_NE(r.output.find("is the working folder or one of its parents"), std::string::npos) << r.output;
    EXPECT_EQ(entries(dir.path()), (std::vector<std::string>{"keep.txt", "sub"})) << output;
    EXPECT_EQ(readText(dir / "keep.txt"), "mine");
  }
  // A parent of the working folder.
  const MeasuredRun r = runMeasured(dir / "sub", "synth -o .. --force --size 32x32");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(entries(dir.path()), (std::vector<std::string>{"keep.txt", "sub"}));
}

TEST(CliDataSafety, SynthForceReplacesOnlyAFolderSynthWrote) {
  TempDir dir;
  fs::create_directories(dir / "photos");
  writeText(dir / "photos/a.jpg", "not an image, but mine");
  auto r = runSolo("synth -o " + shellQuoted(dir / "photos") + " --force --size 32x32");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("photos: is not a folder solo synth wrote (it lacks synth.json from solo synth)"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(readText(dir / "photos/a.jpg"), "not an image, but mine");

  // A synth folder the user added a file to keeps it: the file is named, nothing is deleted.
  synth(dir / "scene", 1);
  writeText(dir / "scene/est/notes.txt", "my notes");
  r = runSolo("synth -o " + shellQuoted(dir / "scene") + " --force --size 96x54 --seed 2");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("holds \"est/notes.txt\", which solo synth does not write"), std::string::npos) << r.output;
  EXPECT_EQ(readText(dir / "scene/est/notes.txt"), "my notes");
  EXPECT_EQ(synthSeed(dir / "scene"), 1);

  // Without it, --force replaces the scene; no temporary folder is left beside it.
  fs::remove(dir / "scene/est/notes.txt");
  synth(dir / "scene", 2, "--force");
  EXPECT_EQ(synthSeed(dir / "scene"), 2);
  EXPECT_EQ(entries(dir.path()), (std::vector<std::string>{"photos", "scene"}));
}

TEST(CliDataSafety, SynthOutputWithATrailingSlashWorks) {
  TempDir dir;
  synth(dir / "fresh", 3);  // no slash: the reference
  auto r = runSolo("synth -o " + shellQuoted(dir.path().string() + "/new/") + " --size 96x54 --seed 3");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(readText(dir / "new/scene.json"), readText(dir / "fresh/scene.json"));
  r = runSolo("synth -o " + shellQuoted(dir.path().string() + "/new//") + " --size 96x54 --seed 4 --force");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(synthSeed(dir / "new"), 4);
  EXPECT_EQ(entries(dir.path()), (std::vector<std::string>{"fresh", "new"}));
  r = runSolo("synth -o " + shellQuoted(dir.path().string() + "/new/") + " --size 96x54");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("new: already exists (pass --force"), std::string::npos) << r.output;
}

// ------------------------------------------------------------------ full disk

TEST(CliDataSafety, AFullDiskFailsEveryImageWriteNamingTheFileAndLeavesNothing) {
  TempDir dir;
  cv::Mat render(128, 128, CV_32FC3);  // random XYZ below the default exposure's white: a PNG of tens of KB
  cv::randu(render, 0.0f, 0.1f);
  solo::writeImage(dir / "render.exr", render);
  cv::Mat depth(40, 60, CV_32F);
  cv::randu(depth, 1.0f, 50.0f);
  solo::writeImage(dir / "d.exr", depth);
  const std::vector<std::string> before = entries(dir.path());
  for (const std::string output : {"p.png", "p.jpg", "p.tif", "p.exr"}) {
    const MeasuredRun r = runMeasured(dir.path(), "post render.exr -o " + output, kFullDisk);
    EXPECT_EQ(r.exit_code, 2) << output << "\n" << r.output;
    EXPECT_NE(r.output.find(output + ": write failed"), std::string::npos) << r.output;
    EXPECT_EQ(entries(dir.path()), before) << output << ": no output and no temporary left";
  }
  for (const std::string output : {"out.png", "out.pfm", "out.npy", "out.exr"}) {
    const MeasuredRun r = runMeasured(dir.path(), "convert depth d.exr " + output, kFullDisk);
    EXPECT_EQ(r.exit_code, 2) << output << "\n" << r.output;
    EXPECT_NE(r.output.find(output + ": write failed"), std::string::npos) << r.output;
    EXPECT_EQ(entries(dir.path()), before) << output;
  }
  // With room, the same runs succeed (the limit is what failed them).
  EXPECT_EQ(runMeasured(dir.path(), "post render.exr -o p.png").exit_code, 0);
  EXPECT_GT(fs::file_size(dir / "p.png"), 1024u);
}

TEST(CliDataSafety, NightOnAFullDiskExitsNonZeroAndLeavesNoImage) {
  TempDir dir;
  synth(dir / "s", 5);
  const std::vector<std::string> before = entries(dir.path());
  const MeasuredRun r = runMeasured(dir.path(), "night s/scene.json -o night.png --preset draft --seed 1", kFullDisk);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("night.png: write failed"), std::string::npos) << r.output;
  EXPECT_EQ(entries(dir.path()), before);
}

// ------------------------------------------------------------------ outputs that are inputs

TEST(CliDataSafety, NightRefusesAnOutputThatIsOneOfItsInputsBeforeAnyWork) {
  TempDir dir;
  synth(dir / "s", 6);
  const std::string day = readText(dir / "s/day.png"), manifest = readText(dir / "s/scene.json");
  struct Case {
    std::string arguments, message;
  };
  const std::vector<Case> cases = {
      {"-o s/day.png", "-o: \"s/day.png\" is an input of this run"},
      {"-o s/./est/../day.png", "is an input of this run"},
      {"-o night.png --report s/scene.json", "--report: \"s/scene.json\" is an input of this run"},
      {"-o night.png --report " + shellQuoted(dir / "s/gt/../scene.json"), "--report:"},
      {"-o night.png --contact-sheet s/est/normals.png", "--contact-sheet:"},
      {"-o night.png --render-exr s/est/depth.exr", "--render-exr:"},
  };
  const double startup_s = startupSeconds(dir.path());
  for (const Case& c : cases) {
    const MeasuredRun r = runMeasured(dir.path(), "night s/scene.json --preset draft " + c.arguments);
    EXPECT_EQ(r.exit_code, 2) << c.arguments << "\n" << r.output;
    EXPECT_NE(r.output.find(c.message), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("input ..."), std::string::npos) << "refused before the input stage";
    EXPECT_LT(r.seconds, startup_s + 2.0);
  }
  EXPECT_EQ(readText(dir / "s/day.png"), day);
  EXPECT_EQ(readText(dir / "s/scene.json"), manifest);
  EXPECT_EQ(entries(dir.path()), (std::vector<std::string>{"s"}));
}

TEST(CliDataSafety, PostAndConvertRefuseToOverwriteTheirInput) {
  TempDir dir;
  solo::writeImage(dir / "render.exr", cv::Mat(8, 8, CV_32FC3, cv::Scalar::all(0.25)));
  const std::string render = readText(dir / "render.exr");
  auto r = runSolo("post " + shellQuoted(dir / "render.exr") + " -o " + shellQuoted(dir / "./render.exr"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("-o: "), std::string::npos) << r.output;
  r = runSolo("convert depth " + shellQuoted(dir / "render.exr") + " " + shellQuoted(dir / "render.exr"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("is an input of this run"), std::string::npos) << r.output;
  EXPECT_EQ(readText(dir / "render.exr"), render);
}

// ------------------------------------------------------------------ only regular files

TEST(CliDataSafety, DevicesFifosFoldersAndLinkLoopsAreRefusedByName) {
  TempDir dir;
  synth(dir / "s", 7);
  ASSERT_EQ(::mkfifo((dir / "fifo").c_str(), 0600), 0);
  fs::create_symlink(dir / "loop_b", dir / "loop_a");
  fs::create_symlink(dir / "loop_a", dir / "loop_b");
  fs::create_directories(dir / "folder.json");
  struct Case {
    std::string file, problem;
  };
  const std::vector<Case> maps = {{"/dev/zero", "is a character device, expected a map or image file"},
                                  {"/dev/urandom", "is a character device"},
                                  {(dir / "fifo").string(), "is a FIFO (named pipe)"},
                                  {(dir / "s").string(), "is a folder"},
                                  {(dir / "loop_a").string(), "symbolic link loop"}};
  const std::string manifest = readText(dir / "s/scene.json");
  const double startup_s = startupSeconds(dir.path());
  for (const Case& c : maps) {
    // The depth map of the scene replaced by the special file.
    auto j = nlohmann::json::parse(manifest);
    j["depth"] = c.file;
    writeText(dir / "s/scene.json", j.dump());
    const MeasuredRun r = runMeasured(dir.path(), "info s/scene.json");
    EXPECT_EQ(r.exit_code, 2) << c.file << "\n" << r.output;
    EXPECT_NE(r.output.find(c.file + ": " + c.problem), std::string::npos) << r.output;
    EXPECT_LT(r.seconds, startup_s + 2.0) << c.file;
  }
  const std::vector<Case> manifests = {{(dir / "folder.json").string(), "is a folder, expected a scene manifest file"},
                                       {"/dev/zero", "is a character device, expected a scene manifest file"},
                                       {(dir / "fifo").string(), "is a FIFO (named pipe), expected a scene manifest"},
                                       {(dir / "loop_a").string(), "symbolic link loop"}};
  for (const Case& c : manifests) {
    const MeasuredRun r = runMeasured(dir.path(), "night " + shellQuoted(c.file) + " -o n.png");
    EXPECT_EQ(r.exit_code, 2) << c.file << "\n" << r.output;
    EXPECT_NE(r.output.find(c.file + ": " + c.problem), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("underflow"), std::string::npos) << r.output;
    EXPECT_LT(r.seconds, startup_s + 2.0) << c.file;
  }
  ::symlink((dir / "fifo").c_str(), (dir / "pipe.off").c_str());
  const MeasuredRun piped = runMeasured(dir.path(), "mesh clean pipe.off -o out.ply");
  EXPECT_EQ(piped.exit_code, 2) << piped.output;
  EXPECT_NE(piped.output.find("pipe.off: is a FIFO (named pipe), expected a mesh file"), std::string::npos)
      << piped.output;
  EXPECT_LT(piped.seconds, startup_s + 2.0);
}

// ------------------------------------------------------------------ sizes before memory

TEST(CliDataSafety, HeadersClaimingHugeImagesOrMeshesAreRefusedQuicklyAndSmall) {
  TempDir dir;
  writeText(dir / "huge.pfm", "Pf\n100000 100000\n-1.0\n" + std::string(64, '\0'));
  writeText(dir / "huge.off", "OFF\n3 1000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  writeText(dir / "huge.npy", npyFile("(4611686018427387905, 1)", 4));
  struct Case {
    std::string arguments, message;
  };
  const std::vector<Case> cases = {
      {"convert depth huge.pfm out.exr", "huge.pfm: image is 100000x100000 pixels, more than the limit of 268435456"},
      {"convert depth huge.npy out.exr", "huge.npy: image is 1x4611686018427387905 pixels"},
      {"mesh clean huge.off -o out.ply",
       "huge.off: cannot read as a mesh: header declares 1000000000 faces, more than the file's"},
  };
  const double startup_s = startupSeconds(dir.path());
  for (const Case& c : cases) {
    const MeasuredRun r = runMeasured(dir.path(), c.arguments);
    EXPECT_EQ(r.exit_code, 2) << c.arguments << "\n" << r.output;
    EXPECT_NE(r.output.find(c.message), std::string::npos) << r.output;
    EXPECT_LT(r.seconds, startup_s + 2.0) << c.arguments;
    EXPECT_LT(r.peak_resident_mb, kRefusalPeak_mb) << c.arguments;
  }
  // The limit is the documented environment variable's to raise: past the pixel limit the
  // PFM's header is still checked against its size.
  const MeasuredRun raised =
      runMeasured(dir.path(), "convert depth huge.pfm out.exr", "export SOLO_MAX_IMAGE_PIXELS=20000000000");
  EXPECT_EQ(raised.exit_code, 2) << raised.output;
  EXPECT_NE(raised.output.find("huge.pfm: PFM header declares 100000x100000 pixels, 40000000000 bytes of data, but "
                               "the file holds 64 after its header"),
            std::string::npos)
      << raised.output;
  EXPECT_LT(raised.peak_resident_mb, kRefusalPeak_mb);
  EXPECT_FALSE(fs::exists(dir / "out.exr"));
  EXPECT_FALSE(fs::exists(dir / "out.ply"));
}

// ------------------------------------------------------------------ values that cannot be used

namespace {

/// An 8x8 scene: a grey day image, the given depth map (float metres) and inline intrinsics with
/// `camera_size` as its "width" and "height" text.
void writeSmallScene(const fs::path& folder, const cv::Mat& depth_m, const std::string& camera_size = "") {
  solo::writeImage(folder / "day.png", cv::Mat(8, 8, CV_8UC3, cv::Scalar::all(128)));
  solo::writeImage(folder / "depth.exr", depth_m);
  writeText(folder / "scene.json", R"({"image": "day.png", "depth": "depth.exr", "camera": {"fx": 8, "fy": 8, )"
                                   R"("cx": 3.5, "cy": 3.5)" +
                                       camera_size + "}}");
}

}  // namespace

TEST(CliDataSafety, ACameraWidthBeyondAnIntIsRefusedNamingTheManifest) {
  TempDir dir;
  writeSmallScene(dir.path(), cv::Mat(8, 8, CV_32F, cv::Scalar(5)), R"(, "width": 4294967328, "height": 8)");
  const auto before = entries(dir.path());
  for (const std::string command : {"info scene.json", "mesh from-depth scene.json -o m.ply"}) {
    const MeasuredRun r = runMeasured(dir.path(), command);
    EXPECT_EQ(r.exit_code, 2) << command << "\n" << r.output;
    EXPECT_NE(r.output.find("scene.json: \"camera\".\"width\" must be a whole number of pixels from 1 to 65536, found "
                            "4294967328"),
              std::string::npos)
        << r.output;
  }
  EXPECT_EQ(entries(dir.path()), before);
}

TEST(CliDataSafety, MeshFromDepthRefusesADepthMapThatFormsNoFace) {
  TempDir dir;
  // One valid pixel, then a diagonal of them: no 2x2 block of depths, so no face.
  cv::Mat one(8, 8, CV_32F, cv::Scalar(0));
  one.at<float>(3, 3) = 5;
  cv::Mat diagonal(8, 8, CV_32F, cv::Scalar(0));
  for (int i = 0; i < 8; ++i) diagonal.at<float>(i, i) = 5;
  for (const cv::Mat& depth : {one, diagonal}) {
    writeSmallScene(dir.path(), depth);
    const auto before = entries(dir.path());
    const MeasuredRun r = runMeasured(dir.path(), "mesh from-depth scene.json -o m.ply --report r.json");
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find("depth.exr: no 2x2 block of valid depth pixels in the 8x8 map"), std::string::npos)
        << r.output;
    EXPECT_EQ(entries(dir.path()), before);
  }
}

TEST(CliDataSafety, MeshCleanRefusesNonFiniteStlVerticesAndOutOfRangePlyFaces) {
  TempDir dir;
  std::string stl(80, '\0');
  const std::uint32_t count = 1;
  stl.append(reinterpret_cast<const char*>(&count), 4);
  const float triangle[9] = {0, 0, 0, 1, 0, 0, 0, std::numeric_limits<float>::quiet_NaN(), 0};
  stl.append(12, '\0');
  stl.append(reinterpret_cast<const char*>(triangle), sizeof triangle);
  stl.append(2, '\0');
  writeText(dir / "nan.stl", stl);
  writeText(dir / "bad.ply",
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
            "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n");
  const auto before = entries(dir.path());
  struct Case {
    std::string arguments, message;
  };
  const std::vector<Case> cases = {
      {"mesh clean nan.stl -o out.ply", "nan.stl: vertex 2 (triangle 0, corner 2) has a non-finite coordinate"},
      {"mesh clean bad.ply -o out.ply", "bad.ply: face 0 refers to vertex 5, but the file has 3 vertices"},
      {"eval mesh bad.ply --csv out.csv", "bad.ply: face 0 refers to vertex 5"},
  };
  for (const Case& c : cases) {
    const MeasuredRun r = runMeasured(dir.path(), c.arguments);
    EXPECT_EQ(r.exit_code, 2) << c.arguments << "\n" << r.output;
    EXPECT_NE(r.output.find("solo: error: " + c.message), std::string::npos) << r.output;
  }
  EXPECT_EQ(entries(dir.path()), before);
}

// ------------------------------------------------------------------ library text on stderr

namespace {

struct SplitRun {
  int exit_code = -1;
  std::string out, err;
};

/// Runs solo with `arguments` in `folder`, stdout and stderr kept apart.
SplitRun runSplit(const fs::path& folder, const std::string& arguments) {
  const fs::path out = folder / ".run.out", err = folder / ".run.err";
  const std::string command = "cd " + shellQuoted(folder) + " && exec \"" + SOLO_BINARY + "\" " + arguments + " > " +
                              shellQuoted(out) + " 2> " + shellQuoted(err);
  const int status = std::system(command.c_str());
  SplitRun run;
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  run.out = readText(out);
  run.err = readText(err);
  fs::remove(out);
  fs::remove(err);
  return run;
}

/// The lines of `text`, the last one without its newline.
std::vector<std::string> linesOf(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) lines.push_back(line);
  return lines;
}

/// A copy of the PNG `source` with the byte at `offset` inverted (inside the compressed pixels).
void writeCorruptCopy(const fs::path& source, const fs::path& target, std::size_t offset) {
  std::string bytes = readText(source);
  ASSERT_LT(offset, bytes.size());
  bytes[offset] = static_cast<char>(~bytes[offset]);
  writeText(target, bytes);
}

}  // namespace

TEST(CliDataSafety, ABrokenPngGivesSolosErrorLineOnlyNamingTheFile) {
  TempDir dir;
  cv::Mat day(48, 64, CV_8UC3);
  cv::randu(day, 0, 255);
  solo::writeImage(dir / "day.png", day);
  cv::Mat depth(48, 64, CV_16U);
  cv::randu(depth, 1, 60000);
  solo::writeImage(dir / "depth.png", depth);
  const std::size_t day_bytes = fs::file_size(dir / "day.png");
  solo::test::writeTruncatedCopy(dir / "day.png", dir / "cut.png", day_bytes / 2);
  writeCorruptCopy(dir / "day.png", dir / "flipped.png", day_bytes / 2);
  solo::test::writeTruncatedCopy(dir / "depth.png", dir / "cut-depth.png", fs::file_size(dir / "depth.png") / 2);
  solo::test::writeTruncatedCopy(dir / "day.png", dir / "header-only.png", 40);
  const std::vector<std::pair<std::string, std::string>> runs = {
      {"fda --source cut.png --target day.png -o f.png", "cut.png"},
      {"fda --source flipped.png --target day.png -o f.png", "flipped.png"},
      {"fda --source day.png --target header-only.png -o f.png", "header-only.png"},
      {"convert depth cut-depth.png d.exr --input-scale 0.01", "cut-depth.png"}};
  for (const auto& [arguments, file] : runs) {
    const SplitRun r = runSplit(dir.path(), arguments);
    EXPECT_EQ(r.exit_code, 2) << arguments << "\n" << r.err;
    const std::vector<std::string> lines = linesOf(r.err);
    ASSERT_EQ(lines.size(), 1u) << arguments << ": one line, solo's own:\n" << r.err;
    EXPECT_EQ(lines[0].rfind("solo: error: " + file + ": ", 0), 0u) << lines[0];
    EXPECT_EQ(lines[0].find("libpng error"), std::string::npos) << lines[0];
    EXPECT_FALSE(fs::exists(dir / "f.png") || fs::exists(dir / "d.exr")) << arguments;
  }
}

TEST(CliDataSafety, AMalformedMeshGivesSolosErrorLineOnlyWithCgalsWords) {
  TempDir dir;
  writeText(dir / "not.ply", "plx\nformat ascii 1.0\n");
  writeText(dir / "list.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty list uchar\nend_header\n");
  for (const std::string file : {"not.ply", "list.ply"}) {
    const SplitRun r = runSplit(dir.path(), "mesh clean " + file + " -o out.ply");
    EXPECT_EQ(r.exit_code, 2) << file << "\n" << r.err;
    const std::vector<std::string> lines = linesOf(r.err);
    ASSERT_EQ(lines.size(), 1u) << file << ": one line, solo's own:\n" << r.err;
    EXPECT_EQ(lines[0].rfind("solo: error: " + file + ": cannot read as a mesh: malformed or truncated (Error", 0), 0u)
        << lines[0];
  }
}

// ------------------------------------------------------------------ signals

namespace {

/// Starts solo with `arguments` (stdout and stderr to /dev/null); returns its pid.
pid_t startSolo(const std::vector<std::string>& arguments) {
  std::vector<std::string> argv = {"solo"};
  argv.insert(argv.end(), arguments.begin(), arguments.end());
  const pid_t pid = ::fork();
  if (pid != 0) return pid;
  const int null = ::open("/dev/null", O_RDWR);
  ::dup2(null, 1);
  ::dup2(null, 2);
  std::vector<char*> pointers;
  for (std::string& a : argv) pointers.push_back(a.data());
  pointers.push_back(nullptr);
  ::execv(SOLO_BINARY, pointers.data());
  ::_exit(127);
}

std::vector<std::string> hiddenEntries(const fs::path& folder) {
  std::vector<std::string> hidden;
  for (const std::string& name : entries(folder))
    if (name[0] == '.') hidden.push_back(name);
  return hidden;
}

}  // namespace

TEST(CliDataSafety, NightStoppedBySigtermAtAnyPointLeavesNoHiddenTemporary) {
  TempDir dir;
  synth(dir / "s", 8);
  const fs::path out = dir / "out";
  const std::vector<std::string> arguments = {
      "night", (dir / "s" / "scene.json").string(), "-o", (out / "night.png").string(), "--report",
      (out / "report.json").string(), "--contact-sheet", (out / "sheet.png").string(), "--render-exr",
      (out / "render.exr").string(), "--preset", "draft", "--seed", "3"};
  // One whole run: how long the writes take to come.
  const auto start = std::chrono::steady_clock::now();
  int status = 0;
  const pid_t whole = startSolo(arguments);
  ASSERT_EQ(::waitpid(whole, &status, 0), whole);
  const double run_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status;
  ASSERT_TRUE(fs::exists(out / "sheet.png"));
  // Then SIGTERM at 16 points spread over the run, the last ones among the writes at its end.
  constexpr int kPoints = 16;
  int killed = 0;
  for (int k = 1; k <= kPoints; ++k) {
    fs::remove_all(out);
    const double delay_s = run_s * (0.3 + 0.7 * k / (kPoints + 1.0));
    const pid_t pid = startSolo(arguments);
    std::this_thread::sleep_for(std::chrono::duration<double>(delay_s));
    ::kill(pid, SIGTERM);
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    const bool ended_by_sigterm = WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM;
    killed += ended_by_sigterm;
    EXPECT_TRUE(ended_by_sigterm || (WIFEXITED(status) && WEXITSTATUS(status) == 0))
        << "at " << delay_s << " s: status " << status;
    if (fs::exists(out)) {
      EXPECT_EQ(hiddenEntries(out), std::vector<std::string>{}) << "SIGTERM at " << delay_s << " s of " << run_s;
    }
  }
  EXPECT_GT(killed, kPoints / 2) << "most runs were stopped mid-way";
}

TEST(CliDataSafety, SynthStoppedBySigtermWhileWritingLeavesNoStagingFolder) {
  TempDir dir;
  const std::vector<std::string> arguments = {"synth", "-o", (dir / "scene").string(), "--size", "640x360",
                                              "--seed", "5", "--depth-source", "stereo"};
  // SIGTERM once the hidden staging folder exists, after 0 to 40 ms more: among the map writes.
  int killed = 0;
  for (const int delay_ms : {0, 1, 2, 4, 8, 15, 25, 40}) {
    fs::remove_all(dir / "scene");
    const pid_t pid = startSolo(arguments);
    int status = 0;
    bool staged = false;
    while (!staged && ::waitpid(pid, &status, WNOHANG) == 0) {
      staged = !hiddenEntries(dir.path()).empty();
      if (!staged) std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    if (!staged) continue;  // ended before a poll saw the folder
    std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
    ::kill(pid, SIGTERM);
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    const bool ended_by_sigterm = WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM;
    killed += ended_by_sigterm;
    EXPECT_EQ(hiddenEntries(dir.path()), std::vector<std::string>{}) << "SIGTERM " << delay_ms << " ms into the writes";
    if (ended_by_sigterm) {
      EXPECT_FALSE(fs::exists(dir / "scene")) << delay_ms << " ms: a stopped run leaves no folder";
    } else {
      EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << delay_ms << " ms: status " << status;
      EXPECT_TRUE(fs::exists(dir / "scene" / "synth.json")) << delay_ms << " ms";
    }
  }
  EXPECT_GE(killed, 4) << "most runs were stopped while writing";
}
