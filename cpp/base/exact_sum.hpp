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

}  // namespace exact_detail

// Terms m * 2^bit (units of 2^kExpMin, |m| < 2^53) collected in one int64 bin per bit position by
// plain additions, and added into an accumulator by flush_into after at most kTermsPerFlush terms
// (a bin then holds less than 2^53 * 2^9 = 2^62). Adding each term into the accumulator directly
// (its carries and chunk bounds) took about three times as long as a bin addition.
class ExactBins {
 public:
  static constexpr int kBias = -ExactAccumulator::kExpMin;
  // one past the highest bit of a term: the low part of the largest product of two doubles (its
  // high part goes into bins of its own, flushed 53 bits up)
  static constexpr int kBits = 2 * 2046 - 2 * 1075 + kBias + 1;
  static constexpr int kTermsPerFlush = 512;

  ExactBins() : bins_(kBits, 0) {}

  inline void add(std::int64_t m, int bit) {
    bins_[bit] += m;
    first_ = std::min(first_, bit);
    last_ = std::max(last_, bit);
  }

  // the bins into acc at `shift` bits up (each as two parts below 2^31, so that every chunk of the
  // accumulator takes additions of at most 2^32 until the caller normalises it); the bins emptied
  void flush_into(ExactAccumulator& acc, int shift = 0) {
    for (int b = first_; b <= last_; ++b) {
      const std::int64_t v = bins_[b];
      if (!v) continue;
      acc.add_mantissa(v & ((std::int64_t(1) << 31) - 1), b + shift);
      acc.add_mantissa(v >> 31, b + shift + 31);
      bins_[b] = 0;
    }
    first_ = kBits, last_ = -1;
  }

 private:
  std::vector<std::int64_t> bins_;
  int first_ = kBits, last_ = -1;  // the bins touched since the last flush
};

namespace exact_detail {

// x as a bins' term: false for infinities and NaN
inline bool add_double(ExactBins& bins, double x) {
  std::int64_t m;
  int e;
  const bool finite = split(x, m, e);
  bins.add(m, e + ExactBins::kBias);
  return finite;
}

// item(i) for i in [0, n), each adding one term to `bins`, flushed into the sum every
// kTermsPerFlush items; the sum
template <class Item>
ExactAccumulator sum_items(ExactBins& bins, std::int64_t n, Item&& item) {
  ExactAccumulator acc;
  for (std::int64_t start = 0; start < n; start += ExactBins::kTermsPerFlush) {
    const std::int64_t end = std::min<std::int64_t>(n, start + ExactBins::kTermsPerFlush);
    for (std::int64_t i = start; i < end; ++i) item(i);
    bins.flush_into(acc);
    acc.normalise();
  }
  return acc;
}

}  // namespace exact_detail

// sum(x[0..n)) exactly. what: the array's name in the error of a non-finite entry.
inline ExactAccumulator exact_sum(const double* x, std::int64_t n, const char* what = "the array") {
  ExactBins bins;
  return exact_detail::sum_items(bins, n, [&](std::int64_t i) {
    if (!exact_detail::add_double(bins, x[i])) exact_detail::non_finite(what, x[i], i);
  });
}

// sum(x[i] * y[i]) exactly, over the entries i whose row i / width is flagged in `rows` (nullptr:
// every entry). The product of the two 53-bit mantissas is formed exactly in 128 bits and split into
// its low and high 53 bits, so no case (subnormal, underflowing or overflowing product) needs a path
// of its own; the low parts and the high parts go into bins of their own.
inline ExactAccumulator exact_dot(const double* x, const double* y, std::int64_t n, const char* what_x = "the first array",
                                  const char* what_y = "the second array", const std::uint8_t* rows = nullptr,
                                  std::int64_t width = 1) {
  using namespace exact_detail;
  constexpr int kBias = ExactBins::kBias;
  constexpr std::uint64_t kLow53 = (std::uint64_t(1) << 53) - 1, kFrac = (std::uint64_t(1) << 52) - 1;
  ExactBins low, high;  // high: bin b holds the parts at bit b + 53
  ExactAccumulator acc;
  for (std::int64_t start = 0; start < n; start += ExactBins::kTermsPerFlush) {
    const std::int64_t end = std::min<std::int64_t>(n, start + ExactBins::kTermsPerFlush);
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
      low.add((std::int64_t((std::uint64_t)p & kLow53) ^ sign) - sign, bit);
      high.add((std::int64_t((std::uint64_t)(p >> 53)) ^ sign) - sign, bit);
    }
    low.flush_into(acc);
    high.flush_into(acc, 53);
    acc.normalise();
  }
  return acc;
}

// The node products of a nodal dot: fl(x_i . y_i), the `width` products of node i summed left to
// right in double (the order numpy's (x * y).sum(axis=1) takes), for every node i flagged in `rows`
// (nullptr: every node); then those node values summed exactly. A node is owned by one rank, which
// forms its value with the same operations on any partition, so the sum is the same on every rank
// count; it reads a node once rather than splitting each of its products exactly.
inline ExactAccumulator exact_node_dot(const double* x, const double* y, std::int64_t nodes, int width, const std::uint8_t* rows = nullptr) {
  ExactBins bins;
  return exact_detail::sum_items(bins, nodes, [&](std::int64_t i) {
    if (rows && !rows[i]) return;
    const double* a = x + i * width;
    const double* b = y + i * width;
    double s = a[0] * b[0];
    for (int c = 1; c < width; ++c) s += a[c] * b[c];
    if (!exact_detail::add_double(bins, s))
      throw InputError("the product at node " + std::to_string(i) + " is not finite (" + (std::isnan(s) ? "nan" : "inf") +
                       "): an exact sum needs finite values");
  });
}

}  // namespace cmg
