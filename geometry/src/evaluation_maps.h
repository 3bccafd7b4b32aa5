#pragma once
// Private to the geometry library: the input checks that evaluateDepth and evaluateNormals
// share before comparing a predicted map with ground truth pixel by pixel.

#include <solo/core/error.h>
#include <solo/core/image_io.h>

#include <opencv2/core.hpp>

#include <filesystem>
#include <string>

namespace solo {

/// What an evaluated map must be, and how its errors say so.
struct EvaluatedMapKind {
  int channels;
  const char* needs;   ///< the channel requirement's subject and verb: "depth needs", "normals need"
  const char* reader;  ///< the reader that gives such a map: "readDepth"
};

/// `map` in double precision (CV_64F, `kind.channels` channels), or an InputError naming `file`
/// when it is empty, has another channel count or is not a float map; `what` names the map.
inline cv::Mat evaluatedMapAsDouble(const cv::Mat& map, const EvaluatedMapKind& kind, const std::filesystem::path& file,
                                    const char* what) {
  if (map.empty()) throw InputError(file, std::string(what) + " is empty");
  if (map.channels() != kind.channels)
    throw InputError(file, std::string(what) + " has " + std::to_string(map.channels()) + " channels, " + kind.needs +
                               " " + std::to_string(kind.channels));
  if (map.depth() != CV_32F && map.depth() != CV_64F)
    throw InputError(file, std::string(what) + " is not a float map (read it with " + kind.reader + ")");
  cv::Mat out;
  map.convertTo(out, CV_MAKETYPE(CV_64F, kind.channels));
  return out;
}

/// Checks that the prediction and the input's mask have the ground truth's size (InputError
/// naming the files otherwise) and returns the mask as CV_8U, 255 where evaluated; empty when
/// the input has none (every pixel). `Input`: DepthEvaluationInput or NormalEvaluationInput.
template <typename Input>
cv::Mat checkedEvaluationMask(const Input& in, const cv::Mat& prediction, const cv::Mat& ground_truth) {
  if (prediction.size() != ground_truth.size())
    throw InputError(in.prediction_file, "prediction is " + sizeText(prediction) + " but ground truth " +
                                             in.ground_truth_file.string() + " is " + sizeText(ground_truth));
  if (in.mask.empty()) return cv::Mat();
  if (in.mask.size() != ground_truth.size())
    throw InputError(in.mask_file, "mask is " + sizeText(in.mask) + " but ground truth " +
                                       in.ground_truth_file.string() + " is " + sizeText(ground_truth));
  if (in.mask.channels() != 1) throw InputError(in.mask_file, "mask must have one channel");
  return in.mask != 0;
}

}  // namespace solo
