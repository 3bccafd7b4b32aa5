#include "solo/lighting/raw_gray_card.h"

#include "solo/lighting/colorimetry.h"

#include <solo/core/error.h>
#include <solo/core/input_file.h>

#include <OpenImageIO/imageio.h>

#include <memory>
#include <vector>

namespace solo {

namespace {

// LibRaw scales each camera channel by its daylight multiplier (from the colour matrix)
// before the matrix, normalised to the smallest multiplier under the default highlight mode
// 0: a channel with a larger multiplier then saturates (is cut at 65535) well below the raw
// white level, and a bright but unsaturated card comes out with a wrong colour. Highlight
// mode 1 ("unclip") normalises to the largest multiplier instead, so nothing below the
// white level is cut; the colour of unsaturated pixels is the same in both modes.
std::unique_ptr<OIIO::ImageInput> openRaw(const std::filesystem::path& raw_file, bool camera_rgb) {
  OIIO::ImageSpec config;
  config.attribute("raw:use_camera_wb", 0);
  config.attribute("raw:use_camera_matrix", 1);
  config.attribute("raw:auto_bright", 0);
  config.attribute("raw:adjust_maximum_thr", 0.0f);
  config.attribute("raw:HighlightMode", 1);
  if (camera_rgb) {
    // Camera RGB with unit multipliers: black subtracted, 1.0 at the white level.
    config.attribute("raw:ColorSpace", "raw");
    const float unit[4] = {1, 1, 1, 1};
    config.attribute("raw:user_mul", OIIO::TypeDesc(OIIO::TypeDesc::FLOAT, 4), unit);
  } else {
    config.attribute("raw:ColorSpace", "XYZ");
  }
  auto input = OIIO::ImageInput::open(raw_file.string(), &config);
  if (!input) throw InputError(raw_file, "cannot be read as a raw photo: " + OIIO::geterror());
  if (std::string(input->format_name()) != "raw")
    throw InputError(raw_file, std::string("is not a camera raw file (read as ") + input->format_name() + ")");
  if (input->spec().nchannels < 3) throw InputError(raw_file, "decoded to fewer than 3 channels");
  return input;
}

// Debian's OpenImageIO has its global "debug" attribute on by default, and the raw plugin then
// prints a note on stderr at every open and decode with a highlight mode other than 0: silenced
// while measuring, restored afterwards.
class QuietOpenImageIo {
 public:
  QuietOpenImageIo() {
    OIIO::getattribute("debug", debug_);
    OIIO::attribute("debug", 0);
  }
  ~QuietOpenImageIo() { OIIO::attribute("debug", debug_); }
  QuietOpenImageIo(const QuietOpenImageIo&) = delete;
  QuietOpenImageIo& operator=(const QuietOpenImageIo&) = delete;

 private:
  int debug_ = 0;
};

// The region's rows, all channels, as float (16-bit output / 65535).
std::vector<float> readRows(OIIO::ImageInput& input, const std::filesystem::path& raw_file, const cv::Rect& region) {
  const OIIO::ImageSpec& spec = input.spec();
  std::vector<float> rows(static_cast<std::size_t>(region.height) * spec.width * spec.nchannels);
  if (!input.read_scanlines(0, 0, region.y, region.y + region.height, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT,
                            rows.data()))
    throw InputError(raw_file, "cannot decode the raw data: " + input.geterror());
  return rows;
}

}  // namespace

GrayCardMeasurement measureGrayCard(const std::filesystem::path& raw_file, const cv::Rect& region) {
  requireRegularFile(raw_file, "raw image");
  const QuietOpenImageIo quiet;
  auto xyz_input = openRaw(raw_file, false);
  const OIIO::ImageSpec& spec = xyz_input->spec();
  const cv::Rect image(0, 0, spec.width, spec.height);
  if (region.empty() || (region & image) != region)
    throw InputError(raw_file, "region " + std::to_string(region.x) + "," + std::to_string(region.y) + " " +
                                   std::to_string(region.width) + "x" + std::to_string(region.height) +
                                   " is empty or outside the " + std::to_string(spec.width) + "x" +
                                   std::to_string(spec.height) + " image");
  const std::vector<float> xyz_rows = readRows(*xyz_input, raw_file, region);
  auto camera_input = openRaw(raw_file, true);
  if (camera_input->spec().width != spec.width || camera_input->spec().height != spec.height)
    throw InputError(raw_file, "decodes to different sizes in XYZ and camera RGB");
  const std::vector<float> camera_rows = readRows(*camera_input, raw_file, region);
  const int xyz_channels = spec.nchannels, camera_channels = camera_input->spec().nchannels;

  GrayCardMeasurement m;
  m.camera = std::string(spec.get_string_attribute("Make")) + " " + std::string(spec.get_string_attribute("Model"));
  // A camera channel at the white level (1.0 after black subtraction and scaling), or an XYZ
  // value cut at the 16-bit output limit, means the true colour is unknown.
  constexpr float kSaturated = 65534.0f / 65535.0f;
  for (int y = 0; y < region.height; ++y)
    for (int x = region.x; x < region.x + region.width; ++x) {
      const std::size_t pixel = static_cast<std::size_t>(y) * spec.width + x;
      const float* p = &xyz_rows[pixel * xyz_channels];
      const float* c = &camera_rows[pixel * camera_channels];
      m.xyz += Eigen::Vector3d(p[0], p[1], p[2]);
      if (p[0] >= kSaturated || p[1] >= kSaturated || p[2] >= kSaturated || c[0] >= kSaturated ||
          c[1] >= kSaturated || c[2] >= kSaturated)
        ++m.clipped;
      ++m.pixels;
    }
  m.xyz /= static_cast<double>(m.pixels);
  if (!(m.xyz.sum() > 0) || !(m.xyz.y() > 0)) throw InputError(raw_file, "the region is black: no light to measure");
  m.xy = chromaticity(m.xyz);
  return m;
}

}  // namespace solo
