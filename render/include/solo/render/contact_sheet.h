#pragma once
// The contact sheet of a `solo night` run: one PNG that shows at a glance what each stage did.
// Tiles in a grid, row-major, each image downscaled (area averaging) to the tile size with its
// label in a strip above it. Tiles are 8-bit RGB; the helpers below make the depth and
// removed-face pictures.

#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace solo {

struct ContactSheetOptions {
  int columns = 3;
  int max_tile_width = 480;  ///< pixels; smaller images keep their size
  int gap = 6;               ///< pixels between tiles and around the sheet
  int label_height = 22;     ///< pixels of the label strip above each tile
};

/// Where everything goes: tile i's picture at tiles[i], its label strip at labels[i].
struct ContactSheetLayout {
  cv::Size sheet;
  cv::Size tile;
  std::vector<cv::Rect> tiles, labels;
};

/// The layout for `count` tiles of an image of `image_size`: tile width
/// min(image width, max_tile_width), height in the image's aspect ratio (rounded, >= 1).
ContactSheetLayout contactSheetLayout(cv::Size image_size, int count, const ContactSheetOptions& options = {});

struct ContactSheetTile {
  std::string label;
  cv::Mat image;  ///< CV_8UC3 RGB, any size (resized to the tile)
};

/// The sheet (CV_8UC3 RGB, dark grey background, white labels), laid out by
/// contactSheetLayout for the first tile's image size. Throws std::invalid_argument for no
/// tile or a tile that is not CV_8UC3.
cv::Mat composeContactSheet(const std::vector<ContactSheetTile>& tiles, const ContactSheetOptions& options = {});

/// Depth in metres to colours (turbo colormap, RGB) on a log scale from near_m (blue) to far_m
/// (red), so that two maps drawn with the same range compare. Invalid pixels (<= 0, not
/// finite) are black.
cv::Mat colourizeDepth(const cv::Mat& depth_m, double near_m, double far_m);

/// A depth range for colourizeDepth covering the valid pixels of all `depths_m` (CV_32F):
/// their 1st and 99th percentiles (an outlier does not flatten the scale). {1, 100} when no
/// pixel is valid.
std::pair<double, double> depthDisplayRange(const std::vector<cv::Mat>& depths_m);

/// The day image (CV_8UC3 RGB) with each pixel of `criteria` (CV_8U of any size, resampled
/// nearest, SpuriousCriterion bits of the removed faces there) painted: depth jump red,
/// uncertain yellow, instance boundary cyan, grazing magenta (first bit that is set wins).
cv::Mat drawRemovedFaces(const cv::Mat& day_rgb8, const cv::Mat& criteria);

}  // namespace solo
