// The scrambled Sobol sampler (sampler.h): every power-of-two prefix of a pixel's points in one
// dimension is a (0,k,2)-net, any prefix is spread over the unit interval, values stay in
// [0, 1), and pixels and dimensions are decorrelated; the independent sampler is PCG32.

#include <solo/render/sampler.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>
#include <vector>

namespace {

// The points of `count` samples of one pixel at dimension `dimension` (earlier dimensions
// drawn as 2D pairs and ignored), as the path tracer draws them.
std::vector<std::pair<float, float>> points2D(std::uint64_t seed, std::uint64_t pixel, int dimension, int count) {
  solo::Sampler sampler(solo::SamplerKind::Sobol, seed, pixel);
  std::vector<std::pair<float, float>> out;
  for (int i = 0; i < count; ++i) {
    sampler.startSample(static_cast<std::uint32_t>(i));
    for (int d = 0; d < dimension; ++d) sampler.get2D();
    out.push_back(sampler.get2D());
  }
  return out;
}

std::vector<float> values1D(std::uint64_t seed, std::uint64_t pixel, int dimension, int count) {
  solo::Sampler sampler(solo::SamplerKind::Sobol, seed, pixel);
  std::vector<float> out;
  for (int i = 0; i < count; ++i) {
    sampler.startSample(static_cast<std::uint32_t>(i));
    for (int d = 0; d < dimension; ++d) sampler.get1D();
    out.push_back(sampler.get1D());
  }
  return out;
}

double correlation(const std::vector<float>& a, const std::vector<float>& b) {
  double ma = 0, mb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) ma += a[i] / a.size(), mb += b[i] / b.size();
  double ab = 0, aa = 0, bb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ab += (a[i] - ma) * (b[i] - mb);
    aa += (a[i] - ma) * (a[i] - ma);
    bb += (b[i] - mb) * (b[i] - mb);
  }
  return ab / std::sqrt(aa * bb);
}

}  // namespace

TEST(Sampler, PowerOfTwoPrefixesAreZeroTwoNets) {
  // One point in each of the 2^k cells of every 2^a x 2^b grid with a + b = k.
  for (const std::uint64_t pixel : {0ULL, 1ULL, 12345ULL, 129599ULL})
    for (const int dimension : {0, 1, 5, solo::kLowDiscrepancyDimensions - 1}) {
      const auto points = points2D(7, pixel, dimension, 1 << 10);
      for (int k = 0; k <= 10; ++k)
        for (int a = 0; a <= k; ++a) {
          const int nx = 1 << a, ny = 1 << (k - a);
          std::vector<int> count(static_cast<std::size_t>(nx * ny), 0);
          for (int i = 0; i < (1 << k); ++i) {
            const int cx = static_cast<int>(points[static_cast<std::size_t>(i)].first * nx);
            const int cy = static_cast<int>(points[static_cast<std::size_t>(i)].second * ny);
            ++count[static_cast<std::size_t>(cy * nx + cx)];
          }
          for (int c : count) ASSERT_EQ(c, 1) << "pixel " << pixel << " dimension " << dimension << " k " << k << " a " << a;
        }
    }
}

TEST(Sampler, OneDimensionalPrefixesAreStratified) {
  for (const int dimension : {0, 3, solo::kLowDiscrepancyDimensions - 1}) {
    const auto values = values1D(3, 999, dimension, 1 << 12);
    for (int k = 0; k <= 12; ++k) {
      std::vector<int> count(static_cast<std::size_t>(1 << k), 0);
      for (int i = 0; i < (1 << k); ++i) ++count[static_cast<std::size_t>(values[static_cast<std::size_t>(i)] * (1 << k))];
      for (int c : count) ASSERT_EQ(c, 1) << "dimension " << dimension << " k " << k;
    }
    // Adaptive sampling stops at any count: a prefix of n samples holds the first 2^floor(log2 n)
    // (a full stratification) plus part of the next block, so every interval of width
    // 2^-floor(log2 n) holds one or two values.
    for (int n : {3, 24, 40, 100, 777}) {
      const int k = static_cast<int>(std::floor(std::log2(n)));
      std::vector<int> count(static_cast<std::size_t>(1 << k), 0);
      for (int i = 0; i < n; ++i) ++count[static_cast<std::size_t>(values[static_cast<std::size_t>(i)] * (1 << k))];
      for (int c : count) {
        EXPECT_GE(c, 1) << n;
        EXPECT_LE(c, 2) << n;
      }
    }
  }
}

