#include "solo/geometry/upsample_maps.h"

#include "solo/core/image_io.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <string>

namespace solo {
namespace {

// Bilinear resize of `values` (invalid samples already 0) and of the validity weight;
// the ratio is the valid-weighted average.
void weightedResize(const cv::Mat& values, const cv::Mat& valid, cv::Size size, cv::Mat& sum, cv::Mat& weight) {
  cv::Mat valid_f;
  valid.convertTo(valid_f, CV_32F, 1.0 / 255);
  cv::resize(values, sum, size, 0, 0, cv::INTER_LINEAR);
  cv::resize(valid_f, weight, size, 0, 0, cv::INTER_LINEAR);
}

}  // namespace

cv::Mat resizeValidBilinear(const cv::Mat& map, cv::Size size, double min_valid_weight) {
  CV_Assert(map.type() == CV_32F);
  if (map.size() == size) return map.clone();
  cv::Mat valid = map > 0, clean;
  map.copyTo(clean);
  clean.setTo(0, ~valid);
  cv::Mat sum, weight;
  weightedResize(clean, valid, size, sum, weight);
  cv::Mat out(size, CV_32F, cv::Scalar(0));
  const float threshold = static_cast<float>(std::max(min_valid_weight, 1e-6));
  out.forEach<float>([&](float& v, const int* p) {
    const float w = weight.at<float>(p[0], p[1]);
    if (w >= threshold) v = sum.at<float>(p[0], p[1]) / w;
  });
  return out;
}

cv::Mat resizeNormalsBilinear(const cv::Mat& normals, cv::Size size, double min_valid_weight) {
  CV_Assert(normals.type() == CV_32FC3);
  cv::Mat valid(normals.size(), CV_8U);
  valid.forEach<uchar>([&](uchar& v, const int* p) {
    const cv::Vec3f n = normals.at<cv::Vec3f>(p[0], p[1]);
    v = (std::isfinite(n[0]) && std::isfinite(n[1]) && std::isfinite(n[2]) && n.dot(n) > 0) ? 255 : 0;
  });
  cv::Mat clean = normals.clone();
  clean.setTo(cv::Scalar::all(0), ~valid);
  cv::Mat sum, weight;
  if (normals.size() == size) {
    sum = clean;
    valid.convertTo(weight, CV_32F, 1.0 / 255);
  } else {
    weightedResize(clean, valid, size, sum, weight);
  }
  cv::Mat out(size, CV_32FC3, cv::Scalar::all(0));
  const float threshold = static_cast<float>(std::max(min_valid_weight, 1e-6));
  out.forEach<cv::Vec3f>([&](cv::Vec3f& n, const int* p) {
    if (weight.at<float>(p[0], p[1]) < threshold) return;
    const cv::Vec3f s = sum.at<cv::Vec3f>(p[0], p[1]);
    const float length = std::sqrt(s.dot(s));
    if (length > 1e-6f) n = s / length;  // opposite normals averaging to nothing stay invalid
  });
  return out;
}

cv::Mat jointBilateralUpsample(const cv::Mat& map, const cv::Mat& guide, double sigma_color, double sigma_space_px) {
  CV_Assert((map.type() == CV_32F || map.type() == CV_32FC3) && guide.type() == CV_32FC3);
  CV_Assert(sigma_color > 0 && sigma_space_px > 0);
  cv::Mat guide_low;
  cv::resize(guide, guide_low, map.size(), 0, 0, cv::INTER_AREA);
  const int channels = map.channels();
  const double sx = static_cast<double>(map.cols) / guide.cols, sy = static_cast<double>(map.rows) / guide.rows;
  const int radius = std::max(1, static_cast<int>(std::ceil(2 * sigma_space_px)));
  const double space = -0.5 / (sigma_space_px * sigma_space_px), range = -0.5 / (sigma_color * sigma_color);
  cv::Mat out(guide.size(), map.type(), cv::Scalar::all(0));
  cv::parallel_for_(cv::Range(0, guide.rows), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      const double yl = (y + 0.5) * sy - 0.5;
      const int y0 = static_cast<int>(std::floor(yl));
      for (int x = 0; x < guide.cols; ++x) {
        const double xl = (x + 0.5) * sx - 0.5;
        const int x0 = static_cast<int>(std::floor(xl));
        const cv::Vec3f ip = guide.at<cv::Vec3f>(y, x);
        double sum[3] = {0, 0, 0}, weight = 0;
        for (int qy = std::max(0, y0 - radius + 1); qy <= std::min(map.rows - 1, y0 + radius); ++qy)
          for (int qx = std::max(0, x0 - radius + 1); qx <= std::min(map.cols - 1, x0 + radius); ++qx) {
            const cv::Vec3f diff = ip - guide_low.at<cv::Vec3f>(qy, qx);
            const double w = std::exp(space * ((qx - xl) * (qx - xl) + (qy - yl) * (qy - yl)) + range * diff.dot(diff));
            const float* q = map.ptr<float>(qy) + qx * channels;
            for (int c = 0; c < channels; ++c) sum[c] += w * q[c];
            weight += w;
          }
        float* o = out.ptr<float>(y) + x * channels;
        for (int c = 0; c < channels; ++c) o[c] = weight > 0 ? static_cast<float>(sum[c] / weight) : 0.f;
      }
    }
  });
  return out;
}

