#include "solo/core/camera.h"

#include "solo/core/error.h"
#include "solo/core/input_file.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>

namespace solo {

PinholeCamera PinholeCamera::acdc() { return {1780.0, 1780.0, 959.5, 539.5, 1920, 1080}; }

PinholeCamera PinholeCamera::scaledTo(int new_width, int new_height) const {
  const double sx = static_cast<double>(new_width) / width;
  const double sy = static_cast<double>(new_height) / height;
  return {fx * sx, fy * sy, (cx + 0.5) * sx - 0.5, (cy + 0.5) * sy - 0.5, new_width, new_height};
}

void validateCamera(const PinholeCamera& c, const std::filesystem::path& source) {
  auto finite = [](double v) { return std::isfinite(v); };
  if (!finite(c.fx) || !finite(c.fy) || !finite(c.cx) || !finite(c.cy))
    throw InputError(source, "camera intrinsics must be finite numbers");
  if (c.fx <= 0 || c.fy <= 0)
    throw InputError(source, "impossible camera: focal lengths must be positive (fx = " + std::to_string(c.fx) +
                                 ", fy = " + std::to_string(c.fy) + ")");
  if (c.width <= 0 || c.height <= 0) throw InputError(source, "camera resolution must be positive");
  if (c.cx < -0.5 * c.width || c.cx > 1.5 * c.width || c.cy < -0.5 * c.height || c.cy > 1.5 * c.height)
    throw InputError(source, "impossible camera: principal point (" + std::to_string(c.cx) + ", " +
                                 std::to_string(c.cy) + ") is far outside the " + std::to_string(c.width) + "x" +
                                 std::to_string(c.height) + " image");
}

PinholeCamera readCityscapesCamera(const std::filesystem::path& file) {
  requireRegularFile(file, "camera");
  std::ifstream in(file);
  if (!in) throw InputError(file, "cannot open for reading");
  nlohmann::json j;
  try {
    in >> j;
  } catch (const nlohmann::json::exception& e) {
    throw InputError(file, std::string("not valid JSON: ") + e.what());
  }
  if (!j.is_object() || !j.contains("intrinsic") || !j["intrinsic"].is_object())
    throw InputError(file, "Cityscapes camera JSON needs an \"intrinsic\" object");
  const auto& k = j["intrinsic"];
  auto number = [&](const char* key) {
    if (!k.contains(key) || !k[key].is_number())
      throw InputError(file, std::string("\"intrinsic\".\"") + key + "\" must be a number");
    return k[key].get<double>();
  };
  PinholeCamera c;
  c.fx = number("fx");
  c.fy = number("fy");
  c.cx = number("u0");
  c.cy = number("v0");
  return c;
}

}  // namespace solo
