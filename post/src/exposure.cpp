#include <solo/post/exposure.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

namespace solo {

namespace {
const CameraExposure kReferenceCamera{};  // ISO 3200, 1/30 s, f/2 = +3.25 stops
constexpr double kReferenceStops = 3.25;
}  // namespace

double exposureStops(const ExposureOptions& options) {
  if (!options.camera) {
    if (!std::isfinite(options.stops)) throw std::invalid_argument("exposure stops must be finite");
    return options.stops;
  }
  const CameraExposure& c = *options.camera;
  if (!(c.iso > 0 && std::isfinite(c.iso))) throw std::invalid_argument("camera ISO must be positive");
  if (!(c.shutter_s > 0 && std::isfinite(c.shutter_s)))
    throw std::invalid_argument("camera shutter time must be positive");
  if (!(c.f_number > 0 && std::isfinite(c.f_number))) throw std::invalid_argument("camera f-number must be positive");
  // Sensor exposure is proportional to ISO * t / N^2.
  const double ratio = (c.iso / kReferenceCamera.iso) * (c.shutter_s / kReferenceCamera.shutter_s) *
                       std::pow(kReferenceCamera.f_number / c.f_number, 2.0);
  return kReferenceStops + std::log2(ratio);
}

double exposureScale(const ExposureOptions& options) { return std::exp2(exposureStops(options)); }

StageReport applyExposure(cv::Mat& linear_image, const ExposureOptions& options) {
  Stopwatch clock;
  StageReport report;
  report.name = "exposure";
  const double stops = exposureStops(options);
  const double scale = std::exp2(stops);
  report.add("stops", stops, "EV").add("scale", scale);
  if (options.camera) {
    report.add("camera_iso", options.camera->iso)
        .add("camera_shutter", options.camera->shutter_s, "s")
        .add("camera_f_number", options.camera->f_number);
  }
  if (stops == 0) {
    report.skipped = true;
    report.skip_reason = "exposure of 0 stops: the image is left as it is";
  } else {
    linear_image *= scale;
  }
  report.seconds = clock.seconds();
  return report;
}

cv::Size meteringPreviewSize(int width, int height, int max_pixels) {
  int divisor = 4;
  for (; divisor < 64; divisor *= 2) {
    const int preview_width = width / divisor, preview_height = height / divisor;  // whole pixels
    if (static_cast<double>(preview_width) * preview_height <= max_pixels) break;
  }
  return {std::max(16, width / divisor), std::max(16, height / divisor)};
}

double meteredSensorWhite(const cv::Mat& radiance_xyz, const cv::Mat& emitter_coverage, double percentile, double level) {
  if (radiance_xyz.type() != CV_32FC3 || emitter_coverage.type() != CV_32F ||
      radiance_xyz.size() != emitter_coverage.size())
    throw std::invalid_argument("meteredSensorWhite: expects a CV_32FC3 radiance and a CV_32F emitter coverage of the "
                                "same size");
  std::vector<float> y;
  y.reserve(radiance_xyz.total());
  for (int r = 0; r < radiance_xyz.rows; ++r)
    for (int c = 0; c < radiance_xyz.cols; ++c) {
      const float v = radiance_xyz.at<cv::Vec3f>(r, c)[1];
      if (emitter_coverage.at<float>(r, c) == 0.f && v > 0.f) y.push_back(v);
    }
  if (y.empty()) return 1.0;
  const auto k = static_cast<std::ptrdiff_t>(percentile * static_cast<double>(y.size() - 1));
  std::nth_element(y.begin(), y.begin() + k, y.end());
  return std::max(1e-6, static_cast<double>(y[static_cast<std::size_t>(k)]) / level);
}

namespace {

void checkNightCamera(const NightCameraOptions& o) {
  const auto positive = [](double v) { return v > 0 && std::isfinite(v); };
  if (!(positive(o.f_number) && positive(o.min_shutter_s) && positive(o.max_shutter_s) && positive(o.min_iso) &&
        positive(o.max_iso) && positive(o.meter_constant) && positive(o.saturation_exposure) &&
        positive(o.lens_factor)))
    throw std::invalid_argument("night camera: every setting must be positive and finite");
  if (!(std::abs(o.compensation_ev) <= 10)) throw std::invalid_argument("night camera: compensation outside +-10 EV");
  if (o.min_shutter_s > o.max_shutter_s) throw std::invalid_argument("night camera: min shutter above max shutter");
  if (o.min_iso > o.max_iso) throw std::invalid_argument("night camera: min ISO above max ISO");
}

}  // namespace

NightCameraExposure nightCameraExposure(double metered_cd_m2, const NightCameraOptions& o) {
  checkNightCamera(o);
  if (!(metered_cd_m2 >= 0 && std::isfinite(metered_cd_m2)))
    throw std::invalid_argument("night camera: the metered luminance must be finite and >= 0");
  const double n2 = o.f_number * o.f_number;
  // Exposure product S t the meter asks for; infinite when nothing is lit.
  const double wanted_st = metered_cd_m2 > 0 ? std::exp2(o.compensation_ev) * o.meter_constant * n2 / metered_cd_m2
                                             : std::numeric_limits<double>::infinity();
  NightCameraExposure e;
  e.metered_cd_m2 = metered_cd_m2;
  e.camera.f_number = o.f_number;
  e.camera.iso = o.min_iso;
  e.camera.shutter_s = std::clamp(wanted_st / o.min_iso, o.min_shutter_s, o.max_shutter_s);
  if (wanted_st / o.min_iso > o.max_shutter_s)
    e.camera.iso = std::min(o.max_iso, wanted_st / o.max_shutter_s);
  const double st = e.camera.iso * e.camera.shutter_s;
  e.at_exposure_limit = st < wanted_st * (1 - 1e-12);
  e.at_bright_limit = st > wanted_st * (1 + 1e-12);
  e.white_cd_m2 = o.saturation_exposure * n2 / (o.lens_factor * st);
  return e;
}

NightCameraExposure nightCameraForWhite(double white_cd_m2, const NightCameraOptions& o) {
  checkNightCamera(o);
  if (!(white_cd_m2 > 0 && std::isfinite(white_cd_m2)))
    throw std::invalid_argument("night camera: the white luminance must be positive and finite");
  const double n2 = o.f_number * o.f_number;
  const double iso = o.saturation_exposure * n2 / (o.lens_factor * white_cd_m2 * o.max_shutter_s);
  NightCameraExposure e;
  e.camera = {std::clamp(iso, o.min_iso, o.max_iso), o.max_shutter_s, o.f_number};
  e.white_cd_m2 = white_cd_m2;
  e.at_exposure_limit = iso > o.max_iso;
  e.at_bright_limit = iso < o.min_iso;
  return e;
}

double meteredMeanLuminance(const cv::Mat& radiance_xyz, const cv::Mat& emitter_coverage) {
  if (radiance_xyz.type() != CV_32FC3 || emitter_coverage.type() != CV_32F ||
      radiance_xyz.size() != emitter_coverage.size())
    throw std::invalid_argument("meteredMeanLuminance: expects a CV_32FC3 radiance and a CV_32F emitter coverage of "
                                "the same size");
  double sum = 0;
  std::int64_t count = 0;
  for (int r = 0; r < radiance_xyz.rows; ++r) {
    const cv::Vec3f* radiance = radiance_xyz.ptr<cv::Vec3f>(r);
    const float* coverage = emitter_coverage.ptr<float>(r);
    for (int c = 0; c < radiance_xyz.cols; ++c)
      if (coverage[c] == 0.f && std::isfinite(radiance[c][1])) {
        sum += std::max(0.f, radiance[c][1]);
        ++count;
      }
  }
  return count > 0 ? sum / static_cast<double>(count) : 0.0;
}

}  // namespace solo
