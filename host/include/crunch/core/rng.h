// The single source of randomness. Every random choice flows from one --seed (ARCHITECTURE §3).
// Distributions are implemented here rather than with <random>'s distributions, whose output is
// implementation-defined, so a seed gives the same run with any standard library.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>

namespace crunch {

// xoshiro256** seeded with splitmix64. Not thread-safe: one instance per thread of work.
// Parallel work that must not depend on the thread count draws from streams split by jump():
// one Rng per piece of work, each jumped once more than the last (Mapper's global chains).
class Rng {
 public:
  explicit Rng(uint64_t seed) { reseed(seed); }
  // The generator in exactly this state (tests against published vectors); not all zero.
  explicit Rng(const std::array<uint64_t, 4>& state) : s_{state[0], state[1], state[2], state[3]} {}

  void reseed(uint64_t seed) {
    for (auto& s : s_) {
      seed += 0x9E3779B97F4A7C15ull;
      uint64_t z = seed;
      z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
      z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
      s = z ^ (z >> 31);
    }
    has_spare_ = false;
  }

  uint64_t next() {
    const uint64_t result = rotl(s_[1] * 5, 7) * 9;
    const uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return result;
  }

  // Uniform in [0, 1).
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  // Uniform integer in [0, n); n > 0.
  uint32_t below(uint32_t n) { return static_cast<uint32_t>((next() >> 32) * n >> 32); }
  // Standard normal (Marsaglia polar method).
  double normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u, v, s;
    do {
      u = 2.0 * uniform() - 1.0;
      v = 2.0 * uniform() - 1.0;
      s = u * u + v * v;
    } while (s >= 1.0 || s == 0.0);
    const double m = std::sqrt(-2.0 * std::log(s) / s);
    spare_ = v * m;
    has_spare_ = true;
    return u * m;
  }
  double normal(double mean, double sigma) { return mean + sigma * normal(); }

  // Advances the state by 2^128 draws (the authors' jump polynomial for xoshiro256, Blackman &
  // Vigna 2018): the streams of a generator jumped 0, 1, 2, ... times never overlap for 2^128
  // draws, so each is a piece of work's own. Forgets a spare normal draw.
  void jump() {
    constexpr uint64_t kJump[] = {0x180ec6d33cfd0abaull, 0xd5a61266f0c9392cull,
                                  0xa9582618e03fc9aaull, 0x39abdc4529b1661cull};
    uint64_t t[4] = {0, 0, 0, 0};
    for (const uint64_t word : kJump) {
      for (int b = 0; b < 64; ++b) {
        if (word & (uint64_t{1} << b)) {
          for (int i = 0; i < 4; ++i) t[i] ^= s_[i];
        }
        next();
      }
    }
    for (int i = 0; i < 4; ++i) s_[i] = t[i];
    has_spare_ = false;
  }

  std::array<uint64_t, 4> state() const { return {s_[0], s_[1], s_[2], s_[3]}; }

 private:
  static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  uint64_t s_[4];
  double spare_ = 0.0;
  bool has_spare_ = false;
};

// An index i drawn with probability exp(log_w[i]) / sum_j exp(log_w[j]) (one uniform draw; the
// largest weight is subtracted first, so any finite log weights work). `log_w` is overwritten
// with the unnormalised weights exp(log_w[i] - max). Not empty.
inline std::size_t drawLogWeighted(std::span<double> log_w, Rng& rng) {
  double top = -std::numeric_limits<double>::infinity();
  for (double w : log_w) top = std::max(top, w);
  double total = 0.0;
  for (double& w : log_w) total += (w = std::exp(w - top));
  double pick = rng.uniform() * total;
  std::size_t k = 0;
  while (k + 1 < log_w.size() && (pick -= log_w[k]) >= 0.0) ++k;
  return k;
}

}  // namespace crunch
