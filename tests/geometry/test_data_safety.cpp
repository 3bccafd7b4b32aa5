// Readers that take only regular files and check sizes before memory, writers that check every
// write, and output paths that can never be an input or the working folder.

#include <solo/core/atomic_file.h>
#include <solo/core/camera.h>
#include <solo/core/error.h>
#include <solo/core/image_io.h>
#include <solo/core/image_limits.h>
#include <solo/core/input_file.h>
#include <solo/core/output_path.h>
#include <solo/core/scene.h>
#include <solo/geometry/triangle_mesh.h>
#include <solo/lighting/illuminant_table.h>
#include <solo/lighting/light_record.h>

#include "test_support.h"

#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>
#include <chrono>
#include <csignal>
#include <functional>

namespace fs = std::filesystem;
using solo::test::TempDir;
using solo::test::writeText;

namespace {

std::string messageOf(const std::function<void()>& action) {
  try {
    action();
  } catch (const solo::InputError& e) {
    return e.what();
  }
  return "(no InputError)";
}

/// A .npy file of float32 with the given shape text and `data_bytes` zero bytes of data.
std::string npyFile(const std::string& shape, std::size_t data_bytes) {
  const std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': " + shape + ", }\n";
  return std::string("\x93NUMPY\x01\x00", 8) + static_cast<char>(header.size() & 0xff) +
         static_cast<char>(header.size() >> 8) + header + std::string(data_bytes, '\0');
}

/// While alive, files this process writes may not grow past `bytes`: a larger write fails
/// with EFBIG as a write to a full disk fails with ENOSPC (SIGXFSZ ignored meanwhile).
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    ::getrlimit(RLIMIT_FSIZE, &saved_);
    previous_handler_ = std::signal(SIGXFSZ, SIG_IGN);
    rlimit limited = saved_;
    limited.rlim_cur = bytes;
    ::setrlimit(RLIMIT_FSIZE, &limited);
  }
  ~FileSizeLimit() {
    ::setrlimit(RLIMIT_FSIZE, &saved_);
    std::signal(SIGXFSZ, previous_handler_);
  }

 private:
  rlimit saved_{};
  void (*previous_handler_)(int) = nullptr;
};