UpsampledMaps upsampleMaps(const Scene& scene, const UpsampleOptions& options) {
  Stopwatch clock;
  UpsampledMaps out;
  out.report.name = "upsample";
  const cv::Size size = scene.image.size();
  out.report.add("image_width", std::int64_t{size.width}, "px").add("image_height", std::int64_t{size.height}, "px");
  const auto nearest = [&](const cv::Mat& m) {
    cv::Mat r;
    cv::resize(m, r, size, 0, 0, cv::INTER_NEAREST);
    return r;
  };
  const auto note = [&](const char* name, const cv::Mat& m, const char* method) {
    out.report.notes.push_back(std::string(name) + " " + sizeText(m) + " -> " + sizeText(scene.image) + " (" + method + ")");
  };
  std::int64_t resized_maps = 0;
  const auto process = [&](const char* name, const cv::Mat& in, cv::Mat& result, auto interpolate, const char* method) {
    if (in.empty()) return;
    if (in.size() == size) {
      result = in.clone();
      return;
    }
    ++resized_maps;
    if (options.enabled) {
      result = interpolate(in);
      note(name, in, method);
    } else {
      result = nearest(in);
      note(name, in, "nearest neighbour: upsampling switched off");
    }
  };
  const double w = options.min_valid_weight;
  process("depth", scene.depth_m, out.depth_m, [&](const cv::Mat& m) { return resizeValidBilinear(m, size, w); },
          "valid-weighted bilinear");
  process("normals", scene.normals, out.normals, [&](const cv::Mat& m) { return resizeNormalsBilinear(m, size, w); },
          "valid-weighted bilinear, renormalised");
  const auto material = [&](const cv::Mat& m) {
    return jointBilateralUpsample(m, scene.image, options.material_sigma_color, options.material_sigma_space_px);
  };
  process("albedo", scene.albedo, out.albedo, material, "joint bilateral, guided by the day image");
  process("roughness", scene.roughness, out.roughness, material, "joint bilateral, guided by the day image");
  process("instances", scene.instances, out.instances, nearest, "nearest neighbour");
  process("labels", scene.labels, out.labels, nearest, "nearest neighbour");
  if (!out.roughness.empty()) cv::min(cv::max(out.roughness, 0.0), 1.0, out.roughness);
  if (!out.albedo.empty()) cv::min(cv::max(out.albedo, cv::Scalar::all(0)), cv::Scalar::all(1), out.albedo);
  out.report.add("maps_resized", resized_maps);
  out.report.add("depth_valid_pixels", static_cast<std::int64_t>(cv::countNonZero(out.depth_m > 0)));
  if (resized_maps == 0) out.report.notes.push_back("every map is already at the image resolution");
  out.report.seconds = clock.seconds();
  return out;
}

}  // namespace solo
