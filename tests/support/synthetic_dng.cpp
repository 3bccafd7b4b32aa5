#include "synthetic_dng.h"

#include <tiffio.h>

#include <array>
#include <memory>
#include <stdexcept>
#include <vector>

namespace solo::test {

namespace {

constexpr std::uint16_t kPhotometricLinearRaw = 34892;  // not named in libtiff 4.5's tiff.h

struct TiffCloser {
  void operator()(TIFF* t) const { TIFFClose(t); }
};

void check(int ok, const std::filesystem::path& file, const char* what) {
  if (ok != 1) throw std::runtime_error(file.string() + ": libtiff refused " + what);
}

}  // namespace

void writeSyntheticDng(const std::filesystem::path& file, const SyntheticDng& dng) {
  if (dng.camera_raw.type() != CV_16UC3 || dng.camera_raw.empty())
    throw std::runtime_error("writeSyntheticDng: camera_raw must be a non-empty CV_16UC3 image");
  const bool bayer = dng.layout == SyntheticDng::Layout::kBayerRggb;
  if (bayer && (dng.camera_raw.cols % 2 != 0 || dng.camera_raw.rows % 2 != 0))
    throw std::runtime_error("writeSyntheticDng: a Bayer image needs even width and height");
  std::unique_ptr<TIFF, TiffCloser> tif(TIFFOpen(file.c_str(), "w"));
  if (!tif) throw std::runtime_error(file.string() + ": cannot be created");
  TIFF* t = tif.get();
  const int width = dng.camera_raw.cols, height = dng.camera_raw.rows;
  const int samples = bayer ? 1 : 3;
  check(TIFFSetField(t, TIFFTAG_SUBFILETYPE, 0), file, "NewSubFileType");
  check(TIFFSetField(t, TIFFTAG_IMAGEWIDTH, width), file, "ImageWidth");
  check(TIFFSetField(t, TIFFTAG_IMAGELENGTH, height), file, "ImageLength");
  check(TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, 16), file, "BitsPerSample");
  check(TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, samples), file, "SamplesPerPixel");
  check(TIFFSetField(t, TIFFTAG_COMPRESSION, COMPRESSION_NONE), file, "Compression");
  check(TIFFSetField(t, TIFFTAG_PHOTOMETRIC, bayer ? PHOTOMETRIC_CFA : kPhotometricLinearRaw), file, "Photometric");
  check(TIFFSetField(t, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG), file, "PlanarConfiguration");
  check(TIFFSetField(t, TIFFTAG_ORIENTATION, ORIENTATION_TOPLEFT), file, "Orientation");
  check(TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, height), file, "RowsPerStrip");
  check(TIFFSetField(t, TIFFTAG_MAKE, dng.make.c_str()), file, "Make");
  check(TIFFSetField(t, TIFFTAG_MODEL, dng.model.c_str()), file, "Model");
  const std::string unique_model = dng.make + " " + dng.model;
  check(TIFFSetField(t, TIFFTAG_UNIQUECAMERAMODEL, unique_model.c_str()), file, "UniqueCameraModel");
  const std::array<std::uint8_t, 4> version{1, 4, 0, 0};
  check(TIFFSetField(t, TIFFTAG_DNGVERSION, version.data()), file, "DNGVersion");
  check(TIFFSetField(t, TIFFTAG_DNGBACKWARDVERSION, version.data()), file, "DNGBackwardVersion");
  if (bayer) {
    const std::array<std::uint16_t, 2> repeat{2, 2};
    const std::array<std::uint8_t, 4> rggb{0, 1, 1, 2};
    check(TIFFSetField(t, TIFFTAG_CFAREPEATPATTERNDIM, repeat.data()), file, "CFARepeatPatternDim");
    check(TIFFSetField(t, TIFFTAG_CFAPATTERN, 4, rggb.data()), file, "CFAPattern");
  }
  // One black level per sample (DNG: BlackLevelRepeatDim 1x1 times SamplesPerPixel values).
  const std::vector<float> black(samples, static_cast<float>(dng.black_level));
  check(TIFFSetField(t, TIFFTAG_BLACKLEVEL, samples, black.data()), file, "BlackLevel");
  const std::vector<std::uint32_t> white(samples, dng.white_level);
  check(TIFFSetField(t, TIFFTAG_WHITELEVEL, samples, white.data()), file, "WhiteLevel");
  std::array<float, 9> matrix{};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) matrix[r * 3 + c] = static_cast<float>(dng.color_matrix(r, c));
  check(TIFFSetField(t, TIFFTAG_COLORMATRIX1, 9, matrix.data()), file, "ColorMatrix1");
  check(TIFFSetField(t, TIFFTAG_CALIBRATIONILLUMINANT1, dng.calibration_illuminant), file, "CalibrationIlluminant1");
  const std::array<float, 3> neutral{static_cast<float>(dng.as_shot_neutral.x()),
                                     static_cast<float>(dng.as_shot_neutral.y()),
                                     static_cast<float>(dng.as_shot_neutral.z())};
  check(TIFFSetField(t, TIFFTAG_ASSHOTNEUTRAL, 3, neutral.data()), file, "AsShotNeutral");

  std::vector<std::uint16_t> row(static_cast<std::size_t>(width) * samples);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const cv::Vec3w& v = dng.camera_raw.at<cv::Vec3w>(y, x);
      if (bayer) {
        const int colour = (y % 2 == 0) ? (x % 2 == 0 ? 0 : 1) : (x % 2 == 0 ? 1 : 2);  // RGGB
        row[x] = v[colour];
      } else {
        for (int c = 0; c < 3; ++c) row[static_cast<std::size_t>(x) * 3 + c] = v[c];
      }
    }
    if (TIFFWriteScanline(t, row.data(), static_cast<std::uint32_t>(y), 0) != 1)
      throw std::runtime_error(file.string() + ": cannot write row " + std::to_string(y));
  }
  if (TIFFWriteDirectory(t) != 1) throw std::runtime_error(file.string() + ": cannot write the directory");
}

}  // namespace solo::test
