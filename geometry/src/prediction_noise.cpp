#include "solo/geometry/prediction_noise.h"

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <random>

namespace solo {
namespace {

// Independent, reproducible streams per map, so changing one perturbation leaves the others.
std::mt19937_64 stream(std::uint64_t seed, std::uint64_t salt) {
  std::seed_seq sequence{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32),
                         static_cast<std::uint32_t>(salt)};
  return std::mt19937_64(sequence);
}

cv::Size reduced(const cv::Mat& m, int factor) {
  return {std::max(1, m.cols / std::max(1, factor)), std::max(1, m.rows / std::max(1, factor))};
}

// Area-downsampling that averages valid pixels only; a low-res pixel is valid when at
// least half of what it covers was.
cv::Mat downsampleValid(const cv::Mat& depth, int factor) {
  cv::Mat valid = depth > 0;
  cv::Mat valid_f;
  valid.convertTo(valid_f, CV_32F, 1.0 / 255);
  cv::Mat sum, weight;
  cv::resize(depth, sum, reduced(depth, factor), 0, 0, cv::INTER_AREA);
  cv::resize(valid_f, weight, reduced(depth, factor), 0, 0, cv::INTER_AREA);
  cv::Mat out(sum.size(), CV_32F);
  for (int y = 0; y < out.rows; ++y)
    for (int x = 0; x < out.cols; ++x) {
      const float w = weight.at<float>(y, x);
      out.at<float>(y, x) = w >= 0.5f ? sum.at<float>(y, x) / w : 0.f;
    }
  return out;
}

}  // namespace

