#pragma once
// Size and type checks of the maps a render filter reads (its AOVs, its guides).

#include <opencv2/core.hpp>

#include <initializer_list>
#include <stdexcept>
#include <string>

namespace solo {

struct MapCheck {
  const cv::Mat* map;
  int type;  ///< the OpenCV type it must have
  const char* name;
};

/// Throws std::invalid_argument, naming `function` and the map, for a map that is not empty and
/// not of `size` and its type.
inline void requireEmptyOrSized(std::initializer_list<MapCheck> maps, cv::Size size, const char* function) {
  for (const MapCheck& c : maps) {
    const cv::Mat& m = *c.map;
    if (m.empty() || (m.size() == size && m.type() == c.type)) continue;
    throw std::invalid_argument(std::string(function) + ": " + c.name + " is " + std::to_string(m.cols) + "x" +
                                std::to_string(m.rows) + " of type " + std::to_string(m.type()) + ", expected " +
                                std::to_string(size.width) + "x" + std::to_string(size.height) + " of type " +
                                std::to_string(c.type));
  }
}

}  // namespace solo
