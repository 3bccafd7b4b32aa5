// CIE 1931 colorimetry: chromaticities recomputed from spectra against published values.

#include <solo/core/error.h>
#include <solo/lighting/colorimetry.h>

#include "test_support.h"

#include <fstream>

namespace {

const std::filesystem::path kColorimetry = std::filesystem::path(SOLO_PROJECT_DATA_DIR) / "colorimetry";

const solo::ColorMatchingFunctions& cmf() {
  static const solo::ColorMatchingFunctions functions =
      solo::readColorMatchingFunctions(kColorimetry / "cie1931_2deg_cmf_1nm.csv");
  return functions;
}

Eigen::Vector2d xyOf(const std::string& spectrum_file) {
  return solo::chromaticity(solo::tristimulus(solo::readSpectrumCsv(kColorimetry / spectrum_file), cmf()));
}

}  // namespace

TEST(Colorimetry, IlluminantAFromItsSpectrum) {
  const Eigen::Vector2d xy = xyOf("cie_illuminant_A.csv");
  EXPECT_NEAR(xy.x(), 0.4476, 1e-3);
  EXPECT_NEAR(xy.y(), 0.4074, 1e-3);
}

TEST(Colorimetry, IlluminantD65FromItsSpectrum) {
  const Eigen::Vector2d xy = xyOf("cie_illuminant_D65.csv");
  EXPECT_NEAR(xy.x(), 0.3127, 1e-3);
  EXPECT_NEAR(xy.y(), 0.3290, 1e-3);
}

TEST(Colorimetry, PlanckianAt2856KMatchesIlluminantA) {
  // CIE A is a black body at 2856 K (defined with c2 = 1.435e-2; we use 1.4388e-2).
  const Eigen::Vector2d xy = solo::planckianChromaticity(2856, cmf());
  EXPECT_NEAR(xy.x(), 0.4476, 2e-3);
  EXPECT_NEAR(xy.y(), 0.4074, 2e-3);
}

TEST(Colorimetry, PlanckianLocusAtKnownTemperatures) {
  // CIE 15 Planckian chromaticities (c2 = 1.4388e-2 m K).
  EXPECT_NEAR(solo::planckianChromaticity(6500, cmf()).x(), 0.3135, 1e-3);
  EXPECT_NEAR(solo::planckianChromaticity(6500, cmf()).y(), 0.3237, 1e-3);
  EXPECT_NEAR(solo::planckianChromaticity(2000, cmf()).x(), 0.5267, 1e-3);
  EXPECT_NEAR(solo::planckianChromaticity(2000, cmf()).y(), 0.4133, 1e-3);
}

TEST(Colorimetry, CorrelatedColourTemperature) {
  const auto a = solo::correlatedColourTemperature(xyOf("cie_illuminant_A.csv"), cmf());
  // CIE 15 defines A by Planck's law at 2848 K with c2 = 1.435e-2 m K: the same spectrum is
  // 2848 * 1.4388 / 1.435 = 2855.5 K with today's c2 = 1.4388e-2.
  EXPECT_NEAR(a.cct_K, 2848 * 1.4388 / 1.435, 1);
  EXPECT_NEAR(a.duv, 0, 2e-4);
  const auto d65 = solo::correlatedColourTemperature(xyOf("cie_illuminant_D65.csv"), cmf());
  EXPECT_NEAR(d65.cct_K, 6504, 10);
  EXPECT_NEAR(d65.duv, 0.0032, 3e-4);  // D65 lies above the Planckian locus
  // On the locus itself the CCT is the temperature.
  EXPECT_NEAR(solo::correlatedColourTemperature(solo::planckianChromaticity(4000, cmf()), cmf()).cct_K, 4000, 1);
}

TEST(Colorimetry, ReferenceAnchorSampleLiesNearItsStatedTemperature) {
  // The reference's only published sample: xy (0.3812, 0.4329) at 4313 K. Its CCT on our
  // locus is within 2 % of the stated value; it lies well above the locus (a green cast).
  const auto anchor = solo::correlatedColourTemperature({0.3812, 0.4329}, cmf());
  EXPECT_NEAR(anchor.cct_K, 4313, 0.02 * 4313);
  EXPECT_GT(anchor.duv, 0.02);
}

TEST(Colorimetry, NarrowLedLiesNearTheSpectralLocus) {
  const Eigen::Vector2d xy = solo::chromaticity(solo::tristimulus(solo::gaussianLedSpectrum(590, 1), cmf()));
  EXPECT_NEAR(xy.x(), 0.5752, 2e-3);  // the spectral locus at 590 nm
  EXPECT_NEAR(xy.y(), 0.4242, 2e-3);
  EXPECT_TRUE(solo::insidePolygon(solo::chromaticity(solo::tristimulus(solo::gaussianLedSpectrum(590, 20), cmf())),
                                  solo::spectralLocus(cmf())));
  EXPECT_FALSE(solo::insidePolygon({0.1, 0.1}, solo::spectralLocus(cmf())));
}

TEST(Colorimetry, SharedCheckValuesAreReproducedFromTheSpectra) {
  SOLO_REQUIRE_SHARED_DATA(check, "illuminants/lamp_xy_cct_from_spd.csv");
  const std::filesystem::path spectra = check.parent_path().parent_path() / "colorimetry";
  std::ifstream in(check);
  std::string line;
  std::getline(in, line);
  int compared = 0;
  while (std::getline(in, line)) {
    const std::string file = line.substr(0, line.find(','));
    if (!std::filesystem::exists(spectra / file)) continue;  // the check file lists two spectra that are not shipped
    const auto last = line.rfind(',');
    const auto before = line.rfind(',', last - 1);
    const auto x_end = before;
    const auto x_begin = line.rfind(',', x_end - 1) + 1;
    const double x = std::stod(line.substr(x_begin, x_end - x_begin));
    const double y = std::stod(line.substr(before + 1, last - before - 1));
    const Eigen::Vector2d xy = solo::chromaticity(solo::tristimulus(solo::readSpectrumCsv(spectra / file), cmf()));
    EXPECT_NEAR(xy.x(), x, 1e-3) << file;
    EXPECT_NEAR(xy.y(), y, 1e-3) << file;
    ++compared;
  }
  EXPECT_GE(compared, 20);
}

TEST(Colorimetry, MalformedSpectraAreRefusedNamingTheFileAndLine) {
  solo::test::TempDir dir;
  solo::test::writeText(dir / "down.csv", "wavelength_nm,relative_power\n400,1\n390,2\n");
  try {
    solo::readSpectrumCsv(dir / "down.csv");
    FAIL() << "no error";
  } catch (const solo::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("down.csv: line 3: wavelengths must increase"), std::string::npos) << e.what();
  }
  solo::test::writeText(dir / "neg.csv", "400,1\n410,-2\n");
  EXPECT_THROW(solo::readSpectrumCsv(dir / "neg.csv"), solo::InputError);
  solo::test::writeText(dir / "text.csv", "400,1\n410,lots\n");
  EXPECT_THROW(solo::readSpectrumCsv(dir / "text.csv"), solo::InputError);
  EXPECT_THROW(solo::readSpectrumCsv(dir / "absent.csv"), solo::InputError);
}
