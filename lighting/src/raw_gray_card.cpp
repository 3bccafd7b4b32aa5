#include "solo/lighting/raw_gray_card.h"

#include "solo/lighting/colorimetry.h"

#include <solo/geometry/error.h>

#include <OpenImageIO/imageio.h>

#include <vector>

namespace solo {

GrayCardMeasurement measureGrayCard(const std::filesystem::path& raw_file, const cv::Rect& region) {
  if (!std::filesystem::exists(raw_file)) throw InputError(raw_file, "file not found");
  OIIO::ImageSpec config;
  config.attribute("raw:ColorSpace", "XYZ");
  config.attribute("raw:use_camera_wb", 0);
  config.attribute("raw:use_camera_matrix", 1);
  config.attribute("raw:auto_bright", 0);
  config.attribute("raw:adjust_maximum_thr", 0.0f);
  config.attribute("raw:HighlightMode", 0);
  auto input = OIIO::ImageInput::open(raw_file.string(), &config);
  if (!input) throw InputError(raw_file, "cannot be read as a raw photo: " + OIIO::geterror());
  if (std::string(input->format_name()) != "raw")
    throw InputError(raw_file, std::string("is not a camera raw file (read as ") + input->format_name() + ")");
  const OIIO::ImageSpec& spec = input->spec();
  const cv::Rect image(0, 0, spec.width, spec.height);
  if (region.empty() || (region & image) != region)
    throw InputError(raw_file, "region " + std::to_string(region.x) + "," + std::to_string(region.y) + " " +
                                   std::to_string(region.width) + "x" + std::to_string(region.height) +
                                   " is empty or outside the " + std::to_string(spec.width) + "x" +
                                   std::to_string(spec.height) + " image");
  if (spec.nchannels < 3) throw InputError(raw_file, "decoded to fewer than 3 channels");
  std::vector<float> rows(static_cast<std::size_t>(region.height) * spec.width * spec.nchannels);
  if (!input->read_scanlines(0, 0, region.y, region.y + region.height, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT,
                             rows.data()))
    throw InputError(raw_file, "cannot decode the raw data: " + input->geterror());
  GrayCardMeasurement m;
  m.camera = std::string(spec.get_string_attribute("Make")) + " " + std::string(spec.get_string_attribute("Model"));
  for (int y = 0; y < region.height; ++y)
    for (int x = region.x; x < region.x + region.width; ++x) {
      const float* p = &rows[(static_cast<std::size_t>(y) * spec.width + x) * spec.nchannels];
      m.xyz += Eigen::Vector3d(p[0], p[1], p[2]);
      if (p[0] >= 0.999f || p[1] >= 0.999f || p[2] >= 0.999f) ++m.clipped;
      ++m.pixels;
    }
  m.xyz /= static_cast<double>(m.pixels);
  if (!(m.xyz.sum() > 0) || !(m.xyz.y() > 0)) throw InputError(raw_file, "the region is black: no light to measure");
  m.xy = chromaticity(m.xyz);
  return m;
}

}  // namespace solo
