#pragma once
// Street lights in the instance map. Cityscapes counts a street light's head as part of its pole
// (class 17). An estimated instance map often gives a lamp head a few pixels high the class of
// the building behind it or of the sky, or the pole's class over a blob wider than the lamp. The
// instance-reference depth filter then averages the lamp's depth with what lies behind it: on
// the 960x540 synthetic street (exact depth, estimated instances) the lamps' centroids moved
// 1.5-40 m back, behind their own crumpled faces, and their light fell on the walls instead of
// the road. The light map, which outlines each lamp, is the better witness for those pixels:
// each street light becomes an instance of its own, of the pole's class.

#include <opencv2/core.hpp>

#include <cstdint>

namespace solo {

/// Cityscapes' class of poles, street lights included.
inline constexpr int kCityscapesPoleClass = 17;

/// `instances` (CV_32S Cityscapes instanceIds) with every street-light pixel of `lights`
/// (CV_32S categoryId * 1000 + k; categories street_light_HT and street_light_LT) set to a pole
/// instance of that lamp's own (class kCityscapesPoleClass: 17000 + k unless another lamp or a
/// pixel off the street lights already has it, else the next free id, wrapping within
/// 17001-17999): one instance per lamp, also for a high- and a low-CCT lamp with the same k,
/// which the filter averages with nothing else and the mesh stage treats as a foreground thing.
/// Depends on the maps alone, so applying it twice changes nothing more. A copy, the input is
/// untouched. `lights` at another size is sampled at the nearest pixel. Either map empty:
/// `instances` as it is. `changed`, when given, receives how many pixels changed. Throws
/// std::invalid_argument when no free pole id is left.
cv::Mat streetLightsAsPoles(const cv::Mat& instances, const cv::Mat& lights, std::int64_t* changed = nullptr);

}  // namespace solo
