// The night statistics of images, the ranges of a reference set and what falls outside them.

#include <solo/pipeline/night_evaluation.h>

#include <solo/core/error.h>
#include <solo/core/image_io.h>
#include <solo/core/quantile.h>
#include <solo/core/report.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <fstream>

namespace fs = std::filesystem;

namespace solo {
namespace {

NightStatistics nightStatisticsOf(const fs::path& image) {
  return computeNightStatistics(readColorImage(image), ChannelOrder::Rgb);
}

std::vector<NightReferenceRange> referenceRanges(const std::vector<NightStatistics>& reference) {
  std::vector<NightReferenceRange> ranges(namedNightStatistics(NightStatistics{}).size());
  for (std::size_t k = 0; k < ranges.size(); ++k) {
    std::vector<double> values;
    for (const NightStatistics& s : reference)
      if (const std::optional<double> v = namedNightStatistics(s)[k].value) values.push_back(*v);
    if (values.empty()) continue;
    ranges[k].min = *std::min_element(values.begin(), values.end());
    ranges[k].max = *std::max_element(values.begin(), values.end());
    ranges[k].median = sampleQuantile(values, 0.5);
  }
  return ranges;
}

/// A folder's image files, sorted.
std::vector<fs::path> folderImages(const fs::path& folder) {
  std::vector<fs::path> images;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder)) {
    std::string ext = entry.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (entry.is_regular_file() &&
        (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".tif" || ext == ".tiff"))
      images.push_back(entry.path());
  }
  std::sort(images.begin(), images.end());
  if (images.empty()) throw InputError(folder, "no image (.png, .jpg, .jpeg, .tif, .tiff) in the folder");
  return images;
}

/// A list file's paths, relative ones taken from the list's folder.
std::vector<fs::path> listedImages(const fs::path& list) {
  std::ifstream in(list);
  if (!in) throw InputError(list, "reference not found (a folder of images or a list file)");
  std::vector<fs::path> images;
  std::string line;
  while (std::getline(in, line)) {
    const std::size_t begin = line.find_first_not_of(" \t\r");
    if (begin == std::string::npos || line[begin] == '#') continue;
    const std::size_t end = line.find_last_not_of(" \t\r");
    const fs::path path = line.substr(begin, end - begin + 1);
    images.push_back(path.is_absolute() ? path : list.parent_path() / path);
  }
  if (images.empty()) throw InputError(list, "the list names no image");
  return images;
}

std::string joined(const std::vector<std::string>& words, const std::string& separator) {
  std::string out;
  for (const std::string& w : words) out += (out.empty() ? "" : separator) + w;
  return out;
}

}  // namespace

std::vector<fs::path> nightReferenceImages(const fs::path& reference) {
  std::error_code ec;
  return fs::is_directory(reference, ec) ? folderImages(reference) : listedImages(reference);
}

NightEvaluation evaluateNightImages(const NightEvaluationOptions& options) {
  Stopwatch clock;
  NightEvaluation evaluation;
  evaluation.files = options.images;
  for (const fs::path& file : evaluation.files) evaluation.statistics.push_back(nightStatisticsOf(file));
  if (options.reference) {
    evaluation.reference = options.reference;
    evaluation.reference_files = nightReferenceImages(*options.reference);
    std::vector<NightStatistics> reference;
    for (const fs::path& file : evaluation.reference_files) reference.push_back(nightStatisticsOf(file));
    evaluation.ranges = referenceRanges(reference);
  }
  evaluation.seconds = clock.seconds();
  return evaluation;
}

std::vector<std::string> nightStatisticsOutsideRange(const NightStatistics& s,
                                                     const std::vector<NightReferenceRange>& ranges) {
  std::vector<std::string> outside;
  const std::vector<NamedNightStatistic> named = namedNightStatistics(s);
  for (std::size_t k = 0; k < named.size(); ++k)
    if (named[k].value && ranges[k].min && (*named[k].value < *ranges[k].min || *named[k].value > *ranges[k].max))
      outside.push_back(named[k].key);
  return outside;
}

EvaluationRecord nightEvaluationRecord(const NightEvaluation& evaluation, std::size_t i) {
  const NightStatistics& s = evaluation.statistics[i];
  EvaluationRecord r;
  r.command = "eval night";
  r.inputs = {{"file", "image", evaluation.files[i].string(), ""},
              {"width_px", "width", std::int64_t{s.source_width_px}, "px"},
              {"height_px", "height", std::int64_t{s.source_height_px}, "px"}};
  r.options = {{"reference", "reference", optionalPathValue(evaluation.reference), ""}};
  for (const NamedNightStatistic& n : namedNightStatistics(s))
    r.metrics.push_back({n.key, n.key, optionalNumberValue(n.value), n.unit});
  r.metrics.push_back({"outside_reference", "outside reference",
                       evaluation.ranges.empty()
                           ? EvaluationValue(std::monostate{})
                           : EvaluationValue(joined(nightStatisticsOutsideRange(s, evaluation.ranges), ";")),
                       ""});
  return r;
}

}  // namespace solo