SimulatedPredictions simulatePredictions(const cv::Mat& depth_m, const cv::Mat& normals, const cv::Mat& albedo,
                                         const cv::Mat& labels, const cv::Mat& instances,
                                         const PredictionNoiseOptions& o, std::uint64_t seed) {
  CV_Assert(depth_m.type() == CV_32F && normals.type() == CV_32FC3 && albedo.type() == CV_32FC3);
  CV_Assert(labels.type() == CV_32S && instances.type() == CV_32S);
  SimulatedPredictions p;

  // Depth: low resolution, smoothed across edges, scaled, noisy with distance.
  {
    std::mt19937_64 rng = stream(seed, 1);
    cv::Mat low = downsampleValid(depth_m, o.depth_downscale);
    cv::Mat valid = low > 0;
    cv::Mat edges(low.size(), CV_8U, cv::Scalar(0));
    for (int y = 0; y < low.rows; ++y)
      for (int x = 0; x < low.cols; ++x) {
        const float d = low.at<float>(y, x);
        if (d <= 0) continue;
        for (const auto& [dx, dy] : {std::pair{1, 0}, std::pair{0, 1}}) {
          if (x + dx >= low.cols || y + dy >= low.rows) continue;
          const float e = low.at<float>(y + dy, x + dx);
          if (e > 0 && std::abs(e - d) > o.edge_relative_jump * std::min(d, e)) {
            edges.at<uchar>(y, x) = 255;
            edges.at<uchar>(y + dy, x + dx) = 255;
          }
        }
      }
    if (o.edge_bleed_px > 0) {
      cv::Mat band;
      cv::dilate(edges, band, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * o.edge_bleed_px + 1, 2 * o.edge_bleed_px + 1)));
      cv::Mat weight, sum, valid_f;
      valid.convertTo(valid_f, CV_32F, 1.0 / 255);
      const double sigma = std::max(0.5, o.edge_bleed_px / 1.5);
      cv::GaussianBlur(low, sum, cv::Size(), sigma);  // invalid pixels are 0: they add nothing
      cv::GaussianBlur(valid_f, weight, cv::Size(), sigma);
      for (int y = 0; y < low.rows; ++y)
        for (int x = 0; x < low.cols; ++x)
          if (band.at<uchar>(y, x) && low.at<float>(y, x) > 0 && weight.at<float>(y, x) > 1e-3f)
            low.at<float>(y, x) = sum.at<float>(y, x) / weight.at<float>(y, x);
    }
    p.depth_scale_bias = 1 + std::uniform_real_distribution<double>(-o.depth_bias_max, o.depth_bias_max)(rng);
    std::normal_distribution<double> unit(0, 1);
    for (int y = 0; y < low.rows; ++y)
      for (int x = 0; x < low.cols; ++x) {
        float& d = low.at<float>(y, x);
        const double noise = unit(rng);  // drawn for every pixel: the stream does not depend on validity
        if (d <= 0) continue;
        const double sigma = o.depth_noise_relative * (1 + d / o.depth_noise_growth_m);
        d = static_cast<float>(d * p.depth_scale_bias * std::max(0.2, 1 + sigma * noise));
      }
    p.depth_m = low;
  }

  // Normals: low resolution, blurred, angular noise, renormalised; invalid where depth is.
  {
    std::mt19937_64 rng = stream(seed, 2);
    cv::Mat low, valid_low;
    cv::resize(normals, low, reduced(normals, o.normal_downscale), 0, 0, cv::INTER_AREA);
    cv::Mat valid = depth_m > 0;
    cv::resize(valid, valid_low, low.size(), 0, 0, cv::INTER_NEAREST);
    if (o.normal_blur_px > 0) cv::GaussianBlur(low, low, cv::Size(), o.normal_blur_px);
    std::normal_distribution<double> unit(0, 1);
    const double sigma = std::tan(o.normal_noise_deg * 3.14159265358979323846 / 180);
    for (int y = 0; y < low.rows; ++y)
      for (int x = 0; x < low.cols; ++x) {
        cv::Vec3f& n = low.at<cv::Vec3f>(y, x);
        const cv::Vec3d noise(unit(rng), unit(rng), unit(rng));
        if (!valid_low.at<uchar>(y, x) || cv::norm(n) < 1e-6) {
          n = {0, 0, 0};
          continue;
        }
        cv::Vec3d v = cv::Vec3d(n) / cv::norm(n);
        const cv::Vec3d tangent_noise = noise - v * v.dot(noise);  // perpendicular to n
        v += sigma * tangent_noise;
        v /= cv::norm(v);
        n = cv::Vec3f(v);
      }
    p.normals = low;
  }

  cv::resize(albedo, p.albedo, reduced(albedo, o.albedo_downscale), 0, 0, cv::INTER_AREA);

  // Labels: one smooth random displacement field moves every boundary a little.
  {
    std::mt19937_64 rng = stream(seed, 3);
    const int step = std::max(2, static_cast<int>(o.label_jitter_scale_px));
    const cv::Size coarse(labels.cols / step + 2, labels.rows / step + 2);
    cv::Mat dx(coarse, CV_32F), dy(coarse, CV_32F);
    std::uniform_real_distribution<float> u(-1.f, 1.f);
    for (int y = 0; y < coarse.height; ++y)
      for (int x = 0; x < coarse.width; ++x) {
        dx.at<float>(y, x) = static_cast<float>(o.label_jitter_px) * u(rng);
        dy.at<float>(y, x) = static_cast<float>(o.label_jitter_px) * u(rng);
      }
    cv::Mat fine_dx, fine_dy;
    cv::resize(dx, fine_dx, cv::Size(coarse.width * step, coarse.height * step), 0, 0, cv::INTER_CUBIC);
    cv::resize(dy, fine_dy, cv::Size(coarse.width * step, coarse.height * step), 0, 0, cv::INTER_CUBIC);
    cv::Mat map_x(labels.size(), CV_32F), map_y(labels.size(), CV_32F);
    for (int y = 0; y < labels.rows; ++y)
      for (int x = 0; x < labels.cols; ++x) {
        map_x.at<float>(y, x) = static_cast<float>(x) + fine_dx.at<float>(y, x);
        map_y.at<float>(y, x) = static_cast<float>(y) + fine_dy.at<float>(y, x);
      }
    // remap does not take CV_32S with nearest neighbour in every OpenCV build: go through float,
    // which is exact for ids below 2^24.
    auto displace = [&](const cv::Mat& ids) {
      cv::Mat as_float, moved_float, moved;
      ids.convertTo(as_float, CV_32F);
      cv::remap(as_float, moved_float, map_x, map_y, cv::INTER_NEAREST, cv::BORDER_REPLICATE);
      moved_float.convertTo(moved, CV_32S);
      return moved;
    };
    p.labels = displace(labels);
    p.instances = displace(instances);
  }
  return p;
}

}  // namespace solo