// A 32-bit CRC (the one PNG chunks carry), bit by bit: polynomial 0xEDB88320, reflected.
std::uint32_t crc32(const std::string& bytes) {
  std::uint32_t crc = 0xFFFFFFFFu;
  for (unsigned char byte : bytes) {
    crc ^= byte;
    for (int bit = 0; bit < 8; ++bit) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

std::string bigEndian32(std::uint32_t value) {
  return {static_cast<char>(value >> 24), static_cast<char>(value >> 16), static_cast<char>(value >> 8),
          static_cast<char>(value)};
}

std::string pngChunk(const std::string& type, const std::string& data) {
  return bigEndian32(static_cast<std::uint32_t>(data.size())) + type + data + bigEndian32(crc32(type + data));
}

/// A PNG whose header declares width x height 8-bit grey pixels, with an empty zlib stream as
/// its only pixel data.
std::string pngHeaderOnly(std::uint32_t width, std::uint32_t height) {
  const std::string ihdr = bigEndian32(width) + bigEndian32(height) + std::string("\x08\x00\x00\x00\x00", 5);
  const std::string empty_zlib("\x78\x9c\x03\x00\x00\x00\x00\x01", 8);
  return std::string("\x89PNG\r\n\x1a\n", 8) + pngChunk("IHDR", ihdr) + pngChunk("IDAT", empty_zlib) +
         pngChunk("IEND", "");
}

double secondsOf(const std::function<void()>& action) {
  const auto start = std::chrono::steady_clock::now();
  action();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

// ------------------------------------------------------------------ regular files only

TEST(RegularFile, ReturnsTheSizeOfARegularFileAndOfALinkToIt) {
  TempDir dir;
  writeText(dir / "a.json", "{}\n");
  fs::create_symlink(dir / "a.json", dir / "link.json");
  EXPECT_EQ(solo::requireRegularFile(dir / "a.json", "scene manifest"), 3u);
  EXPECT_EQ(solo::requireRegularFile(dir / "link.json", "scene manifest"), 3u);
  writeText(dir / "empty.png", "");
  EXPECT_EQ(solo::requireRegularFile(dir / "empty.png", "map"), 0u);
  EXPECT_EQ(messageOf([&] { solo::requireNonEmptyRegularFile(dir / "empty.png", "map"); }),
            (dir / "empty.png").string() + ": file is empty");
}

TEST(RegularFile, RefusesEveryOtherKindByName) {
  TempDir dir;
  ASSERT_EQ(::mkfifo((dir / "fifo").c_str(), 0600), 0);
  fs::create_directories(dir / "folder");
  fs::create_symlink(dir / "b", dir / "a");
  fs::create_symlink(dir / "a", dir / "b");
  fs::create_symlink(dir / "nowhere", dir / "dangling");
  const int socket_fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  const std::string socket_path = (dir / "sock").string();
  ASSERT_LT(socket_path.size(), sizeof(address.sun_path));
  std::copy(socket_path.begin(), socket_path.end(), address.sun_path);
  ASSERT_EQ(::bind(socket_fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)), 0);

  const auto expect = [&](const fs::path& file, const std::string& problem) {
    EXPECT_EQ(messageOf([&] { solo::requireRegularFile(file, "depth map"); }), file.string() + ": " + problem);
  };
  expect("/dev/zero", "is a character device, expected a depth map file");
  expect("/dev/urandom", "is a character device, expected a depth map file");
  expect(dir / "fifo", "is a FIFO (named pipe), expected a depth map file");
  expect(dir / "sock", "is a socket, expected a depth map file");
  expect(dir / "folder", "is a folder, expected a depth map file");
  expect(dir / "a", "symbolic link loop (too many levels of links), expected a depth map file");
  expect(dir / "dangling", "file not found (broken symbolic link to " + (dir / "nowhere").string() + ")");
  expect(dir / "missing", "file not found");
  ::close(socket_fd);
}

TEST(RegularFile, EveryReaderUsesIt) {
  TempDir dir;
  ASSERT_EQ(::mkfifo((dir / "fifo.png").c_str(), 0600), 0);
  ASSERT_EQ(::mkfifo((dir / "fifo.npy").c_str(), 0600), 0);
  ASSERT_EQ(::mkfifo((dir / "fifo.off").c_str(), 0600), 0);
  ASSERT_EQ(::mkfifo((dir / "fifo.json").c_str(), 0600), 0);
  const std::string fifo = ": is a FIFO (named pipe), expected a ";
  EXPECT_EQ(messageOf([&] { solo::readColorImage(dir / "fifo.png"); }),
            (dir / "fifo.png").string() + fifo + "map or image file");
  EXPECT_EQ(messageOf([&] { solo::readNpy(dir / "fifo.npy"); }),
            (dir / "fifo.npy").string() + fifo + "map or image file");
  EXPECT_EQ(messageOf([&] { solo::probeImage(dir / "fifo.png"); }),
            (dir / "fifo.png").string() + fifo + "map or image file");
  EXPECT_EQ(messageOf([&] { solo::readMesh(dir / "fifo.off"); }), (dir / "fifo.off").string() + fifo + "mesh file");
  EXPECT_EQ(messageOf([&] { solo::loadScene(dir / "fifo.json"); }),
            (dir / "fifo.json").string() + fifo + "scene manifest file");
  EXPECT_EQ(messageOf([&] { solo::readCityscapesCamera(dir / "fifo.json"); }),
            (dir / "fifo.json").string() + fifo + "camera file");
  EXPECT_EQ(messageOf([&] { solo::readLightRecord(dir / "fifo.json"); }),
            (dir / "fifo.json").string() + fifo + "light record file");
  fs::create_directories(dir / "folder.json");
  EXPECT_EQ(messageOf([&] { solo::loadScene(dir / "folder.json"); }),
            (dir / "folder.json").string() + ": is a folder, expected a scene manifest file");
  EXPECT_EQ(messageOf([&] { solo::readIlluminantTable("/dev/zero"); }),
            "/dev/zero: is a character device, expected a table file");
}

// ------------------------------------------------------------------ output paths

TEST(OutputPath, TrailingSeparatorsAndDotsAreDropped) {
  EXPECT_EQ(solo::withoutTrailingSeparators("out/"), fs::path("out"));
  EXPECT_EQ(solo::withoutTrailingSeparators("out//"), fs::path("out"));
  EXPECT_EQ(solo::withoutTrailingSeparators("a/b/../c/./"), fs::path("a/c"));
  EXPECT_EQ(solo::withoutTrailingSeparators("./"), fs::path("."));
  EXPECT_EQ(solo::withoutTrailingSeparators("/"), fs::path("/"));
}

TEST(OutputPath, TheWorkingFolderItsParentsAndTheRootAreRefused) {
  TempDir dir;
  fs::create_directories(dir / "work/sub");
  const fs::path saved = fs::current_path();
  fs::current_path(dir / "work");
  for (const fs::path& folder :
       {fs::path("."), fs::path("./"), fs::path(".."), fs::path("sub/.."), dir / "work", dir.path(), fs::path("/")})
    EXPECT_NE(messageOf([&] {
                solo::refuseWorkingFolderOrParent(folder, "-o");
              }).find("-o: \"" + folder.string() + "\" is the working folder or one of its parents"),
              std::string::npos)
        << folder;
  EXPECT_EQ(messageOf([&] { solo::refuseWorkingFolderOrParent("sub", "-o"); }), "(no InputError)");
  EXPECT_EQ(messageOf([&] { solo::refuseWorkingFolderOrParent("new_folder", "-o"); }), "(no InputError)");
  EXPECT_EQ(messageOf([&] { solo::refuseWorkingFolderOrParent(dir / "work2", "-o"); }), "(no InputError)")
      << "a sibling whose name starts like the working folder's is not a parent";
  fs::current_path(saved);
}

TEST(OutputPath, AnOutputIsAnInputUnderAnySpelling) {
  TempDir dir;
  fs::create_directories(dir / "s/est");
  writeText(dir / "s/day.png", "day");
  fs::create_symlink(dir / "s", dir / "alias");
  const std::vector<fs::path> inputs = {dir / "s/scene.json", dir / "s/day.png"};
  EXPECT_TRUE(solo::samePath(dir / "s/est/../day.png", dir / "s/day.png"));
  EXPECT_TRUE(solo::samePath(dir / "alias/day.png", dir / "s/day.png"));
  EXPECT_TRUE(solo::samePath(dir / "s/./scene.json", dir / "s/scene.json")) << "neither exists: compared as paths";
  EXPECT_FALSE(solo::samePath(dir / "s/night.png", dir / "s/day.png"));
  EXPECT_EQ(messageOf([&] { solo::refuseOutputThatIsAnInput(dir / "alias/day.png", inputs, "-o"); }),
            "-o: \"" + (dir / "alias/day.png").string() + "\" is an input of this run (" +
                (dir / "s/day.png").string() + "); writing it would overwrite that input");
  EXPECT_EQ(messageOf([&] { solo::refuseOutputThatIsAnInput(dir / "s/night.png", inputs, "-o"); }), "(no InputError)");
}

// ------------------------------------------------------------------ sizes before memory

TEST(ImageLimit, DefaultIsTwoToThe28PixelsAndTheVariableOverridesIt) {
  ::unsetenv("SOLO_MAX_IMAGE_PIXELS");
  EXPECT_EQ(solo::maxImagePixels(), 268435456u);
  EXPECT_EQ(messageOf([] { solo::requireImageSizeWithinLimit("a.png", 16384, 16384); }), "(no InputError)");
  EXPECT_EQ(messageOf([] { solo::requireImageSizeWithinLimit("a.png", 16384, 16385); }),
            "a.png: image is 16384x16385 pixels, more than the limit of 268435456 pixels (raise it with the "
            "environment variable SOLO_MAX_IMAGE_PIXELS)");
  EXPECT_NE(messageOf([] { solo::requireImageSizeWithinLimit("a.png", 1ull << 40, 1ull << 40); }).find("more than"),
            std::string::npos)
      << "the product overflows 64 bits";
  ::setenv("SOLO_MAX_IMAGE_PIXELS", "100", 1);
  EXPECT_EQ(solo::maxImagePixels(), 100u);
  EXPECT_EQ(messageOf([] { solo::requireImageSizeWithinLimit("a.png", 10, 10); }), "(no InputError)");
  EXPECT_NE(messageOf([] { solo::requireImageSizeWithinLimit("a.png", 10, 11); }).find("limit of 100 pixels"),
            std::string::npos);
  for (const char* bad : {"0", "-5", "1e9", "12abc", ""}) {
    ::setenv("SOLO_MAX_IMAGE_PIXELS", bad, 1);
    EXPECT_EQ(messageOf([] { solo::maxImagePixels(); }),
              std::string("SOLO_MAX_IMAGE_PIXELS: expected a positive whole number of pixels, got \"") + bad + "\"");
  }
  ::unsetenv("SOLO_MAX_IMAGE_PIXELS");
}

TEST(ImageLimit, NpyShapesAreParsedStrictlyAndCheckedAgainstTheFileSize) {
  TempDir dir;
  struct Case {
    std::string shape;
    std::size_t data_bytes;
    std::string problem;
  };
  const std::vector<Case> cases = {
      {"('a', 3)", 0, "malformed .npy shape: \"'a'\" is not a whole number"},
      {"(12345678901234567890, 3)", 0, ".npy shape entry 12345678901234567890 is implausibly large"},
      {"(3037000500, 3037000500)", 0,
       "image is 3037000500x3037000500 pixels, more than the limit of 268435456 "
       "pixels (raise it with the environment variable SOLO_MAX_IMAGE_PIXELS)"},
      {"(4611686018427387905, 1)", 4,
       "image is 1x4611686018427387905 pixels, more than the limit of 268435456 "
       "pixels (raise it with the environment variable SOLO_MAX_IMAGE_PIXELS)"},
      {"(-2, 3)", 0, "malformed .npy shape: \"-2\" is not a whole number"},
      {"(2, 3)", 23, "truncated .npy data: the shape needs 24 bytes, the file holds 23"},
  };
  for (const Case& c : cases) {
    writeText(dir / "a.npy", npyFile(c.shape, c.data_bytes));
    EXPECT_EQ(messageOf([&] { solo::readNpy(dir / "a.npy"); }), (dir / "a.npy").string() + ": " + c.problem) << c.shape;
  }
  // The same shape with its 24 bytes is read.
  writeText(dir / "a.npy", npyFile("(2, 3)", 24));
  EXPECT_EQ(solo::readNpy(dir / "a.npy").size(), cv::Size(3, 2));
  // With the pixel limit raised out of the way, a side must still fit an OpenCV image and the
  // byte count 64 bits: (2^31 - 1)^2 pixels x 4 channels x 4 bytes is about 2^66.
  ::setenv("SOLO_MAX_IMAGE_PIXELS", "9223372036854775807", 1);
  writeText(dir / "a.npy", npyFile("(1, 4611686018427387904, 2)", 4));
  EXPECT_NE(messageOf([&] { solo::readNpy(dir / "a.npy"); }).find("image is 4611686018427387904x1 pixels"),
            std::string::npos);
  writeText(dir / "a.npy", npyFile("(2147483647, 2147483647, 4)", 4));
  EXPECT_EQ(messageOf([&] { solo::readNpy(dir / "a.npy"); }),
            (dir / "a.npy").string() + ": truncated .npy data: the shape needs more than 2^64 bytes, the file holds 4");
  ::unsetenv("SOLO_MAX_IMAGE_PIXELS");
}

TEST(ImageLimit, PfmAndPngHeadersAreCheckedBeforeDecoding) {
  TempDir dir;
  writeText(dir / "huge.pfm", "Pf\n100000 100000\n-1.0\n" + std::string(64, '\0'));
  writeText(dir / "short.pfm", "Pf\n4 4\n-1.0\n" + std::string(63, '\0'));
  writeText(dir / "bomb.png", pngHeaderOnly(20000, 20000));
  const double seconds = secondsOf([&] {
    EXPECT_EQ(messageOf([&] { solo::readDepth(dir / "huge.pfm", 0); }),
              (dir / "huge.pfm").string() +
                  ": image is 100000x100000 pixels, more than the limit of 268435456 "
                  "pixels (raise it with the environment variable SOLO_MAX_IMAGE_PIXELS)");
    EXPECT_EQ(messageOf([&] { solo::readDepth(dir / "short.pfm", 0); }),
              (dir / "short.pfm").string() +
                  ": PFM header declares 4x4 pixels, 64 bytes of data, but the file holds 63 after its header "
                  "(truncated or corrupt)");
    EXPECT_NE(messageOf([&] { solo::readColorImage(dir / "bomb.png"); }).find("bomb.png: image is 20000x20000 pixels"),
              std::string::npos);
  });
  EXPECT_LT(seconds, 2.0);
}

TEST(MeshHeader, CountsBeyondTheFileSizeAreRefusedBeforeReading) {
  TempDir dir;
  writeText(dir / "faces.off", "OFF\n3 1000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  writeText(dir / "vertices.off", "# comment\nOFF # keyword\n# counts next\n20 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  writeText(dir / "vertices.ply",
            "ply\nformat binary_little_endian 1.0\nelement vertex 100000000\nproperty float x\n"
            "property float y\nproperty float z\nelement face 1\nproperty list uchar int "
            "vertex_indices\nend_header\n" +
                std::string(64, '\0'));
  writeText(dir / "ascii.ply",
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
            "property float z\nelement face 4000000000000000000\nproperty list uchar int "
            "vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  const auto expect = [&](const std::string& name, const std::string& problem) {
    EXPECT_EQ(messageOf([&] { solo::readMesh(dir / name); }),
              (dir / name).string() + ": cannot read as a mesh: " + problem);
  };
  const double seconds = secondsOf([&] {
    expect("faces.off",
           "header declares 1000000000 faces, more than the file's 45 bytes can hold (truncated or "
           "corrupt header)");
    // 20 ASCII vertices need at least 20 x 6 bytes ("0 0 0\n"), more than the file's.
    expect("vertices.off", "header declares 20 vertices, more than the file's " +
                               std::to_string(fs::file_size(dir / "vertices.off")) +
                               " bytes can hold (truncated or corrupt header)");
    expect("vertices.ply", "header declares 100000000 vertex, more than the file's " +
                               std::to_string(fs::file_size(dir / "vertices.ply")) +
                               " bytes can hold (truncated or corrupt header)");
    expect("ascii.ply", "header declares 4000000000000000000 face, more than the file's " +
                            std::to_string(fs::file_size(dir / "ascii.ply")) +
                            " bytes can hold (truncated or corrupt header)");
  });
  EXPECT_LT(seconds, 2.0);
  // Headers that fit are read as before.
  writeText(dir / "ok.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(solo::readMesh(dir / "ok.off").faces.size(), 1u);
}

// ------------------------------------------------------------------ writers on a full disk

TEST(CheckedWrites, EveryWriterFailsOnAFullDiskNamingTheTargetAndLeavesNothing) {
  TempDir dir;
  cv::Mat noise(64, 64, CV_16UC3);
  cv::randu(noise, 0, 65535);
  cv::Mat noise8;
  noise.convertTo(noise8, CV_8UC3, 1.0 / 257.0);
  cv::Mat depth(64, 64, CV_32F);
  cv::randu(depth, 1.0f, 50.0f);
  cv::Mat normals(64, 64, CV_32FC3);
  cv::randu(normals, -1.0f, 1.0f);
  solo::TriangleMesh mesh;
  for (int i = 0; i < 300; ++i) {
    mesh.vertices.emplace_back(i, i * 0.5, i * 0.25);
    if (i >= 2)
      mesh.faces.push_back(
          {static_cast<std::uint32_t>(i - 2), static_cast<std::uint32_t>(i - 1), static_cast<std::uint32_t>(i)});
  }
  const std::vector<std::pair<std::string, std::function<void(const fs::path&)>>> writers = {
      {"a.png", [&](const fs::path& f) { solo::writeImage(f, noise); }},
      {"a.jpg", [&](const fs::path& f) { solo::writeImage(f, noise8); }},
      {"a.tif", [&](const fs::path& f) { solo::writeImage(f, noise); }},
      {"a.exr", [&](const fs::path& f) { solo::writeImage(f, depth); }},
      {"a.pfm", [&](const fs::path& f) { solo::writeImage(f, depth); }},
      {"a.npy", [&](const fs::path& f) { solo::writeImage(f, depth); }},
      {"d.png", [&](const fs::path& f) { solo::writeDepth(f, depth); }},
      {"n.png", [&](const fs::path& f) { solo::writeNormals(f, normals); }},
      {"m.ply", [&](const fs::path& f) { solo::writeMesh(f, mesh); }},
      {"m.off", [&](const fs::path& f) { solo::writeMesh(f, mesh); }},
      {"t.json", [&](const fs::path& f) { solo::writeTextAtomically(f, std::string(5000, 'x')); }},
  };
  for (const auto& [name, write] : writers) {
    std::string message;
    {
      const FileSizeLimit full_disk(1024);
      message = messageOf([&] { write(dir / name); });
    }
    EXPECT_EQ(message.rfind((dir / name).string() + ": write failed", 0), 0u) << name << ": " << message;
    EXPECT_TRUE(solo::test::listFolder(dir.path()).empty()) << name << ": no file and no temporary left";
    write(dir / name);  // with room the same write succeeds
    EXPECT_GT(fs::file_size(dir / name), 1024u) << name;
    fs::remove(dir / name);
  }
}

namespace {

// In a child process: removeTemporariesOnSignals, then a writeAtomically whose writer creates
// its temporary, writes half of it, tells the parent (one byte on `ready`) and waits to be
// signalled. Returns the child's pid.
pid_t startWriterThatWaitsForASignal(const fs::path& target, int ready) {
  const pid_t pid = ::fork();
  if (pid != 0) return pid;
  solo::removeTemporariesOnSignals();
  try {
    solo::writeAtomically(target, [ready](const fs::path& temporary) {
      writeText(temporary, "half of a file");
      const char byte = 1;
      if (::write(ready, &byte, 1) != 1) ::_exit(3);
      while (true) ::pause();
    });
  } catch (...) {
    ::_exit(5);
  }
  ::_exit(4);
}

std::vector<std::string> hiddenFiles(const fs::path& folder) {
  std::vector<std::string> hidden;
  for (const std::string& name : solo::test::listFolder(folder))
    if (name[0] == '.') hidden.push_back(name);
  return hidden;
}

}  // namespace

TEST(CheckedWrites, ASignalDuringAWriteRemovesTheTemporaryAndEndsByThatSignal) {
  for (const int signal : {SIGTERM, SIGINT, SIGHUP}) {
    TempDir dir;
    int pipe_ends[2];
    ASSERT_EQ(::pipe(pipe_ends), 0);
    const pid_t child = startWriterThatWaitsForASignal(dir / "sheet.png", pipe_ends[1]);
    ::close(pipe_ends[1]);
    char byte = 0;
    ASSERT_EQ(::read(pipe_ends[0], &byte, 1), 1) << "the writer started";
    ::close(pipe_ends[0]);
    ASSERT_EQ(hiddenFiles(dir.path()).size(), 1u) << "the temporary exists while it is written";
    ::kill(child, signal);
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == signal) << "signal " << signal << ", status " << status;
    EXPECT_TRUE(hiddenFiles(dir.path()).empty()) << "signal " << signal << ": " << hiddenFiles(dir.path())[0];
    EXPECT_FALSE(fs::exists(dir / "sheet.png"));
  }
}

TEST(CheckedWrites, ASignalRemovesALiveStagingFolderWithEverythingInIt) {
  TempDir dir;
  int pipe_ends[2];
  ASSERT_EQ(::pipe(pipe_ends), 0);
  const fs::path staging = dir / ".scene.tmp1";
  const pid_t child = ::fork();
  if (child == 0) {
    solo::removeTemporariesOnSignals();
    const solo::LiveTemporaryFolder registered(staging);
    fs::create_directories(staging / "gt" / "deeper");
    for (int i = 0; i < 300; ++i) writeText(staging / ("map" + std::to_string(i) + ".png"), "x");  // several reads
    writeText(staging / "gt" / "depth.exr", "x");
    writeText(staging / "gt" / "deeper" / "mesh.ply", "x");
    const char byte = 1;
    if (::write(pipe_ends[1], &byte, 1) != 1) ::_exit(3);
    while (true) ::pause();
  }
  ::close(pipe_ends[1]);
  char byte = 0;
  ASSERT_EQ(::read(pipe_ends[0], &byte, 1), 1) << "the child filled its staging folder";
  ::close(pipe_ends[0]);
  ASSERT_TRUE(fs::exists(staging / "gt" / "deeper" / "mesh.ply"));
  ::kill(child, SIGTERM);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM) << status;
  EXPECT_EQ(solo::test::listFolder(dir.path()), std::vector<std::string>{});
}

TEST(CheckedWrites, AStagingFolderNoLongerRegisteredIsLeftAlone) {
  TempDir dir;
  fs::create_directories(dir / "out");
  { const solo::LiveTemporaryFolder registered(dir / "out"); }
  writeText(dir / "out" / "kept.txt", "x");
  solo::removeLiveTemporaries();
  EXPECT_EQ(solo::test::readText(dir / "out" / "kept.txt"), "x");
}

TEST(CheckedWrites, AWriteThatEndedLeavesNothingForTheSignalHandler) {
  TempDir dir;
  solo::writeTextAtomically(dir / "a.json", "{}\n");
  EXPECT_THROW(solo::writeAtomically(dir / "b.json", [](const fs::path& temporary) {
                 writeText(temporary, "x");
                 throw solo::InputError(temporary, "failed on purpose");
               }),
               solo::InputError);
  solo::removeLiveTemporaries();  // what a signal would do now: nothing of the finished writes
  EXPECT_EQ(solo::test::readText(dir / "a.json"), "{}\n");
  EXPECT_EQ(solo::test::listFolder(dir.path()), std::vector<std::string>{"a.json"});
}

// ------------------------------------------------------------------ fuzzing findings (tests/fuzz)

TEST(FuzzFindings, APlyPropertyBeforeAnyElementIsRefusedNotDereferenced) {
  // fuzz_mesh_ply: CGAL's PLY reader took the last element of an empty list (a crash in solo
  // mesh clean) when a "property" line came before every "element" line.
  TempDir dir;
  writeText(dir / "p.ply",
            "ply\nformat ascii 1.0\nrmat binary_little_endianelement vertex 4\nproperty float x\nproperty float y\n"
            "property float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n");
  EXPECT_EQ(messageOf([&] { solo::readMesh(dir / "p.ply"); }),
            (dir / "p.ply").string() +
                ": cannot read as a mesh: PLY header has a property before any element (corrupt header)");
  writeText(dir / "long.ply", "ply\nformat ascii 1.0\n" + std::string(70000, 'c') + "\n");
  EXPECT_NE(messageOf([&] { solo::readMesh(dir / "long.ply"); }).find("PLY header has no end_header in its first 65536 bytes"),
            std::string::npos);
}

TEST(FuzzFindings, NpyHeadersWithoutAValueOrAClosingQuoteAreRefused) {
  // fuzz_map_npy: 'fortran_order': at the end of the header, with only spaces after it, threw
  // std::out_of_range from std::string::compare instead of an InputError naming the file.
  TempDir dir;
  const auto npy = [](const std::string& header) {
    return std::string("\x93NUMPY\x01\x00", 8) + static_cast<char>(header.size()) + '\0' + header + std::string(12, '\0');
  };
  writeText(dir / "f.npy", npy("{'descr': '|u1', 'shape': (3, 4), 'fortran_order':" + std::string(40, ' ')));
  EXPECT_EQ(messageOf([&] { solo::readColorImage(dir / "f.npy"); }),
            (dir / "f.npy").string() + ": malformed .npy header: 'fortran_order' has no value");
  writeText(dir / "d.npy", npy("{'shape': (3, 4), 'fortran_order': False, 'descr': '|u1\n"));
  EXPECT_EQ(messageOf([&] { solo::readDepth(dir / "d.npy", 1.0); }),
            (dir / "d.npy").string() + ": malformed .npy descr: no closing quote");
}

TEST(FuzzFindings, PlyVertexCoordinatesMustBeFloatScalars) {
  // fuzz_mesh_ply: a list (or integer) property named x in the vertex element made CGAL's reader
  // call through a null pointer (a crash in solo mesh clean).
  TempDir dir;
  writeText(dir / "list.ply",
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float y\nproperty float z\n"
            "property list uchar int x\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
            "0 0 1 0\n1 0 1 1\n0 1 1 2\n3 0 1 2\n");
  EXPECT_EQ(messageOf([&] { solo::readMesh(dir / "list.ply"); }),
            (dir / "list.ply").string() +
                ": cannot read as a mesh: PLY vertex coordinate x is a list, not a float or double (corrupt header)");
  // CGAL takes " ply" as the signature and the second line as the format line, whatever it holds.
  writeText(dir / "spaced.ply", " ply\nformat binary_little_endian 1.0\nproperty float x\nend_header\n");
  EXPECT_NE(messageOf([&] { solo::readMesh(dir / "spaced.ply"); }).find("PLY header has a property before any element"),
            std::string::npos);
  writeText(dir / "second.ply", "ply\nelement vertex 1\nproperty float x\nend_header\n0\n");
  EXPECT_NE(messageOf([&] { solo::readMesh(dir / "second.ply"); }).find("PLY header has a property before any element"),
            std::string::npos);
  // fuzz_mesh_ply: an element without properties and a count of 8888888884 kept CGAL looping.
  writeText(dir / "empty.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                               "property float z\nelement e 8888888884\nend_header\n0 0 0\n1 0 0\n0 1 0\n");
  const auto start = std::chrono::steady_clock::now();
  EXPECT_NE(messageOf([&] { solo::readMesh(dir / "empty.ply"); }).find("header declares 8888888884 e, more than"),
            std::string::npos);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 2.0);
  // fuzz_mesh_ply: a face list whose signed short size reads -15984 made CGAL resize a vector
  // to 2^64 - 15984 items (std::length_error escaping the reader).
  std::string negative = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                         "property float y\nproperty float z\nelement face 1\n"
                         "property list short int vertex_indices\nend_header\n" + std::string(36, '\0');
  negative += std::string("\x90\xc1", 2) + std::string(12, '\0');
  writeText(dir / "negative.ply", negative);
  EXPECT_EQ(messageOf([&] { solo::readMesh(dir / "negative.ply"); }),
            (dir / "negative.ply").string() + ": cannot read as a mesh: PLY face 0 has a list of negative size -15984 (corrupt file)");
  writeText(dir / "count.ply", "ply\nformat ascii 1.0\nelement vertex 3x\nproperty float x\nend_header\n0\n1\n2\n");
  EXPECT_NE(messageOf([&] { solo::readMesh(dir / "count.ply"); }).find("PLY element vertex has the count \"3x\""),
            std::string::npos);
}

TEST(FuzzFindings, PlyListSizesBeyondTheFileAreRefusedBeforeAllocation) {
  // fuzz_mesh_ply: a binary face list whose uint size read 4294967289 made CGAL resize a vector
  // to it (16 GB, out of memory after two minutes).
  TempDir dir;
  const std::string header = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                             "element face 2\nproperty list uint int vertex_indices\nend_header\n";
  const std::string vertices(36, '\0');
  const std::string triangle = std::string("\x03\0\0\0", 4) + std::string("\0\0\0\0\x01\0\0\0\x02\0\0\0", 12);
  writeText(dir / "huge.ply", "ply\nformat binary_little_endian 1.0\n" + header + vertices + triangle +
                                  std::string("\xf9\xff\xff\xff", 4) + std::string(12, '\0'));
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(messageOf([&] { solo::readMesh(dir / "huge.ply"); }),
            (dir / "huge.ply").string() +
                ": cannot read as a mesh: PLY face 1 has a list of 4294967289 values, more than the 12 bytes after it can "
                "hold (corrupt file)");
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 2.0);
  // The same list size in big-endian order, and a size that fits exactly: the second face reads.
  writeText(dir / "big.ply", "ply\nformat binary_big_endian 1.0\n" + header + vertices +
                                 std::string("\0\0\0\x03", 4) + std::string("\0\0\0\0\0\0\0\x01\0\0\0\x02", 12) +
                                 std::string("\xff\xff\xff\xf9", 4) + std::string(12, '\0'));
  EXPECT_NE(messageOf([&] { solo::readMesh(dir / "big.ply"); }).find("PLY face 1 has a list of 4294967289 values"),
            std::string::npos);
  writeText(dir / "fits.ply", "ply\nformat binary_little_endian 1.0\n" + header + vertices + triangle + triangle);
  EXPECT_EQ(solo::readMesh(dir / "fits.ply").faces.size(), 2u);
  // ASCII: a uint size of 4e9, and an int size beyond int32 (the extraction fails and leaves
  // INT_MAX, which CGAL's reader still sized its vector from).
  const std::string ascii = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                            "property float z\nelement face 1\nproperty list ";
  writeText(dir / "ascii.ply", ascii + "uint int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n4000000000 0 1 2\n");
  EXPECT_NE(messageOf([&] { solo::readMesh(dir / "ascii.ply"); }).find("PLY face 0 has a list of 4000000000 values"),
            std::string::npos);
  writeText(dir / "wide.ply", ascii + "int int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n9999999999 0 1 2\n");
  EXPECT_NE(messageOf([&] { solo::readMesh(dir / "wide.ply"); }).find("PLY face 0 has a list of 2147483647 values"),
            std::string::npos);
  writeText(dir / "plain.ply", ascii + "uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2");
  EXPECT_EQ(solo::readMesh(dir / "plain.ply").faces.size(), 1u);
}

