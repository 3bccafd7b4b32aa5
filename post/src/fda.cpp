#include <solo/post/fda.h>

#include <solo/core/option_checks.h>

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <stdexcept>
#include <vector>

namespace solo {

namespace {

/// Signed frequency of DFT index i on an axis of length n: i for i <= n/2, else i - n.
int signedFrequency(int i, int n) { return i <= n / 2 ? i : i - n; }

}  // namespace

void validateFdaOptions(const FdaOptions& options) { requireOptionInRange(options.beta, 0, 1, "--beta"); }

FdaResult fourierDomainAdaptation(const cv::Mat& source, const cv::Mat& target, const FdaOptions& options) {
  Stopwatch clock;
  if (source.empty() || source.type() != CV_32FC3 || target.empty() || target.type() != CV_32FC3)
    throw std::invalid_argument("FDA needs two non-empty 3-channel float images");
  validateFdaOptions(options);
  FdaResult result;
  result.report.name = "fda";
  cv::Mat matched = target;
  if (target.size() != source.size()) {
    const bool shrinking = target.total() > source.total();
    cv::resize(target, matched, source.size(), 0, 0, shrinking ? cv::INTER_AREA : cv::INTER_LINEAR);
    result.report.notes.push_back("target resized from " + std::to_string(target.cols) + "x" +
                                  std::to_string(target.rows) + " to the source's " + std::to_string(source.cols) +
                                  "x" + std::to_string(source.rows));
  }
  const int rows = source.rows, cols = source.cols;
  const int band = static_cast<int>(std::floor(std::min(rows, cols) * options.beta));
  std::int64_t swapped = 0;
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < cols; ++x)
      if (std::abs(signedFrequency(y, rows)) < band && std::abs(signedFrequency(x, cols)) < band) ++swapped;

  std::vector<cv::Mat> source_channels, target_channels, out_channels(3);
  cv::split(source, source_channels);
  cv::split(matched, target_channels);
  cv::parallel_for_(cv::Range(0, 3), [&](const cv::Range& range) {
    for (int c = range.start; c < range.end; ++c) {
      if (band == 0) {
        out_channels[c] = source_channels[c].clone();
        continue;
      }
      cv::Mat source_spectrum, target_spectrum, source_double, target_double;
      source_channels[c].convertTo(source_double, CV_64F);
      target_channels[c].convertTo(target_double, CV_64F);
      cv::dft(source_double, source_spectrum, cv::DFT_COMPLEX_OUTPUT);
      cv::dft(target_double, target_spectrum, cv::DFT_COMPLEX_OUTPUT);
      for (int y = 0; y < rows; ++y) {
        if (std::abs(signedFrequency(y, rows)) >= band) continue;
        cv::Vec2d* s = source_spectrum.ptr<cv::Vec2d>(y);
        const cv::Vec2d* t = target_spectrum.ptr<cv::Vec2d>(y);
        for (int x = 0; x < cols; ++x) {
          if (std::abs(signedFrequency(x, cols)) >= band) continue;
          const double amplitude = std::hypot(t[x][0], t[x][1]);
          const double phase = std::atan2(s[x][1], s[x][0]);
          s[x] = {amplitude * std::cos(phase), amplitude * std::sin(phase)};
        }
      }
      cv::Mat back;
      cv::dft(source_spectrum, back, cv::DFT_INVERSE | cv::DFT_SCALE | cv::DFT_REAL_OUTPUT);
      back.convertTo(out_channels[c], CV_32F);
    }
  });
  cv::merge(out_channels, result.image);

  std::int64_t outside = 0;
  for (int y = 0; y < rows; ++y) {
    const float* p = result.image.ptr<float>(y);
    for (int i = 0; i < cols * 3; ++i) outside += (p[i] < 0.f || p[i] > 1.f) ? 1 : 0;
  }
  result.report.add("beta", options.beta)
      .add("band_half_size", static_cast<std::int64_t>(band), "cycles")
      .add("swapped_frequencies", swapped)
      .add("swapped_fraction", static_cast<double>(swapped) / (static_cast<double>(rows) * cols))
      .add("values_outside_unit_range", outside)
      .add("values_outside_unit_range_fraction", static_cast<double>(outside) / (3.0 * rows * cols));
  if (band == 0) result.report.notes.push_back("beta gives an empty band: the output is the source");
  result.report.seconds = clock.seconds();
  return result;
}

}  // namespace solo
