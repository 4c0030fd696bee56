#pragma once
// Random numbers for the Monte Carlo of the uncertainty analysis: reproducible, cheap, and
// splittable into independent streams, so that run r of a simulation draws the same numbers
// whatever the number of threads.
//  - SplitMix64 (Steele, Lea, Flood 2014) turns (seed, stream) into generator states;
//  - xoshiro256++ (Blackman, Vigna 2019) is the generator;
//  - normal variates by the ziggurat of Marsaglia and Tsang (2000) in the 128-layer form of
//    Doornik (2005, "An improved ziggurat method to generate normal random samples"), exact
//    (rejection), tail by Marsaglia's 1964 method.
// std::normal_distribution is not used: its output is implementation-defined (so not reproducible
// across standard libraries) and about five times slower here.
#include <array>
#include <cmath>
#include <cstdint>

namespace rotacal {

inline std::uint64_t splitmix64(std::uint64_t& x) {
  std::uint64_t z = (x += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

namespace detail {

struct ZigguratTables {
  static constexpr int kLayers = 128;
  static constexpr double kR = 3.442619855899;          // start of the tail
  static constexpr double kV = 9.91256303526217e-3;     // area of each layer
  std::array<double, kLayers + 1> x{};
  std::array<double, kLayers> ratio{};

  ZigguratTables() {
    double f = std::exp(-0.5 * kR * kR);
    x[0] = kV / f;  // the bottom layer (rectangle + tail) as a rectangle of the same area
    x[1] = kR;
    x[kLayers] = 0.0;
    for (int i = 2; i < kLayers; ++i) {
      x[i] = std::sqrt(-2.0 * std::log(kV / x[i - 1] + f));
      f = std::exp(-0.5 * x[i] * x[i]);
    }
    for (int i = 0; i < kLayers; ++i) ratio[i] = x[i + 1] / x[i];
  }
};

inline const ZigguratTables& zigguratTables() {
  static const ZigguratTables t;
  return t;
}

}  // namespace detail

/// xoshiro256++ with a ziggurat normal and a uniform on [0, 1).
class Rng {
 public:
  /// Stream `stream` of seed `seed`: independent generators for every (seed, stream) pair.
  Rng(std::uint64_t seed, std::uint64_t stream) {
    std::uint64_t x = seed ^ (0x6a09e667f3bcc909ULL * (stream + 1));
    // Mix twice so that neighbouring streams share no state bits.
    std::uint64_t y = splitmix64(x) ^ stream;
    for (auto& w : s_) w = splitmix64(y);
  }

  std::uint64_t next() {
    const std::uint64_t result = rotl(s_[0] + s_[3], 23) + s_[0];
    const std::uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return result;
  }

  /// Uniform on [0, 1), 53 bits.
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  /// Uniform on [lo, hi).
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }

  /// Standard normal variate.
  double normal() {
    const auto& z = detail::zigguratTables();
    for (;;) {
      const std::uint64_t r = next();
      const double u = 2.0 * (static_cast<double>(r >> 11) * 0x1.0p-53) - 1.0;  // bits 11..63
      const int i = static_cast<int>(r & 0x7F);                                 // bits 0..6
      if (std::abs(u) < z.ratio[i]) return u * z.x[i];  // inside the layer's inner rectangle
      if (i == 0) return tail(u < 0);
      const double x = u * z.x[i];
      const double f0 = std::exp(-0.5 * (z.x[i] * z.x[i] - x * x));
      const double f1 = std::exp(-0.5 * (z.x[i + 1] * z.x[i + 1] - x * x));
      if (f1 + uniform() * (f0 - f1) < 1.0) return x;  // in the wedge under the density
    }
  }

 private:
  static std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }

  double tail(bool negative) {
    constexpr double r = detail::ZigguratTables::kR;
    double x, y;
    do {
      x = std::log(uniformOpen()) / r;
      y = std::log(uniformOpen());
    } while (-2.0 * y < x * x);
    return negative ? x - r : r - x;
  }
  double uniformOpen() { return (static_cast<double>(next() >> 11) + 0.5) * 0x1.0p-53; }  // (0, 1)

  std::array<std::uint64_t, 4> s_{};
};

}  // namespace rotacal