TEST(FuzzFindings, PlyListSizesCutOffByTheEndOfTheFileAreRefused) {
  // fuzz_mesh_ply: a binary list element whose body is one byte: CGAL's reader read the uint list
  // size from 1 of its 4 bytes, took the rest from uninitialised memory and sized a vector from it
  // (2.7 billion ints under AddressSanitizer).
  TempDir dir;
  const std::string header = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                             "element face 1\nproperty list uint int vertex_indices\nend_header\n";
  const std::string vertices(36, '\0');
  writeText(dir / "cut.ply", "ply\nformat binary_little_endian 1.0\n" + header + vertices + "i");
  const std::string cut_message = ": cannot read as a mesh: PLY face 0 has a list whose size the end of the file cuts "
                                  "off (truncated file)";
  EXPECT_EQ(messageOf([&] { solo::readMesh(dir / "cut.ply"); }), (dir / "cut.ply").string() + cut_message);
  writeText(dir / "ends.ply", "ply\nformat binary_big_endian 1.0\n" + header + vertices);
  EXPECT_EQ(messageOf([&] { solo::readMesh(dir / "ends.ply"); }), (dir / "ends.ply").string() + cut_message);
  // ASCII: the file ends (after white space) where the face's list size should be: the reader's
  // integer extraction fails before it starts and leaves the size uninitialised.
  const std::string ascii = "ply\nformat ascii 1.0\n" + header + "0 0 0\n1 0 0\n0 1 0\n";
  writeText(dir / "ascii.ply", ascii + " \n");
  EXPECT_EQ(messageOf([&] { solo::readMesh(dir / "ascii.ply"); }), (dir / "ascii.ply").string() + cut_message);
  // A size that is there, even as the file's last token, reads.
  writeText(dir / "last.ply", ascii + "3 0 1 2");
  EXPECT_EQ(solo::readMesh(dir / "last.ply").faces.size(), 1u);
}

