#pragma once
/// @file DeterminantFilter.h
/// The floating-point filter of the exact orientation signs: when a determinant computed in
/// double by expansion of minors is certainly of the sign it shows. Shared by the geometry
/// kernel's predicates (runtime/geometry/Predicates.h) and by the readers' degenerate-triangle
/// test, which sit in different layers.

namespace tetrapage::detail {

// Shewchuk's bounds for the determinant of rounded differences expanded by minors:
// orient3d (7 + 56u)u, orient2d (3 + 16u)u with u = 2^-53; rounded up to powers of two so the
// product with the permanent is exact.
inline constexpr double kOrient3dRelativeBound = 0x1p-50;
inline constexpr double kOrient2dRelativeBound = 0x1p-51;
// Gradual underflow adds an absolute error below 2^-1075 per product; a product of a minor
// with a coordinate difference w magnifies it by |w| (hence the |w| term in orient3d). That
// bound, 2^-1072 (|w|_1 + 2), is subnormal: arithmetic on subnormals takes a slow microcode
// path on x86 (about 100 cycles), so the filter never computes it. It accepts a sign when
// |det| exceeds twice each of the two terms (hence their sum), testing the underflow term
// scaled by 2^1000, where every operand is normal.
inline constexpr double kUnderflowScale = 0x1p+1000;
inline constexpr double kUnderflowScaledPerUnit = 0x1p-71;  // 2 * 2^-1072 * 2^1000

// |det| is certainly larger than the rounding error of the filter. False for NaN and for
// overflow (an infinite permanent): the caller then decides exactly.
inline bool filter_accepts(double det_magnitude, double relative_bound, double permanent,
                           double underflow_units) {
  return det_magnitude > 2 * relative_bound * permanent &&
         det_magnitude * kUnderflowScale > kUnderflowScaledPerUnit * underflow_units;
}

}  // namespace tetrapage::detail