TEST(Sampler, ValuesLieInTheHalfOpenUnitInterval) {
  float lo = 1, hi = 0;
  for (std::uint64_t pixel = 0; pixel < 64; ++pixel) {
    for (const auto& [x, y] : points2D(11, pixel, 2, 256)) lo = std::min({lo, x, y}), hi = std::max({hi, x, y});
    for (float v : values1D(11, pixel, 1, 256)) lo = std::min(lo, v), hi = std::max(hi, v);
  }
  EXPECT_GE(lo, 0.f);
  EXPECT_LT(hi, 1.f);
  EXPECT_LT(lo, 1e-3f);  // and they fill it
  EXPECT_GT(hi, 1 - 1e-3f);
}

TEST(Sampler, PixelsAndDimensionsAreDecorrelated) {
  const int n = 256;
  // Two dimensions of one pixel: their x coordinates are uncorrelated, and as a 2D point set
  // they fill a 16 x 16 grid about as densely as random points would (256 (1 - 1/e) = 162
  // cells), not along a curve as unscrambled or unshuffled copies of one sequence would
  // (16 cells on the diagonal).
  const auto a = points2D(5, 42, 0, n), b = points2D(5, 42, 1, n);
  std::vector<float> ax, bx;
  std::set<int> cells;
  for (int i = 0; i < n; ++i) {
    ax.push_back(a[static_cast<std::size_t>(i)].first);
    bx.push_back(b[static_cast<std::size_t>(i)].first);
    cells.insert(static_cast<int>(ax.back() * 16) * 16 + static_cast<int>(bx.back() * 16));
  }
  EXPECT_GT(cells.size(), 120u);
  EXPECT_LT(cells.size(), 200u);  // random points leave some cells empty
  // The correlation of the first coordinates of two dimensions (or of neighbouring pixels in
  // one dimension), sample by sample: over 200 pixels its root mean square is near that of
  // independent uniforms, 1 / sqrt(n) = 0.0625 (measured 0.078: hashed scrambling draws from a
  // smaller family than all permutations), and never close to 1.
  double dimension_square = 0, pixel_square = 0, worst = 0;
  for (std::uint64_t pixel = 0; pixel < 200; ++pixel) {
    const auto p = points2D(5, pixel, 2, n), q = points2D(5, pixel, 3, n), r = points2D(5, pixel + 1, 2, n);
    std::vector<float> px, qx, rx;
    for (int i = 0; i < n; ++i) {
      px.push_back(p[static_cast<std::size_t>(i)].first);
      qx.push_back(q[static_cast<std::size_t>(i)].first);
      rx.push_back(r[static_cast<std::size_t>(i)].first);
    }
    const double pq = correlation(px, qx), pr = correlation(px, rx);
    dimension_square += pq * pq / 200;
    pixel_square += pr * pr / 200;
    worst = std::max({worst, std::abs(pq), std::abs(pr)});
  }
  EXPECT_LT(std::sqrt(dimension_square), 1.5 / std::sqrt(n));
  EXPECT_LT(std::sqrt(pixel_square), 1.5 / std::sqrt(n));
  EXPECT_LT(worst, 0.4);
  // Sample 0 of 4096 pixels in dimension 0: spread like independent uniforms (mean 1/2,
  // variance 1/12), no two pixels alike.
  std::set<std::pair<float, float>> first;
  double mean = 0, square = 0;
  for (std::uint64_t pixel = 0; pixel < 4096; ++pixel) {
    const auto p = points2D(5, pixel, 0, 1)[0];
    first.insert(p);
    mean += p.first / 4096.0;
    square += p.first * p.first / 4096.0;
  }
  EXPECT_EQ(first.size(), 4096u);
  EXPECT_NEAR(mean, 0.5, 4 * std::sqrt(1 / 12.0 / 4096));
  EXPECT_NEAR(square - mean * mean, 1 / 12.0, 0.01);
  // A different seed gives different points for the same pixel.
  EXPECT_NE(points2D(6, 42, 0, 1)[0], a[0]);
}

