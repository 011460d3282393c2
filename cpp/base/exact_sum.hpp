// Exact sums of doubles and of products of two doubles in a fixed-point long accumulator.
//
// Every finite double is m * 2^e with an integer |m| < 2^53 and e >= -1074, and a product of two is
// an integer below 2^106 times 2^(ex + ey) with ex + ey >= -2148: all of them are integer multiples
// of 2^kExpMin. The accumulator holds the sum as that integer, T, in 32-bit digits kept in int64
// chunks; the 31 spare bits of a chunk absorb many additions before the carries must be propagated.
// No term is ever rounded, so the result does not depend on the order of the terms and is the
// same integer as the reference implementation in Python (contactmg.distributed.exchange).
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>
#include "base/common.hpp"

namespace cmg {

class ExactAccumulator {
 public:
  // The weight of bit 0 of T: the smallest subnormal's mantissa unit (2^-1074 = 2^-1 * 2^-1073 as
  // frexp writes it, with a 53-bit mantissa) squared, the lowest bit a product of two doubles has.
  static constexpr int kExpMin = -2 * (1073 + 53);
  static constexpr int kDigitBits = 32;
  // A product's top bit lies below 2^2048 (bit 4300 of T); the spare chunks above take the growth
  // of a sum of up to 2^63 terms and the sign.
  static constexpr int kChunks = 140;
  // Between carry propagations a chunk receives at most two contributions below 2^53 per term:
  // 2 * 256 * 2^53 = 2^62 plus a normalised digit stays below 2^63.
  static constexpr int kTermsPerNormalise = 256;

  ExactAccumulator() { chunks_.fill(0); }

  // Adds m * 2^bit units of 2^kExpMin: |m| < 2^53 signed, bit >= 0 the position of m's lowest bit in T.
  inline void add_mantissa(std::int64_t m, int bit) {
    const int c = bit >> 5, s = bit & 31;
    low_ = std::min(low_, c);
    high_ = std::max(high_, c + 1);
    // m * 2^s = low + high * 2^32 with low its last 32 bits (the unsigned shift may drop high bits,
    // never these) and high = floor(m / 2^(32 - s)), below 2^53 in magnitude
    chunks_[c] += std::int64_t((std::uint64_t(m) << s) & 0xffffffffu);
    chunks_[c + 1] += m >> (32 - s);
  }

  // Carries of every chunk into the next: afterwards all chunks but the last hold a digit in [0, 2^32).
  // Only the chunks from the lowest one added to since the last pass move: below it every chunk is a
  // digit already. Above the highest one added to, a carry may run on (a negative chunk borrows from
  // the digits above it), so the pass goes on until no carry is left: the same digits as a pass over
  // every chunk.
  void normalise() {
    int k = std::min(low_, kChunks - 1);
    for (; k + 1 < kChunks; ++k) {
      const std::int64_t carry = chunks_[k] >> kDigitBits;  // floor division by 2^32
      if (carry == 0 && k >= high_) break;
      chunks_[k] -= carry * (std::int64_t(1) << kDigitBits);
      chunks_[k + 1] += carry;
    }
    low_ = kChunks;
    high_ = 0;
  }

  // T in two's complement, little-endian: kChunks - 1 digits of 4 bytes and the signed last chunk
  // in 8 bytes (int.from_bytes(..., "little", signed=True) gives T). Normalises first.
  std::vector<unsigned char> to_bytes() {
    normalise();
    std::vector<unsigned char> out(4 * (kChunks - 1) + 8);
    for (int k = 0; k + 1 < kChunks; ++k) {
      const std::uint32_t d = (std::uint32_t)chunks_[k];
      for (int b = 0; b < 4; ++b) out[4 * k + b] = (unsigned char)(d >> (8 * b));
    }
    const std::uint64_t top = (std::uint64_t)chunks_[kChunks - 1];
    for (int b = 0; b < 8; ++b) out[4 * (kChunks - 1) + b] = (unsigned char)(top >> (8 * b));
    return out;
  }

