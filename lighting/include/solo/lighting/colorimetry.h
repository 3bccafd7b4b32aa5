#pragma once
// CIE 1931 colorimetry for light sources: a spectral power distribution integrated against
// the 2-degree colour matching functions gives tristimulus XYZ and chromaticity xy; Planck's
// law gives the Planckian locus by colour temperature; the correlated colour temperature of
// a chromaticity is found on that locus in the CIE 1960 UCS. Wavelengths in nanometres,
// temperatures in kelvin; spectra are relative (only ratios matter for xy).

#include <Eigen/Core>

#include <filesystem>
#include <vector>

namespace solo {

/// A sampled spectral power distribution: increasing wavelengths, non-negative powers.
struct Spectrum {
  std::vector<double> wavelength_nm;
  std::vector<double> power;  ///< relative spectral power per nm
  /// Linear interpolation; 0 outside the sampled range.
  double at(double wavelength_nm) const;
};

/// The CIE 1931 2-degree standard observer on a uniform wavelength grid.
struct ColorMatchingFunctions {
  std::vector<double> wavelength_nm;
  std::vector<double> xbar, ybar, zbar;
  double step_nm() const;
};

/// Reads "wavelength_nm,relative_power" (a header line is optional). Throws InputError
/// naming the file for a missing file, a malformed line, non-increasing wavelengths,
/// negative or non-finite power, fewer than 2 samples or no power at all.
Spectrum readSpectrumCsv(const std::filesystem::path& file);

/// Reads "wavelength_nm,xbar,ybar,zbar" on a uniform grid. Throws InputError likewise.
ColorMatchingFunctions readColorMatchingFunctions(const std::filesystem::path& file);

/// XYZ = sum over the CMF grid of S(lambda) * {xbar, ybar, zbar}(lambda) * step, with S
/// interpolated linearly and 0 outside its range. Relative units.
Eigen::Vector3d tristimulus(const Spectrum& spectrum, const ColorMatchingFunctions& cmf);

/// (x, y) = (X, Y) / (X + Y + Z). Precondition: X + Y + Z > 0.
Eigen::Vector2d chromaticity(const Eigen::Vector3d& xyz);

/// XYZ with luminance Y = `luminance` for chromaticity xy (y > 0).
Eigen::Vector3d xyzFromChromaticity(const Eigen::Vector2d& xy, double luminance);

/// Planck's law, spectral radiance of a black body at `temperature_K` per nm (relative:
/// c1 = 1), second radiation constant c2 = 1.4388e-2 m K (CIE 15:2018).
double planckRadiance(double wavelength_nm, double temperature_K);

/// Chromaticity of a black body at `temperature_K` (Planck's law integrated against the CMFs).
Eigen::Vector2d planckianChromaticity(double temperature_K, const ColorMatchingFunctions& cmf);

/// A narrow-band LED modelled as a Gaussian spectrum of the given peak and full width at
/// half maximum, sampled every nanometre over 360-830 nm.
Spectrum gaussianLedSpectrum(double peak_nm, double fwhm_nm);

/// Correlated colour temperature: the Planckian temperature whose CIE 1960 (u, v) is
/// nearest to xy, searched in 1000-100000 K; duv is the signed distance (positive above
/// the locus, toward green).
struct CorrelatedColourTemperature {
  double cct_K = 0;
  double duv = 0;
};
CorrelatedColourTemperature correlatedColourTemperature(const Eigen::Vector2d& xy, const ColorMatchingFunctions& cmf);

/// The spectral locus 380-700 nm closed by the purple line, as an xy polygon.
std::vector<Eigen::Vector2d> spectralLocus(const ColorMatchingFunctions& cmf);

/// Point-in-polygon by ray crossing (the polygon need not be convex). Points within 2e-5 of an edge
/// count as inside.
bool insidePolygon(const Eigen::Vector2d& point, const std::vector<Eigen::Vector2d>& polygon);

/// The CIE 1931 chromaticity of the equal-energy white E.
inline Eigen::Vector2d whiteE() { return {1.0 / 3.0, 1.0 / 3.0}; }

/// Bradford adaptation from white E to D65 (reference section 2) and its inverse.
Eigen::Matrix3d bradfordEToD65();
/// CIE XYZ (D65-referred) to linear sRGB, IEC 61966-2-1.
Eigen::Matrix3d xyzToLinearSrgb();

}  // namespace solo
