// Scrambled Sobol and independent sample streams (see sampler.h).

#include "solo/render/sampler.h"

#include <array>
#include <stdexcept>
#include <string>

namespace solo {
namespace {

// An avalanching 32-bit integer hash (xor-shift-multiply finaliser), for scrambling seeds.
constexpr std::uint32_t hash32(std::uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352dU;
  x ^= x >> 15;
  x *= 0x846ca68bU;
  x ^= x >> 16;
  return x;
}

std::uint32_t reverseBits(std::uint32_t x) {
  x = ((x >> 1) & 0x55555555U) | ((x & 0x55555555U) << 1);
  x = ((x >> 2) & 0x33333333U) | ((x & 0x33333333U) << 2);
  x = ((x >> 4) & 0x0f0f0f0fU) | ((x & 0x0f0f0f0fU) << 4);
  return __builtin_bswap32(x);
}

// A seeded permutation of 32-bit words in which bit j of the output depends only on bits
// 0..j of the input: adding carries upwards, multiplying by an odd number or xoring in the
// word times an even number mixes lower bits into higher ones. Burley's 2020 form (add the
// seed, then four xor-multiplies) leaves the lowest bits, which become the leading digits after
// bit reversal, nearly seed-independent; multiplying by a seed-derived odd number, as in
// Vegdahl's 2021 revision, fixes that.
std::uint32_t laineKarras(std::uint32_t x, std::uint32_t seed) {
  x ^= x * 0x3d20adeaU;
  x += seed;
  x *= (seed >> 16) | 1U;
  x ^= x * 0x05526c56U;
  x ^= x * 0x53a22864U;
  return x;
}

std::uint64_t reverseBits64(std::uint64_t x) {
  x = ((x >> 1) & 0x5555555555555555ULL) | ((x & 0x5555555555555555ULL) << 1);
  x = ((x >> 2) & 0x3333333333333333ULL) | ((x & 0x3333333333333333ULL) << 2);
  x = ((x >> 4) & 0x0f0f0f0f0f0f0f0fULL) | ((x & 0x0f0f0f0f0f0f0f0fULL) << 4);
  return __builtin_bswap64(x);
}

// Owen scrambling of a binary fraction 0.b1 b2 b3 ... flips each digit by a hash of the digits
// before it; it keeps a (0,m,2)-net one. With the fraction's bits held reversed (b1 in bit 0),
// "the digits before" are the lower bits, which laineKarras mixes upwards: the scrambled
// fraction is reverseBits(laineKarras(reversed, seed)). Everything below stays in that
// reversed form until the final reversal, which saves half the bit reversals.

// The second Sobol dimension: the generator matrix is Pascal's triangle mod 2, column i being
// v_i = v_{i-1} xor (v_{i-1} >> 1) from v_0 = 2^31. Tabulated per index byte, bit-reversed.
struct SobolTables {
  std::array<std::array<std::uint32_t, 256>, 4> table{};
  SobolTables() {
    std::array<std::uint32_t, 32> column{};
    column[0] = 0x80000000U;
    for (std::size_t i = 1; i < 32; ++i) column[i] = column[i - 1] ^ (column[i - 1] >> 1);
    for (std::size_t byte = 0; byte < 4; ++byte)
      for (std::uint32_t value = 0; value < 256; ++value) {
        std::uint32_t sum = 0;
        for (std::size_t bit = 0; bit < 8; ++bit)
          if (value & (1U << bit)) sum ^= column[byte * 8 + bit];
        table[byte][value] = reverseBits(sum);
      }
  }
};
const SobolTables kSobol;

// reverseBits(Sobol second dimension of index).
std::uint32_t sobolSecondReversed(std::uint32_t index) {
  return kSobol.table[0][index & 255U] ^ kSobol.table[1][(index >> 8) & 255U] ^ kSobol.table[2][(index >> 16) & 255U] ^
         kSobol.table[3][index >> 24];
}

float toUnit(std::uint32_t x) { return static_cast<float>(x >> 8) * (1.f / 16777216.f); }

}  // namespace

SamplerKind parseSamplerKind(std::string_view name) {
  if (name == "sobol") return SamplerKind::Sobol;
  if (name == "independent") return SamplerKind::Independent;
  throw std::invalid_argument("unknown sampler '" + std::string(name) + "' (sobol, independent)");
}

const char* samplerKindName(SamplerKind kind) { return kind == SamplerKind::Sobol ? "sobol" : "independent"; }

Pcg32::Pcg32(std::uint64_t seed, std::uint64_t stream) : increment_((stream << 1u) | 1u) {
  next();
  state_ += seed;
  next();
}

Sampler::Sampler(SamplerKind kind, std::uint64_t seed, std::uint64_t pixel, int replicates)
    : kind_(kind), replicates_(static_cast<std::uint32_t>(replicates)), rng_(seed, pixel) {
  if (replicates < 1 || replicates > kMaxReplicates)
    throw std::invalid_argument("Sampler: replicates must be in [1, " + std::to_string(kMaxReplicates) + "], got " +
                                std::to_string(replicates));
  if (kind_ != SamplerKind::Sobol) return;
  pixel_hash_ = hash32(static_cast<std::uint32_t>(pixel) ^
                                          hash32(static_cast<std::uint32_t>(pixel >> 32) ^
                                                 hash32(static_cast<std::uint32_t>(seed) ^ hash32(static_cast<std::uint32_t>(seed >> 32)))));
}

// Seed i of the pixel: per replicate and dimension, the index shuffle's
// seed and one scrambling seed per coordinate. Replicate 0's seeds do not depend on the
// replicate count.
std::uint32_t Sampler::scrambleSeed(std::uint32_t i) const { return hash32(pixel_hash_ + 0x632be5abU * (i + 1)); }

void Sampler::startSample(std::uint32_t index) {
  if (replicates_ == 1) {
    index_reversed_ = reverseBits(index);
  } else {
    index_reversed_ = reverseBits(index / replicates_);
    seed_offset_ = static_cast<std::uint32_t>(3 * kLowDiscrepancyDimensions) * (index % replicates_);
  }
  dimension_ = 0;
}

float Sampler::get1D() {
  if (kind_ == SamplerKind::Independent || dimension_ >= kLowDiscrepancyDimensions) return rng_.uniform();
  const std::uint32_t seed = seed_offset_ + static_cast<std::uint32_t>(3 * dimension_);
  ++dimension_;
  // Shuffling the index (an Owen scramble of its reversed bits keeps every aligned block of
  // 2^k indices together) decorrelates this dimension from the others sharing the index; the
  // van der Corput value of the shuffled index, held reversed, is the shuffled index itself.
  const std::uint32_t shuffled = reverseBits(laineKarras(index_reversed_, scrambleSeed(seed)));
  return toUnit(reverseBits(laineKarras(shuffled, scrambleSeed(seed + 1))));
}

std::pair<float, float> Sampler::get2D() {
  if (kind_ == SamplerKind::Independent || dimension_ >= kLowDiscrepancyDimensions) {
    const float u = rng_.uniform();
    return {u, rng_.uniform()};
  }
  const std::uint32_t seed = seed_offset_ + static_cast<std::uint32_t>(3 * dimension_);
  ++dimension_;
  const std::uint32_t shuffled = reverseBits(laineKarras(index_reversed_, scrambleSeed(seed)));
  const std::uint64_t both = (static_cast<std::uint64_t>(laineKarras(shuffled, scrambleSeed(seed + 1))) << 32) |
                             laineKarras(sobolSecondReversed(shuffled), scrambleSeed(seed + 2));
  const std::uint64_t fractions = reverseBits64(both);  // x in the low word, y in the high word
  return {toUnit(static_cast<std::uint32_t>(fractions)), toUnit(static_cast<std::uint32_t>(fractions >> 32))};
}

}  // namespace solo
