#include <solo/post/chromatic_adaptation.h>

#include <stdexcept>

namespace solo {

cv::Matx33d bradfordConeMatrix() {
  return {0.8951, 0.2664, -0.1614,  //
          -0.7502, 1.7135, 0.0367,  //
          0.0389, -0.0685, 1.0296};
}

cv::Matx33d bradfordAdaptation(const cv::Vec3d& source_white_xyz, const cv::Vec3d& destination_white_xyz) {
  const cv::Matx33d cone = bradfordConeMatrix();
  const cv::Vec3d source_cone = cone * source_white_xyz;
  const cv::Vec3d destination_cone = cone * destination_white_xyz;
  cv::Matx33d gain = cv::Matx33d::zeros();
  for (int i = 0; i < 3; ++i) {
    if (!(source_cone[i] > 0 && destination_cone[i] > 0))
      throw std::invalid_argument("white point with a non-positive Bradford cone response");
    gain(i, i) = destination_cone[i] / source_cone[i];
  }
  return cone.inv() * gain * cone;
}

StageReport applyChromaticAdaptation(cv::Mat& xyz, const ChromaticAdaptationOptions& options) {
  Stopwatch clock;
  StageReport report;
  report.name = "adaptation";
  CV_Assert(xyz.type() == CV_32FC3);
  if (options.source_white == options.destination_white) {
    report.skipped = true;
    report.skip_reason = "the render's white point already is the output white point";
    return report;
  }
  const cv::Matx33d matrix = bradfordAdaptation(options.source_white, options.destination_white);
  cv::transform(xyz, xyz, cv::Matx33f(matrix));
  report.add("method", std::string("Bradford"));
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) report.add("m" + std::to_string(r) + std::to_string(c), matrix(r, c));
  report.seconds = clock.seconds();
  return report;
}

}  // namespace solo
