#include "test_support.h"

#include <solo/geometry/triangle_mesh.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>
#include <sys/wait.h>

namespace fs = std::filesystem;

namespace solo::test {

TempDir::TempDir() {
  std::random_device device;
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = info ? std::string(info->test_suite_name()) + "_" + info->name() : "solo_test";
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  path_ = fs::temp_directory_path() / ("solo_" + name + "_" + std::to_string(device()));
  fs::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ec;
  fs::remove_all(path_, ec);
}

void writeText(const fs::path& file, const std::string& text) {
  std::ofstream out(file, std::ios::binary);
  out << text;
}

std::string readText(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

void writeTruncatedCopy(const fs::path& source, const fs::path& target, std::size_t bytes) {
  std::string all = readText(source);
  writeText(target, all.substr(0, std::min(bytes, all.size())));
}

void writeSquareAndLiftedSquare(const std::filesystem::path& folder) {
  solo::TriangleMesh square;
  square.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  square.faces = {{0, 1, 2}, {0, 2, 3}};
  solo::writeMesh(folder / "square.off", square);
  for (auto& v : square.vertices) v.z() = 0.25;
  solo::writeMesh(folder / "lifted.ply", square);
}

CommandResult runSolo(const std::string& arguments) {
  const std::string command = std::string("\"") + SOLO_BINARY + "\" " + arguments + " 2>&1";
  CommandResult result;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (!pipe) return result;
  std::array<char, 4096> buffer;
  std::size_t n;
  while ((n = std::fread(buffer.data(), 1, buffer.size(), pipe)) > 0) result.output.append(buffer.data(), n);
  const int status = ::pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

fs::path sharedData(const std::string& relative) {
  const fs::path p = fs::path(SOLO_SHARED_DATA_DIR) / relative;
  return fs::exists(p) ? p : fs::path();
}

std::vector<std::string> listFolder(const fs::path& folder) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(folder)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

std::int64_t metricInt(const solo::StageReport& report, const std::string& name) {
  const solo::MetricValue* v = report.find(name);
  if (!v) ADD_FAILURE() << "no metric " << name;
  return v ? std::get<std::int64_t>(*v) : -1;
}

double metricNumber(const solo::StageReport& report, const std::string& name) {
  const solo::MetricValue* v = report.find(name);
  if (!v) return std::nan("");
  if (const auto* d = std::get_if<double>(v)) return *d;
  if (const auto* i = std::get_if<std::int64_t>(v)) return static_cast<double>(*i);
  return std::nan("");
}

}  // namespace solo::test
