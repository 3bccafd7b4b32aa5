#pragma once
// Per-pixel sample streams for the path tracer, pbrt-v4 style: for (pixel, sample index,
// dimension) a Sampler hands out values in [0, 1), one at a time (get1D) or in pairs (get2D).
//
// SamplerKind::Sobol (the default): every dimension (a 1D value or a 2D pair) takes the point
// of its sample index from the base-2 Sobol (0,2)-sequence (van der Corput and the second Sobol
// dimension; for 1D the van der Corput sequence alone), with Owen scrambling by hashing (Burley
// 2020, "Practical Hash-based Owen Scrambling"): the index is shuffled and each coordinate
// scrambled with seeds hashed from (seed, pixel, dimension). So the first 2^k samples of a pixel
// in one dimension form a (0,k,2)-net (one point in every elementary interval), any prefix is
// well spread (adaptive sampling may stop at any count), and pixels and dimensions are
// decorrelated. Dimensions past kLowDiscrepancyDimensions come from the pixel's PCG32 stream:
// deep path vertices gain nothing from stratification.
// SamplerKind::Independent: every value from the pixel's PCG32 stream.
// Both are deterministic for (seed, pixel), whatever thread renders the pixel.
//
// Replicates (Sobol only): a pixel's samples can alternate between R independently scrambled
// copies of the point set, sample i taking point i / R of copy i % R. The R partial means are
// then independent and unbiased, so their spread estimates the error of the pixel's mean
// without assuming independent samples (path_tracer.cpp's stopping rule).

#include <cstdint>
#include <string_view>
#include <utility>

namespace solo {

enum class SamplerKind { Sobol, Independent };

/// "sobol" or "independent"; throws std::invalid_argument naming the value otherwise.
SamplerKind parseSamplerKind(std::string_view name);
const char* samplerKindName(SamplerKind kind);

/// PCG32 (O'Neill 2014): small, fast and seedable per pixel.
class Pcg32 {
 public:
  Pcg32(std::uint64_t seed, std::uint64_t stream);
  std::uint32_t next() {
    const std::uint64_t old = state_;
    state_ = old * 6364136223846793005ULL + increment_;
    const auto xorshifted = static_cast<std::uint32_t>(((old >> 18u) ^ old) >> 27u);
    const auto rotation = static_cast<std::uint32_t>(old >> 59u);
    return (xorshifted >> rotation) | (xorshifted << ((32u - rotation) & 31u));
  }
  /// Uniform in [0, 1), 24 bits.
  float uniform() { return static_cast<float>(next() >> 8) * (1.f / 16777216.f); }

 private:
  std::uint64_t state_ = 0;
  std::uint64_t increment_;
};

/// Number of dimensions (1D values and 2D pairs, counted alike) per sample drawn from the
/// scrambled Sobol points; later ones come from PCG32. Dimension 0 is the pixel position, then
/// 4 to 7 per path vertex, so this covers about the first two bounces; on the night street 32
/// gave the same error (docs/rendering.md, Sampler).
inline constexpr int kLowDiscrepancyDimensions = 16;

/// Most independently scrambled copies of the point set a pixel's samples may alternate between.
inline constexpr int kMaxReplicates = 8;

class Sampler {
 public:
  /// A pixel's stream; pixel is any per-pixel id (row-major index). replicates in
  /// [1, kMaxReplicates] (see above; ignored by the independent sampler); std::invalid_argument
  /// otherwise.
  Sampler(SamplerKind kind, std::uint64_t seed, std::uint64_t pixel, int replicates = 1);
  /// Starts sample `index` of the pixel at dimension 0. Indices are used in order 0, 1, 2, ...
  /// With replicates, it is point index / replicates of replicate index % replicates.
  void startSample(std::uint32_t index);
  float get1D();
  std::pair<float, float> get2D();
  SamplerKind kind() const { return kind_; }

 private:
  SamplerKind kind_;
  std::uint32_t replicates_ = 1;
  std::uint32_t index_reversed_ = 0;  // the point index within its replicate, bit-reversed
  std::uint32_t seed_offset_ = 0;  // where the current replicate's scrambling seeds start
  int dimension_ = 0;
  // The scrambling seeds (per replicate and dimension, three each) are hashed from this when
  // used rather than stored: a table of them made each pixel's state 1.5 KiB, and a tile's
  // states outgrew the caches the traversal needs.
  std::uint32_t pixel_hash_ = 0;
  Pcg32 rng_;

  std::uint32_t scrambleSeed(std::uint32_t i) const;
};

}  // namespace solo
