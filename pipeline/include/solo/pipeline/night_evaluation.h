#pragma once
// The evaluation of `solo eval night` as a library (docs/evaluation.md): the realism statistics
// of night images (post/night_statistics.h), and with a reference set of images the median and
// range of each statistic over it and which statistics of an image fall outside that range.

#include <solo/pipeline/evaluation_record.h>
#include <solo/post/night_statistics.h>

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace solo {

struct NightEvaluationOptions {
  std::vector<std::filesystem::path> images;       ///< 8/16-bit sRGB PNG, JPEG or TIFF
  std::optional<std::filesystem::path> reference;  ///< a folder of images, or a list file (one path a line)
};

/// Median (NumPy's rule), minimum and maximum of one statistic over the reference images
/// that have it; none when none has it.
struct NightReferenceRange {
  std::optional<double> median, min, max;
};

struct NightEvaluation {
  std::vector<std::filesystem::path> files;  ///< the images, as given
  std::vector<NightStatistics> statistics;   ///< one per file
  std::optional<std::filesystem::path> reference;
  std::vector<std::filesystem::path> reference_files;  ///< the images the reference names
  std::vector<NightReferenceRange> ranges;  ///< per statistic in namedNightStatistics' order; empty without a reference
  double seconds = 0;                       ///< wall time of reading and measuring every image
};

/// The images a reference names: a folder's image files (.png, .jpg, .jpeg, .tif, .tiff, sorted),
/// or a list file's lines (paths relative to the list's folder; empty lines and # comments
/// skipped). Throws InputError when there is none or the reference does not exist.
std::vector<std::filesystem::path> nightReferenceImages(const std::filesystem::path& reference);

/// The statistics of every image, then those of the reference's images and their ranges.
NightEvaluation evaluateNightImages(const NightEvaluationOptions& options);

/// The keys of the statistics of `s` outside the reference's [min, max].
std::vector<std::string> nightStatisticsOutsideRange(const NightStatistics& s,
                                                     const std::vector<NightReferenceRange>& ranges);

/// The "eval night" record of image `i`: file and size, the reference, the statistics and the
/// keys outside the reference's range (";"-separated; none without a reference).
EvaluationRecord nightEvaluationRecord(const NightEvaluation& evaluation, std::size_t i);

}  // namespace solo
