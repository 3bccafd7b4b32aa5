#include "solo/lighting/colorimetry.h"

#include "csv.h"

#include <solo/core/error.h>

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

namespace solo {

namespace {

constexpr double kSecondRadiationConstant_mK = 1.4388e-2;

/// The file's CSV lines without its header: a first line whose first field is not a number.
std::vector<csv::Line> readDataLines(const std::filesystem::path& file) {
  std::vector<csv::Line> lines = csv::readLines(file);
  double value = 0;
  if (!lines.empty() && !lines.front().fields.empty() && !csv::parseNumber(lines.front().fields[0], value))
    lines.erase(lines.begin());
  return lines;
}

/// An InputError naming the file and the line: "line N: <problem>".
InputError lineError(const std::filesystem::path& file, const csv::Line& line, const std::string& problem) {
  return InputError(file, "line " + std::to_string(line.number) + ": " + problem);
}

/// CIE 1960 UCS (u, v) of a chromaticity.
Eigen::Vector2d ucs1960(const Eigen::Vector2d& xy) {
  const double d = -2 * xy.x() + 12 * xy.y() + 3;
  return {4 * xy.x() / d, 6 * xy.y() / d};
}

}  // namespace

double Spectrum::at(double lambda) const {
  if (wavelength_nm.empty() || lambda < wavelength_nm.front() || lambda > wavelength_nm.back()) return 0;
  const auto upper = std::lower_bound(wavelength_nm.begin(), wavelength_nm.end(), lambda);
  const std::size_t i = static_cast<std::size_t>(upper - wavelength_nm.begin());
  if (wavelength_nm[i] == lambda) return power[i];
  const double t = (lambda - wavelength_nm[i - 1]) / (wavelength_nm[i] - wavelength_nm[i - 1]);
  return power[i - 1] + t * (power[i] - power[i - 1]);
}

double ColorMatchingFunctions::step_nm() const {
  return wavelength_nm.size() < 2 ? 1.0 : (wavelength_nm.back() - wavelength_nm.front()) / (wavelength_nm.size() - 1);
}

Spectrum readSpectrumCsv(const std::filesystem::path& file) {
  Spectrum s;
  for (const csv::Line& line : readDataLines(file)) {
    if (line.fields.size() != 2)
      throw lineError(file, line,
                      "expected 2 columns (wavelength_nm, power), got " + std::to_string(line.fields.size()));
    const double lambda = csv::number(file, line, 0, "wavelength");
    const double power = csv::number(file, line, 1, "power");
    if (power < 0) throw lineError(file, line, "negative spectral power");
    if (!s.wavelength_nm.empty() && lambda <= s.wavelength_nm.back())
      throw lineError(file, line, "wavelengths must increase");
    s.wavelength_nm.push_back(lambda);
    s.power.push_back(power);
  }
  if (s.wavelength_nm.size() < 2) throw InputError(file, "a spectrum needs at least 2 samples");
  if (*std::max_element(s.power.begin(), s.power.end()) <= 0) throw InputError(file, "the spectrum has no power");
  return s;
}

ColorMatchingFunctions readColorMatchingFunctions(const std::filesystem::path& file) {
  ColorMatchingFunctions cmf;
  for (const csv::Line& line : readDataLines(file)) {
    if (line.fields.size() != 4) throw lineError(file, line, "expected 4 columns (wavelength_nm, xbar, ybar, zbar)");
    cmf.wavelength_nm.push_back(csv::number(file, line, 0, "wavelength"));
    cmf.xbar.push_back(csv::number(file, line, 1, "xbar"));
    cmf.ybar.push_back(csv::number(file, line, 2, "ybar"));
    cmf.zbar.push_back(csv::number(file, line, 3, "zbar"));
  }
  if (cmf.wavelength_nm.size() < 10) throw InputError(file, "too few samples for colour matching functions");
  const double step = cmf.step_nm();
  for (std::size_t i = 1; i < cmf.wavelength_nm.size(); ++i)
    if (std::abs(cmf.wavelength_nm[i] - cmf.wavelength_nm[i - 1] - step) > 1e-6 * step)
      throw InputError(file, "wavelengths must be on a uniform grid");
  return cmf;
}

Eigen::Vector3d tristimulus(const Spectrum& spectrum, const ColorMatchingFunctions& cmf) {
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < cmf.wavelength_nm.size(); ++i) {
    const double s = spectrum.at(cmf.wavelength_nm[i]);
    xyz += s * Eigen::Vector3d(cmf.xbar[i], cmf.ybar[i], cmf.zbar[i]);
  }
  return xyz * cmf.step_nm();
}

Eigen::Vector2d chromaticity(const Eigen::Vector3d& xyz) {
  const double sum = xyz.sum();
  return {xyz.x() / sum, xyz.y() / sum};
}

Eigen::Vector3d xyzFromChromaticity(const Eigen::Vector2d& xy, double luminance) {
  return {xy.x() / xy.y() * luminance, luminance, (1 - xy.x() - xy.y()) / xy.y() * luminance};
}