TEST(FuzzFindings, OffFacesWithNegativeHugeOrMissingIndicesAndOffVariantsAreRefused) {
  // fuzz_mesh_off: CGAL converts a face's vertex count and indices from double to size_t
  // (undefined for -1 or 1e23), sizes the face from the count before reading it (111111111111
  // corners: 888 GB), and overflows its buffers reading COFF colours.
  TempDir dir;
  const std::string vertices = "0 0 0\n1 0 0\n0 1 0\n";
  writeText(dir / "negative.off", "OFF\n3 1 0\n" + vertices + "3 0 2-1\n");
  EXPECT_EQ(messageOf([&] { solo::readMesh(dir / "negative.off"); }),
            (dir / "negative.off").string() +
                ": cannot read as a mesh: face 0 has -1 as a vertex index, not a whole number from 0 to 2^53 (corrupt file)");
  writeText(dir / "huge.off", "OFF\n3 1 0\n" + vertices + "88888888888888888888888 0 1 2\n");
  EXPECT_NE(messageOf([&] { solo::readMesh(dir / "huge.off"); }).find("face 0 has 8.88889e+22 as its vertex count"),
            std::string::npos);
  writeText(dir / "counted.off", "OFF\n3 1 0\n" + vertices + "111111111111 0 1 2\n");
  EXPECT_NE(messageOf([&] { solo::readMesh(dir / "counted.off"); }).find("face 0 declares more vertices"),
            std::string::npos);
  // The counts' line may carry the first vertex, as CGAL reads it.
  writeText(dir / "shifted.off", "OFF\n3 1 0 0 0 0\n1 0 0\n0 1 0\n-5 0 1 2\n");
  EXPECT_NE(messageOf([&] { solo::readMesh(dir / "shifted.off"); }).find("face 0 has -5 as its vertex count"),
            std::string::npos);
  writeText(dir / "colour.off", "COFF\n4 4    2301 0 1 3\n3 0 y 03 2\n3\n");
  EXPECT_NE(messageOf([&] { solo::readMesh(dir / "colour.off"); }).find("this one with \"COFF\""), std::string::npos);
  writeText(dir / "glued.off", "OFF$0\n3 5 0\n" + vertices);
  EXPECT_NE(messageOf([&] { solo::readMesh(dir / "glued.off"); }).find("this one with \"OFF$0\""), std::string::npos);
  writeText(dir / "ok.off", "OFF\n# a comment\n3 1 0\n" + vertices + "\n3 0 1 2 # the face\n");
  EXPECT_EQ(solo::readMesh(dir / "ok.off").faces.size(), 1u);
}

