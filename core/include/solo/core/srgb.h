#pragma once
// The sRGB transfer curve of IEC 61966-2-1:1999, the piecewise curve with a
// linear segment near black:
//   encoded = 12.92 linear                       for linear <= 0.0031308,
//             1.055 linear^(1/2.4) - 0.055       otherwise;
//   linear  = encoded / 12.92                    for encoded <= 0.04045,
//             ((encoded + 0.055) / 1.055)^2.4    otherwise.
// Defined on [0, 1]; nothing is clamped here (callers clamp as they need). The float and the
// double overloads compute in their own precision.

#include <cmath>

namespace solo {

/// sRGB decoding of an encoded value in [0, 1].
inline float srgbToLinear(float encoded) {
  return encoded <= 0.04045f ? encoded / 12.92f : std::pow((encoded + 0.055f) / 1.055f, 2.4f);
}
inline double srgbToLinear(double encoded) {
  return encoded <= 0.04045 ? encoded / 12.92 : std::pow((encoded + 0.055) / 1.055, 2.4);
}

/// sRGB encoding of a linear value in [0, 1].
inline float linearToSrgb(float linear) {
  return linear <= 0.0031308f ? 12.92f * linear : 1.055f * std::pow(linear, 1.f / 2.4f) - 0.055f;
}
inline double linearToSrgb(double linear) {
  return linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1 / 2.4) - 0.055;
}

/// d linearToSrgb / d linear at `linear` > 0 (12.92 on the linear segment).
inline double linearToSrgbSlope(double linear) {
  return linear <= 0.0031308 ? 12.92 : 1.055 / 2.4 * std::pow(linear, 1 / 2.4 - 1);
}

}  // namespace solo
