#pragma once
// exp(x) for x <= 0 without a libm call, written so that gcc vectorises loops that use it (no
// branches, no table): the overlap integrals of E_sim and E_col take one exp per Gaussian pair.
//
//   exp(x) = 2^n exp(r),  n = round(x / ln 2),  r = x - n ln 2 in [-ln2/2, ln2/2]
//
// exp(r) by its Taylor series to degree 11 (truncation error |r|^12/12! < 7e-15 relative), ln 2
// split in two parts (Cody-Waite) so that r is exact to double precision, and 2^n built directly
// in the exponent bits. Relative error < 1e-14 for x in [-700, 0]; smaller x give exp(-700) ~ 1e-304
// instead of 0 or a denormal, which is harmless for sums of overlaps.

#include <bit>
#include <cstdint>

namespace handtrack::detail {

inline double exp_nonpositive(double x) {
  constexpr double kMinX = -700.0;
  constexpr double kLog2e = 1.4426950408889634;
  constexpr double kLn2Hi = 0.693147180369123816490;  // ln 2 with its low bits zero: n * kLn2Hi is exact
  constexpr double kLn2Lo = 1.90821492927058770002e-10;
  constexpr double kRoundShift = 0x1.8p52;  // adding it rounds to an integer kept in the low mantissa bits
  x = x < kMinX ? kMinX : x;
  const double shifted = x * kLog2e + kRoundShift;
  const double n = shifted - kRoundShift;
  const double r = (x - n * kLn2Hi) - n * kLn2Lo;
  // exp(r) = sum_{k=0..11} r^k / k!, evaluated by Estrin's scheme: pairs, then pairs of pairs, so
  // the dependency chain is 4 multiply-adds long instead of Horner's 11.
  const double r2 = r * r;
  const double r4 = r2 * r2;
  const double r8 = r4 * r4;
  const double c01 = 1.0 + r;
  const double c23 = 1.0 / 2.0 + r * (1.0 / 6.0);
  const double c45 = 1.0 / 24.0 + r * (1.0 / 120.0);
  const double c67 = 1.0 / 720.0 + r * (1.0 / 5040.0);
  const double c89 = 1.0 / 40320.0 + r * (1.0 / 362880.0);
  const double c1011 = 1.0 / 3628800.0 + r * (1.0 / 39916800.0);
  const double c0123 = c01 + r2 * c23;
  const double c4567 = c45 + r2 * c67;
  const double c891011 = c89 + r2 * c1011;
  const double p = (c0123 + r4 * c4567) + r8 * c891011;
  // 2^n: the low 12 bits of `shifted` hold n (two's complement); shifted into the exponent field
  // and biased by 1023 they are the bits of 2^n for n in [-1022, 0].
  const uint64_t two_n_bits = (std::bit_cast<uint64_t>(shifted) << 52) + (uint64_t{1023} << 52);
  return p * std::bit_cast<double>(two_n_bits);
}

}  // namespace handtrack::detail
