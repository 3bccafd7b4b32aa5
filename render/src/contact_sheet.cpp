#include <solo/render/contact_sheet.h>

#include <solo/core/quantile.h>
#include <solo/geometry/spurious_faces.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace solo {

ContactSheetLayout contactSheetLayout(cv::Size image_size, int count, const ContactSheetOptions& o) {
  if (image_size.width <= 0 || image_size.height <= 0 || count <= 0 || o.columns <= 0)
    throw std::invalid_argument("contact sheet: needs an image and at least one tile and column");
  ContactSheetLayout layout;
  const int width = std::min(image_size.width, o.max_tile_width);
  const int height = std::max(
      1, static_cast<int>(std::lround(static_cast<double>(width) * image_size.height / image_size.width)));
  layout.tile = {width, height};
  const int columns = std::min(o.columns, count);
  const int rows = (count + columns - 1) / columns;
  const int cell_height = o.label_height + height;
  layout.sheet = {o.gap + columns * (width + o.gap), o.gap + rows * (cell_height + o.gap)};
  for (int i = 0; i < count; ++i) {
    const int x = o.gap + (i % columns) * (width + o.gap);
    const int y = o.gap + (i / columns) * (cell_height + o.gap);
    layout.labels.emplace_back(x, y, width, o.label_height);
    layout.tiles.emplace_back(x, y + o.label_height, width, height);
  }
  return layout;
}

cv::Mat composeContactSheet(const std::vector<ContactSheetTile>& tiles, const ContactSheetOptions& options) {
  if (tiles.empty()) throw std::invalid_argument("contact sheet: no tile");
  for (const ContactSheetTile& t : tiles)
    if (t.image.empty() || t.image.type() != CV_8UC3)
      throw std::invalid_argument("contact sheet: tile \"" + t.label + "\" is not an 8-bit RGB image");
  const ContactSheetLayout layout = contactSheetLayout(tiles.front().image.size(), static_cast<int>(tiles.size()), options);
  cv::Mat sheet(layout.sheet, CV_8UC3, cv::Scalar(40, 40, 40));
  for (std::size_t i = 0; i < tiles.size(); ++i) {
    cv::Mat target = sheet(layout.tiles[i]);
    if (tiles[i].image.size() == layout.tile) tiles[i].image.copyTo(target);
    else cv::resize(tiles[i].image, target, layout.tile, 0, 0, cv::INTER_AREA);
    // Labels are clipped to their strip so a long one cannot draw over a picture.
    cv::Mat strip = sheet(layout.labels[i]);
    // Small tiles get smaller text so that the label fits its strip.
    int baseline = 0;
    const cv::Size wide = cv::getTextSize(tiles[i].label, cv::FONT_HERSHEY_SIMPLEX, 0.45, 1, &baseline);
    const double scale = std::max(0.25, std::min(0.45, 0.45 * (strip.cols - 4) / std::max(1, wide.width)));
    const cv::Size text = cv::getTextSize(tiles[i].label, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &baseline);
    cv::putText(strip, tiles[i].label, {2, std::min(strip.rows - 2, (strip.rows + text.height) / 2)},
                cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar(235, 235, 235), 1, cv::LINE_AA);
  }
  return sheet;
}

cv::Mat colourizeDepth(const cv::Mat& depth_m, double near_m, double far_m) {
  if (depth_m.type() != CV_32F) throw std::invalid_argument("colourizeDepth: depth must be CV_32F");
  near_m = std::max(near_m, 1e-6);
  far_m = std::max(far_m, near_m * 1.000001);
  const double log_near = std::log(near_m), log_span = std::log(far_m) - log_near;
  cv::Mat codes(depth_m.size(), CV_8U), valid(depth_m.size(), CV_8U);
  for (int y = 0; y < depth_m.rows; ++y) {
    const float* d = depth_m.ptr<float>(y);
    auto* c = codes.ptr<std::uint8_t>(y);
    auto* v = valid.ptr<std::uint8_t>(y);
    for (int x = 0; x < depth_m.cols; ++x) {
      const bool ok = std::isfinite(d[x]) && d[x] > 0.f;
      v[x] = ok ? 255 : 0;
      const double t = ok ? (std::log(static_cast<double>(d[x])) - log_near) / log_span : 0.0;
      c[x] = static_cast<std::uint8_t>(std::lround(255.0 * std::clamp(t, 0.0, 1.0)));
    }
  }
  cv::Mat bgr, rgb;
  cv::applyColorMap(codes, bgr, cv::COLORMAP_TURBO);
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  rgb.setTo(cv::Scalar::all(0), valid == 0);
  return rgb;
}

std::pair<double, double> depthDisplayRange(const std::vector<cv::Mat>& depths_m) {
  std::vector<double> values;
  for (const cv::Mat& depth : depths_m)
    for (int y = 0; y < depth.rows; ++y) {
      const float* d = depth.ptr<float>(y);
      for (int x = 0; x < depth.cols; ++x)
        if (std::isfinite(d[x]) && d[x] > 0.f) values.push_back(d[x]);
    }
  if (values.empty()) return {1.0, 100.0};
  const double near_m = sampleQuantile(values, 0.01);
  const double far_m = sampleQuantile(values, 0.99);
  return {near_m, std::max(far_m, near_m * 1.01)};
}

cv::Mat drawRemovedFaces(const cv::Mat& day_rgb8, const cv::Mat& criteria) {
  if (day_rgb8.type() != CV_8UC3) throw std::invalid_argument("drawRemovedFaces: the day image must be CV_8UC3");
  cv::Mat out = day_rgb8.clone();
  if (criteria.empty()) return out;
  cv::Mat bits;
  if (criteria.size() == day_rgb8.size()) bits = criteria;
  else cv::resize(criteria, bits, day_rgb8.size(), 0, 0, cv::INTER_NEAREST);
  for (int y = 0; y < out.rows; ++y) {
    const auto* b = bits.ptr<std::uint8_t>(y);
    auto* p = out.ptr<cv::Vec3b>(y);
    for (int x = 0; x < out.cols; ++x) {
      if (b[x] & kDepthJump) p[x] = {255, 0, 0};
      else if (b[x] & kUncertain) p[x] = {255, 230, 0};
      else if (b[x] & kInstanceBoundary) p[x] = {0, 230, 255};
      else if (b[x] & kGrazing) p[x] = {255, 0, 255};
    }
  }
  return out;
}

}  // namespace solo