 private:
  std::array<std::int64_t, kChunks> chunks_;
  int low_ = 0, high_ = kChunks;  // the chunks added to since the last normalise(): [low_, high_]
};

namespace exact_detail {

// x = m * 2^e with the signed integer m (|m| < 2^53) and e >= -1074 read from the bits (branch
// free: the signs of random data would defeat a predictor); false for infinities and NaN.
inline bool split(double x, std::int64_t& m, int& e) {
  std::uint64_t b;
  std::memcpy(&b, &x, sizeof b);
  const unsigned biased = unsigned(b >> 52) & 0x7ff;
  // subnormals (and zero) have no hidden bit and the exponent of the smallest normal
  const std::int64_t magnitude = std::int64_t((b & ((std::uint64_t(1) << 52) - 1)) | (std::uint64_t(biased != 0) << 52));
  const std::int64_t sign = std::int64_t(b) >> 63;  // all ones for a negative x: (v ^ sign) - sign = -v
  m = (magnitude ^ sign) - sign;
  e = int(biased + (biased == 0)) - 1075;
  return biased != 0x7ff;
}

[[noreturn]] inline void non_finite(const char* what, double v, std::int64_t i) {
  throw InputError(std::string(what) + " has a non-finite entry (" + (std::isnan(v) ? "nan" : v > 0 ? "inf" : "-inf") +
                   " at index " + std::to_string(i) + "): an exact sum needs finite values");
}

// Calls add(acc, i) for i in [0, n), propagating the carries every kTermsPerNormalise terms.
template <class Add>
ExactAccumulator accumulate(std::int64_t n, Add&& add) {
  ExactAccumulator acc;
  for (std::int64_t start = 0; start < n; start += ExactAccumulator::kTermsPerNormalise) {
    const std::int64_t end = std::min<std::int64_t>(n, start + ExactAccumulator::kTermsPerNormalise);
    for (std::int64_t i = start; i < end; ++i) add(acc, i);
    acc.normalise();
  }
  return acc;
}

}  // namespace exact_detail

// sum(x[0..n)) exactly. what: the array's name in the error of a non-finite entry.
inline ExactAccumulator exact_sum(const double* x, std::int64_t n, const char* what = "the array") {
  using namespace exact_detail;
  constexpr int kBias = -ExactAccumulator::kExpMin;
  return accumulate(n, [=](ExactAccumulator& acc, std::int64_t i) {
    std::int64_t m;
    int e;
    if (!split(x[i], m, e)) non_finite(what, x[i], i);
    acc.add_mantissa(m, e + kBias);
  });
}

// sum(x[i] * y[i]) exactly, over the entries i whose row i / width is flagged in `rows` (nullptr:
// every entry). The product of the two 53-bit mantissas is formed exactly in 128 bits and split into
// its low and high 53 bits, so no case (subnormal, underflowing or overflowing product) needs a path
// of its own. The parts go into one int64 bin per bit position of T (the low and the high parts in
// bins of their own), plain additions: a bin takes at most kTermsPerFlush parts below 2^53 (below
// 2^62 in all), then the bins touched since the last flush are added into the accumulator. That
// kept the per-term work to two additions (the parts added into the accumulator directly took
// about three times as long).
inline ExactAccumulator exact_dot(const double* x, const double* y, std::int64_t n, const char* what_x = "the first array",
                                  const char* what_y = "the second array", const std::uint8_t* rows = nullptr,
                                  std::int64_t width = 1) {
  using namespace exact_detail;
  constexpr int kBias = -ExactAccumulator::kExpMin;
  constexpr std::uint64_t kLow53 = (std::uint64_t(1) << 53) - 1, kFrac = (std::uint64_t(1) << 52) - 1;
  constexpr std::int64_t kTermsPerFlush = 512;
  constexpr int kBits = 2 * 2046 - 2 * 1075 + kBias + 1;  // one past the largest bit of a low part
  std::vector<std::int64_t> low(kBits, 0), high(kBits, 0);  // the high part of bin b lies at bit b + 53
  int first = kBits, last = -1;                            // the bins touched since the last flush
  ExactAccumulator acc;
  const auto flush = [&]() {
    for (int b = first; b <= last; ++b) {
      for (std::int64_t* bin : {&low[b], &high[b]}) {
        const std::int64_t v = *bin;
        if (!v) continue;
        const int at = b + (bin == &high[b] ? 53 : 0);
        // |v| < 2^62: as two parts below 2^32, so that every chunk of the accumulator takes
        // additions of at most 2^32 until the normalisation below
        acc.add_mantissa(v & ((std::int64_t(1) << 31) - 1), at);
        acc.add_mantissa(v >> 31, at + 31);
        *bin = 0;
      }
    }
    acc.normalise();
    first = kBits, last = -1;
  };
  for (std::int64_t start = 0; start < n; start += kTermsPerFlush) {
    const std::int64_t end = std::min(n, start + kTermsPerFlush);
    for (std::int64_t i = start; i < end; ++i) {
      if (rows && !rows[i / width]) continue;
      std::uint64_t bx, by;
      std::memcpy(&bx, x + i, sizeof bx);
      std::memcpy(&by, y + i, sizeof by);
      const unsigned biased_x = unsigned(bx >> 52) & 0x7ff, biased_y = unsigned(by >> 52) & 0x7ff;
      if (biased_x == 0x7ff) non_finite(what_x, x[i], i);
      if (biased_y == 0x7ff) non_finite(what_y, y[i], i);
      const std::uint64_t mx = (bx & kFrac) | (std::uint64_t(biased_x != 0) << 52);
      const std::uint64_t my = (by & kFrac) | (std::uint64_t(biased_y != 0) << 52);
      const unsigned __int128 p = (unsigned __int128)mx * my;
      // all ones for a negative product: v ^ sign - sign is -v then
      const std::int64_t sign = std::int64_t((bx ^ by)) >> 63;
      const int bit = int(biased_x + (biased_x == 0)) + int(biased_y + (biased_y == 0)) - 2 * 1075 + kBias;
      low[bit] += (std::int64_t((std::uint64_t)p & kLow53) ^ sign) - sign;
      high[bit] += (std::int64_t((std::uint64_t)(p >> 53)) ^ sign) - sign;
      first = std::min(first, bit);
      last = std::max(last, bit);
    }
    flush();
  }
  return acc;
}

}  // namespace cmg