TEST(FuzzFindings, OffIsReadBySolosOwnReaderWhateverItsCommentsAndNumbers) {
  // fuzz_mesh_off: "OFF#1 5 0.0 0", then "0 0 00" and "-05": CGAL's scanner took other counts
  // than a check in front of it could follow and converted the face size -5 to size_t
  // (undefined behaviour). solo reads plain OFF itself.
  TempDir dir;
  writeText(dir / "found.off", "OFF#1 5 0.0 0\n0 0 00 \n-05" + std::string(120, '\0') + "913\n");
  EXPECT_EQ(messageOf([&] { solo::readMesh(dir / "found.off"); }), (dir / "found.off").string() + ": mesh has no vertices");
  writeText(dir / "face.off", "OFF 3 1 0\n0 0 0 1 0 0 0 1 0\n-05 0 1 2\n");
  EXPECT_EQ(messageOf([&] { solo::readMesh(dir / "face.off"); }),
            (dir / "face.off").string() +
                ": cannot read as a mesh: face 0 has -5 as its vertex count, not a whole number from 0 to 2^53 (corrupt file)");
  writeText(dir / "half.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2.5 0 1 2\n");
  EXPECT_NE(messageOf([&] { solo::readMesh(dir / "half.off"); }).find("face 0 has 2.5 as its vertex count"),
            std::string::npos);
  writeText(dir / "word.off", "OFF\n3 1 0\n0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(messageOf([&] { solo::readMesh(dir / "word.off"); }),
            (dir / "word.off").string() + ": cannot read as a mesh: vertex 1 has \"x\" as a coordinate, not a number");
  writeText(dir / "short.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(messageOf([&] { solo::readMesh(dir / "short.off"); }),
            (dir / "short.off").string() + ": cannot read as a mesh: malformed or truncated: the file ends before its faces");
  writeText(dir / "binary.off", "OFF BINARY\n" + std::string(12, '\0'));
  EXPECT_NE(messageOf([&] { solo::readMesh(dir / "binary.off"); }).find("binary OFF is not read"), std::string::npos);
  // Counts and the first vertex on the keyword's line, a face with a colour after its indices,
  // comments anywhere: read as written.
  writeText(dir / "packed.off", "OFF 4 2 0 0 0 0 # square\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2 255 0 0\n3 0 2 3\n");
  const solo::TriangleMesh packed = solo::readMesh(dir / "packed.off");
  ASSERT_EQ(packed.vertices.size(), 4u);
  EXPECT_EQ(packed.vertices[2], Eigen::Vector3d(1, 1, 0));
  ASSERT_EQ(packed.faces.size(), 2u);
  EXPECT_EQ(packed.faces[1][2], 3u);
}

