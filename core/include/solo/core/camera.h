#pragma once
// Pinhole camera in the OpenCV frame: x right, y down, z forward, units metres and pixels.
// Pixel centres sit at integer coordinates: the centre of a W-pixel row is (W - 1) / 2.

#include <Eigen/Core>
#include <filesystem>
#include <string>

namespace solo {

struct PinholeCamera {
  double fx = 0, fy = 0;  ///< focal lengths, pixels
  double cx = 0, cy = 0;  ///< principal point, pixels
  int width = 0;          ///< resolution the intrinsics refer to, pixels
  int height = 0;

  /// The ACDC GoPro intrinsics at 1920x1080 (reference section 5).
  static PinholeCamera acdc();

  /// The same camera for an image of width x height pixels, same field of view.
  /// Pixel centres are kept: c' = (c + 0.5) * s - 0.5.
  PinholeCamera scaledTo(int new_width, int new_height) const;

  /// Camera-frame point x = depth * K^-1 (u, v, 1) for z-depth `depth_m` at pixel (u, v).
  Eigen::Vector3d backproject(double u, double v, double depth_m) const {
    return {depth_m * (u - cx) / fx, depth_m * (v - cy) / fy, depth_m};
  }
  /// Pixel (u, v) of a camera-frame point with z > 0.
  Eigen::Vector2d project(const Eigen::Vector3d& p) const {
    return {fx * p.x() / p.z() + cx, fy * p.y() / p.z() + cy};
  }
};

/// Throws InputError naming `source` when the camera is impossible: non-finite or
/// non-positive focal lengths, non-positive resolution, or a principal point more than
/// half an image outside the frame.
void validateCamera(const PinholeCamera& camera, const std::filesystem::path& source);

/// Reads a Cityscapes camera JSON ({"intrinsic": {"fx","fy","u0","v0"}, ...}). The
/// resolution fields are left 0: Cityscapes files do not state one.
PinholeCamera readCityscapesCamera(const std::filesystem::path& file);

}  // namespace solo
