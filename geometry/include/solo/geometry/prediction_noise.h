#pragma once
// Turns exact maps into maps that behave like a network's predictions, for synthetic
// scenes whose true answer is known. Every perturbation is seeded and its size is an option.

#include <opencv2/core.hpp>

#include <cstdint>

namespace solo {

struct PredictionNoiseOptions {
  int depth_downscale = 2;            ///< depth is predicted at 1/N of the image resolution
  int edge_bleed_px = 2;              ///< band (low-res pixels) around depth edges that is smoothed across
  double edge_relative_jump = 0.05;   ///< a relative depth jump above this is an edge
  double depth_bias_max = 0.06;       ///< global scale bias drawn from 1 +- this
  double depth_noise_relative = 0.01; ///< relative noise sigma at 0 m ...
  double depth_noise_growth_m = 50;   ///< ... growing as (1 + z / this)
  int normal_downscale = 2;
  double normal_blur_px = 1.5;        ///< Gaussian sigma at the low resolution
  double normal_noise_deg = 3.0;      ///< angular noise, per-pixel sigma
  int albedo_downscale = 4;
  double label_jitter_px = 2.0;       ///< amplitude of a smooth boundary displacement field
  double label_jitter_scale_px = 24;  ///< its spatial scale
};

struct SimulatedPredictions {
  cv::Mat depth_m;    ///< CV_32F low resolution, 0 = invalid
  cv::Mat normals;    ///< CV_32FC3 low resolution
  cv::Mat albedo;     ///< CV_32FC3 low resolution
  cv::Mat labels;     ///< CV_32S full resolution, boundaries displaced
  cv::Mat instances;  ///< CV_32S, same displacement as labels
  double depth_scale_bias = 1;  ///< the factor drawn for this seed
};

/// Inputs at full resolution: depth (CV_32F, 0 = invalid), normals (CV_32FC3), albedo
/// (CV_32FC3), labels and instances (CV_32S). Deterministic for a given seed.
SimulatedPredictions simulatePredictions(const cv::Mat& depth_m, const cv::Mat& normals, const cv::Mat& albedo,
                                         const cv::Mat& labels, const cv::Mat& instances,
                                         const PredictionNoiseOptions& options, std::uint64_t seed);

}  // namespace solo