TEST(FuzzFindings, ALightRecordNumberBeyondADoubleIsMalformedJson) {
  // fuzz_light_record: nlohmann's out_of_range for "-32.55E3521653077" escaped as a non-InputError.
  TempDir dir;
  writeText(dir / "lights.json", "{\"format\": \"solo-lights/1\", \"seed\": -32.55E3521653077}");
  EXPECT_NE(messageOf([&] { solo::readLightRecord(dir / "lights.json"); }).find("lights.json: malformed JSON"),
            std::string::npos);
}

TEST(FuzzFindings, ExrAttributeSizesBeyondTheFileAreRefusedQuickly) {
  // fuzz_map_exr: a 135-byte header whose attribute sizes claim more than the file took OpenEXR
  // 15 s and 1.7 GB before it failed.
  TempDir dir;
  const std::string header = std::string("\x76\x2f\x31\x01\x02\x00\x00\x00", 8) + "channels" + '\0' + "chlist" + '\0' +
                             std::string("\xff\xff\xff\x4f", 4) + "Y";
  writeText(dir / "big.exr", header);
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(messageOf([&] { solo::readDepth(dir / "big.exr", 0); }),
            (dir / "big.exr").string() +
                ": OpenEXR header: attribute channels declares 1342177279 bytes, more than the 1 left in the file "
                "(truncated or corrupt)");
  writeText(dir / "cut.exr", std::string("\x76\x2f\x31\x01\x02\x00\x00\x00", 8) + "channels");
  EXPECT_NE(messageOf([&] { solo::readDepth(dir / "cut.exr", 0); }).find("attribute name without its end"),
            std::string::npos);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 2.0);
}