TEST(Sampler, IndependentSamplerIsThePixelsPcgStream) {
  solo::Sampler sampler(solo::SamplerKind::Independent, 9, 77);
  solo::Pcg32 rng(9, 77);
  for (int i = 0; i < 4; ++i) {
    sampler.startSample(static_cast<std::uint32_t>(i));
    EXPECT_EQ(sampler.get1D(), rng.uniform());
    const auto [u, v] = sampler.get2D();
    EXPECT_EQ(u, rng.uniform());
    EXPECT_EQ(v, rng.uniform());
  }
}

TEST(Sampler, DeepDimensionsFallBackToPcg) {
  // Past kLowDiscrepancyDimensions the values are the pixel's PCG32 stream, in order.
  solo::Sampler sampler(solo::SamplerKind::Sobol, 9, 77);
  solo::Pcg32 rng(9, 77);
  for (int i = 0; i < 3; ++i) {
    sampler.startSample(static_cast<std::uint32_t>(i));
    for (int d = 0; d < solo::kLowDiscrepancyDimensions; ++d) sampler.get2D();
    EXPECT_EQ(sampler.get1D(), rng.uniform());
  }
}

TEST(Sampler, NamesParseAndUnknownNamesAreRefused) {
  EXPECT_EQ(solo::parseSamplerKind("sobol"), solo::SamplerKind::Sobol);
  EXPECT_EQ(solo::parseSamplerKind("independent"), solo::SamplerKind::Independent);
  EXPECT_STREQ(solo::samplerKindName(solo::SamplerKind::Sobol), "sobol");
  EXPECT_THROW(solo::parseSamplerKind("halton"), std::invalid_argument);
}

TEST(Sampler, ReplicatesAreIndependentlyScrambledCopiesOfTheNets) {
  // With R replicates, sample i is point i / R of copy i % R: copy 0 is the single-copy
  // sequence itself, every copy's power-of-two prefixes are (0,k,2)-nets, and the copies are
  // differently scrambled (they share no point).
  constexpr int kReplicates = 4, kPoints = 256;
  solo::Sampler single(solo::SamplerKind::Sobol, 5, 77);
  solo::Sampler replicated(solo::SamplerKind::Sobol, 5, 77, kReplicates);
  std::vector<std::vector<std::pair<float, float>>> copies(kReplicates);
  for (int i = 0; i < kReplicates * kPoints; ++i) {
    replicated.startSample(static_cast<std::uint32_t>(i));
    replicated.get2D();  // dimension 0, then a later one
    copies[static_cast<std::size_t>(i % kReplicates)].push_back(replicated.get2D());
  }
  for (int i = 0; i < kPoints; ++i) {
    single.startSample(static_cast<std::uint32_t>(i));
    single.get2D();
    ASSERT_EQ(single.get2D(), copies[0][static_cast<std::size_t>(i)]) << i;
  }
  for (const auto& points : copies)
    for (int k = 0; k <= 8; ++k)
      for (int a = 0; a <= k; ++a) {
        const int nx = 1 << a, ny = 1 << (k - a);
        std::vector<int> count(static_cast<std::size_t>(nx * ny), 0);
        for (int i = 0; i < (1 << k); ++i)
          ++count[static_cast<std::size_t>(static_cast<int>(points[static_cast<std::size_t>(i)].second * ny) * nx +
                                           static_cast<int>(points[static_cast<std::size_t>(i)].first * nx))];
        for (int c : count) ASSERT_EQ(c, 1) << "k " << k << " a " << a;
      }
  std::set<std::pair<float, float>> seen;
  for (const auto& points : copies) seen.insert(points.begin(), points.end());
  EXPECT_EQ(seen.size(), static_cast<std::size_t>(kReplicates * kPoints));
  EXPECT_THROW(solo::Sampler(solo::SamplerKind::Sobol, 1, 1, 0), std::invalid_argument);
  EXPECT_THROW(solo::Sampler(solo::SamplerKind::Sobol, 1, 1, solo::kMaxReplicates + 1), std::invalid_argument);
}
