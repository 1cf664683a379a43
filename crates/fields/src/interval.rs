//! Helpers for [`crate::ScalarField::range`]: distances from a point to a box, and rounding a
//! real interval outward to a conservative `f32` range.
//!
//! **Rounding argument shared by every field.** A field's `sample` computes its value in `f32` by
//! a handful (at most about ten) of additions, subtractions, multiplications and square roots of
//! numbers whose magnitudes add up to at most `M` (the field names its `M`). Each such operation
//! rounds with a relative error of at most `u = 2^-24`, so to first order the value it returns
//! differs from the exact real value of the same formula by at most `10 u M`. The ranges are
//! computed in `f64` from the exact real formula (relative error about `2^-50`, negligible) and
//! then widened by [`SLACK_REL`]` * M + `[`SLACK_ABS`] (`2^-19 = 32 u`, three times the first
//! order bound; the absolute term covers subnormal results), and finally rounded outward to
//! `f32`. So the range contains every value the field actually returns in the box.

use glam::Vec3;

/// Relative widening of a range, per unit of the magnitude `M` of the operands (`2^-19`).
pub(crate) const SLACK_REL: f64 = 1.0 / 524_288.0;
/// Absolute widening of a range (covers subnormal intermediate results).
pub(crate) const SLACK_ABS: f64 = 1e-30;

/// The box `[lo, hi]` in `f64`, or `None` when it is not a proper finite box.
pub(crate) fn box64(lo: Vec3, hi: Vec3) -> Option<([f64; 3], [f64; 3])> {
    if !(lo.is_finite() && hi.is_finite()) || lo.cmpgt(hi).any() {
        return None;
    }
    Some((
        [f64::from(lo.x), f64::from(lo.y), f64::from(lo.z)],
        [f64::from(hi.x), f64::from(hi.y), f64::from(hi.z)],
    ))
}

/// Smallest and largest `|x - c|` for `x` in `[lo, hi]` (one axis).
#[inline]
pub(crate) fn axis_distance(lo: f64, hi: f64, c: f64) -> (f64, f64) {
    let near = if c < lo {
        lo - c
    } else if c > hi {
        c - hi
    } else {
        0.0
    };
    (near, (c - lo).abs().max((hi - c).abs()))
}

/// Smallest and largest Euclidean distance from `c` to a point of the box `[lo, hi]`.
pub(crate) fn distance_to_box(lo: [f64; 3], hi: [f64; 3], c: [f64; 3]) -> (f64, f64) {
    let (mut near, mut far) = (0.0, 0.0);
    for a in 0..3 {
        let (n, f) = axis_distance(lo[a], hi[a], c[a]);
        near += n * n;
        far += f * f;
    }
    (near.sqrt(), far.sqrt())
}

/// The real interval `[lo, hi]` widened by the rounding slack for operand magnitude `magnitude`
/// and rounded outward to `f32`; `None` when it is not finite.
pub(crate) fn widen(lo: f64, hi: f64, magnitude: f64) -> Option<(f32, f32)> {
    let slack = SLACK_REL * magnitude.abs() + SLACK_ABS;
    let (lo, hi) = (lo - slack, hi + slack);
    if !(lo.is_finite() && hi.is_finite()) || lo > hi {
        return None;
    }
    Some((down(lo), up(hi)))
}

/// The largest `f32` at most `x`.
pub(crate) fn down(x: f64) -> f32 {
    let y = x as f32;
    if f64::from(y) > x {
        y.next_down()
    } else {
        y
    }
}

/// The smallest `f32` at least `x`.
pub(crate) fn up(x: f64) -> f32 {
    let y = x as f32;
    if f64::from(y) < x {
        y.next_up()
    } else {
        y
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outward_rounding_brackets_the_value() {
        for x in [0.1f64, -0.1, 1.0 / 3.0, 1e-40, -7.000000001, 0.0] {
            assert!(f64::from(down(x)) <= x && x <= f64::from(up(x)), "{x}");
            assert!(
                f64::from(up(x)) - f64::from(down(x))
                    <= f64::from(f32::EPSILON) * x.abs().max(1e-38) * 2.0
            );
        }
        assert_eq!(distance_to_box([0.0; 3], [1.0; 3], [0.5; 3]).0, 0.0);
        let (n, f) = distance_to_box([1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0; 3]);
        assert_eq!((n, f), (1.0, 2.0));
        assert!(widen(f64::NAN, 1.0, 1.0).is_none());
        assert!(box64(Vec3::ONE, Vec3::ZERO).is_none());
    }
}