double planckRadiance(double wavelength_nm, double temperature_K) {
  const double lambda_m = wavelength_nm * 1e-9;
  return 1.0 / (std::pow(lambda_m, 5) * std::expm1(kSecondRadiationConstant_mK / (lambda_m * temperature_K)));
}

Eigen::Vector2d planckianChromaticity(double temperature_K, const ColorMatchingFunctions& cmf) {
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < cmf.wavelength_nm.size(); ++i)
    xyz += planckRadiance(cmf.wavelength_nm[i], temperature_K) * Eigen::Vector3d(cmf.xbar[i], cmf.ybar[i], cmf.zbar[i]);
  return chromaticity(xyz);
}

Spectrum gaussianLedSpectrum(double peak_nm, double fwhm_nm) {
  Spectrum s;
  const double sigma = fwhm_nm / (2 * std::sqrt(2 * std::log(2.0)));
  for (int lambda = 360; lambda <= 830; ++lambda) {
    s.wavelength_nm.push_back(lambda);
    s.power.push_back(std::exp(-0.5 * std::pow((lambda - peak_nm) / sigma, 2)));
  }
  return s;
}

CorrelatedColourTemperature correlatedColourTemperature(const Eigen::Vector2d& xy, const ColorMatchingFunctions& cmf) {
  const Eigen::Vector2d target = ucs1960(xy);
  // Distance in (u, v) as a function of the reciprocal temperature (mired), which is
  // nearly uniform along the locus: a coarse scan, then a golden-section refinement.
  const auto distance = [&](double mired) { return (ucs1960(planckianChromaticity(1e6 / mired, cmf)) - target).norm(); };
  double best = 10;
  double best_distance = distance(best);
  for (double mired = 10; mired <= 1000; mired += 5) {
    const double d = distance(mired);
    if (d < best_distance) best_distance = d, best = mired;
  }
  double lo = std::max(10.0, best - 5), hi = std::min(1000.0, best + 5);
  const double ratio = (std::sqrt(5.0) - 1) / 2;
  for (int iteration = 0; iteration < 60; ++iteration) {
    const double a = hi - ratio * (hi - lo), b = lo + ratio * (hi - lo);
    if (distance(a) < distance(b))
      hi = b;
    else
      lo = a;
  }
  const double mired = (lo + hi) / 2;
  const Eigen::Vector2d on_locus = ucs1960(planckianChromaticity(1e6 / mired, cmf));
  CorrelatedColourTemperature result;
  result.cct_K = 1e6 / mired;
  result.duv = (target - on_locus).norm() * (target.y() >= on_locus.y() ? 1 : -1);
  return result;
}

std::vector<Eigen::Vector2d> spectralLocus(const ColorMatchingFunctions& cmf) {
  std::vector<Eigen::Vector2d> locus;
  for (std::size_t i = 0; i < cmf.wavelength_nm.size(); ++i) {
    const double lambda = cmf.wavelength_nm[i];
    if (lambda < 380 || lambda > 700) continue;
    locus.push_back(chromaticity({cmf.xbar[i], cmf.ybar[i], cmf.zbar[i]}));
  }
  return locus;
}

bool insidePolygon(const Eigen::Vector2d& p, const std::vector<Eigen::Vector2d>& polygon) {
  // Within 2e-5 of an edge counts as inside: beyond 600 nm the spectral locus is nearly the
  // straight line x + y = 1, and narrow-band red spectra fall a few 1e-6 to either side of
  // its 1 nm chords (50 times below the 1e-3 to which chromaticities are measured).
  constexpr double kEdgeTolerance = 2e-5;
  bool inside = false;
  const std::size_t n = polygon.size();
  for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
    const Eigen::Vector2d& a = polygon[i];
    const Eigen::Vector2d& b = polygon[j];
    const Eigen::Vector2d edge = b - a;
    const double t = edge.squaredNorm() > 0 ? std::clamp((p - a).dot(edge) / edge.squaredNorm(), 0.0, 1.0) : 0.0;
    if ((a + t * edge - p).norm() <= kEdgeTolerance) return true;
    if ((a.y() > p.y()) != (b.y() > p.y()) && p.x() < edge.x() * (p.y() - a.y()) / edge.y() + a.x()) inside = !inside;
  }
  return inside;
}

Eigen::Matrix3d bradfordEToD65() {
  Eigen::Matrix3d m;
  m << 0.9531874, -0.0265906, 0.0238731, -0.0382467, 1.0288406, 0.0094060, 0.0026068, -0.0030332, 1.0892565;
  return m;
}

Eigen::Matrix3d xyzToLinearSrgb() {
  Eigen::Matrix3d m;
  m << 3.2404542, -1.5371385, -0.4985314, -0.9692660, 1.8760108, 0.0415560, 0.0556434, -0.2040259, 1.0572252;
  return m;
}

}  // namespace solo
