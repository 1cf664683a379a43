//! Triangle quality: how far each triangle is from equilateral, and how big it is.
//!
//! Every measure is computed in `f64` from the `f32` positions. For a triangle with edge lengths
//! `a, b, c`, semi-perimeter `s = (a + b + c) / 2` and area `A`:
//!
//! ```text
//!            C
//!           / \          circumradius  R = abc / (4A)
//!        b /   \ a       inradius      r = A / s
//!         /  r  \
//!        A-------B       radius ratio  R / (2r) = abc / (8 (s-a)(s-b)(s-c)) = abc s / (8 A^2)
//!            c           Verdict ratio l_max / (2 sqrt(3) r)
//! ```
//!
//! Both ratios are 1 for an equilateral triangle and grow without bound for slivers. The area is
//! taken from the cross product rather than from Heron's formula: the two agree exactly in real
//! arithmetic (`A^2 = s (s-a)(s-b)(s-c)`), but the cross product keeps its accuracy for the flat
//! triangles that matter most here. Angles come from `atan2(|e1 x e2|, e1 . e2)` at each corner,
//! which is accurate for angles near 0 and 180 degrees.
//!
//! **Zero-area triangles** are those with a repeated vertex index or with
//! `A <= ZERO_AREA_REL_TOL * l_max^2` ([`ZERO_AREA_REL_TOL`] = 1e-12, i.e. a height below
//! 2e-12 of the longest edge: far below the resolution of `f32` coordinates, so only triangles
//! whose corners are collinear as stored are caught, and genuine slivers still count in the
//! ratios). They are counted apart ([`QualityReport::zero_area_triangles`], and the same rule gives
//! [`crate::ValidationReport::zero_area_triangles`]) and excluded from the ratio and angle
//! statistics, whose values would be infinite or meaningless. Area statistics cover every
//! measurable triangle, zero-area ones included.
//!
//! Triangles with an index out of range or a non-finite coordinate cannot be measured; they are
//! counted in [`QualityReport::unmeasurable_triangles`] and left out of every statistic.
//!
//! Percentiles (median, 95th, 99th) interpolate linearly between the two nearest order statistics
//! of the sorted sample (position `p (n - 1)`, numpy's default "linear" method). Standard
//! deviations are population standard deviations (divide by `n`). An empty sample gives zeros.

use crate::Mesh;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// A triangle has zero area when `area <= ZERO_AREA_REL_TOL * longest_edge^2` (height below
/// `2 * ZERO_AREA_REL_TOL` times its longest edge), or when it repeats a vertex index.
pub const ZERO_AREA_REL_TOL: f64 = 1e-12;

/// Triangle quality statistics. Ratios exclude zero-area triangles (counted apart).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct QualityReport {
    /// Mean radius ratio R / (2r) (1 = equilateral).
    pub ar_mean: f64,
    /// Standard deviation of the radius ratio.
    pub ar_sd: f64,
    /// Median radius ratio.
    pub ar_median: f64,
    /// 95th percentile of the radius ratio.
    pub ar_p95: f64,
    /// 99th percentile of the radius ratio.
    pub ar_p99: f64,
    /// Largest radius ratio.
    pub ar_max: f64,
    /// Share of triangles with radius ratio above 2.
    pub ar_share_above_2: f64,
    /// Mean Verdict aspect ratio l_max / (2 sqrt(3) r).
    pub verdict_ar_mean: f64,
    /// Mean of each triangle's smallest angle, degrees.
    pub min_angle_deg_mean: f64,
    /// Smallest angle in the mesh, degrees.
    pub min_angle_deg_min: f64,
    /// Mean triangle area.
    pub area_mean: f64,
    /// Standard deviation of triangle area.
    pub area_sd: f64,
    /// Smallest triangle area.
    pub area_min: f64,
    /// Largest triangle area.
    pub area_max: f64,
    /// Total area.
    pub area_total: f64,
    /// Triangles with (near) zero area (see [`ZERO_AREA_REL_TOL`]); excluded from the ratio and
    /// angle statistics, included in the area statistics.
    #[serde(default)]
    pub zero_area_triangles: usize,
    /// Triangles with an out-of-range index or a non-finite coordinate; excluded from every
    /// statistic.
    #[serde(default)]
    pub unmeasurable_triangles: usize,
}

/// What one triangle looks like to the measures (shared with [`crate::validate`], so that both
/// reports count the same zero-area triangles).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum TriangleShape {
    /// An index is not below the vertex count.
    OutOfRange,
    /// A coordinate is NaN or infinite (or the measures overflow).
    NonFinite,
    /// A repeated index, or collinear corners within [`ZERO_AREA_REL_TOL`].
    ZeroArea {
        /// The (tiny) area, 0 for a repeated index.
        area: f64,
    },
    /// A triangle with a well-defined shape.
    Proper {
        /// Edge lengths, opposite corners 0, 1, 2.
        lengths: [f64; 3],
        /// Twice the area (the cross product's length).
        double_area: f64,
        /// The dot products of the two edges leaving each corner (for the angles).
        corner_dots: [f64; 3],
    },
}

/// The radius ratio R / (2r) above which a triangle counts as a sliver for the checks that
/// guard triangle shape: the extractor's edge collapse and the level-of-detail world's
/// clustering.
pub const SLIVER_RATIO: f64 = 10.0;

/// The radius ratio R / (2r) of the triangle with corners `p` (1 for an equilateral one;
/// infinite for zero area): `a b c s / (8 A^2)` with `s` the half perimeter, as
/// [`quality()`] measures it, for one triangle (the checks that guard triangle shape read it).
pub fn radius_ratio(p: [DVec3; 3]) -> f64 {
    let [a, b, c] = [0, 1, 2].map(|e| (p[(e + 1) % 3] - p[e]).length());
    let area = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length();
    if area > 0.0 {
        a * b * c * (0.5 * (a + b + c)) / (8.0 * area * area)
    } else {
        f64::INFINITY
    }
}

/// Classifies and measures triangle `t` of a mesh with `positions`.
pub(crate) fn triangle_shape(positions: &[[f32; 3]], t: [u32; 3]) -> TriangleShape {
    let n = positions.len();
    if t.iter().any(|&i| i as usize >= n) {
        return TriangleShape::OutOfRange;
    }
    if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
        return TriangleShape::ZeroArea { area: 0.0 };
    }
    let p = t.map(|i| DVec3::from(positions[i as usize].map(f64::from)));
    // Edge i is opposite corner i.
    let e = [p[2] - p[1], p[0] - p[2], p[1] - p[0]];
    let double_area = e[1].cross(e[2]).length();
    let lengths = e.map(|v| v.length());
    if !double_area.is_finite() || lengths.iter().any(|l| !l.is_finite()) {
        return TriangleShape::NonFinite;
    }
    let l_max = lengths[0].max(lengths[1]).max(lengths[2]);
    let area = 0.5 * double_area;
    if area <= ZERO_AREA_REL_TOL * l_max * l_max {
        return TriangleShape::ZeroArea { area };
    }
    // At corner 0 the edges leaving it are p1 - p0 = e[2] and p2 - p0 = -e[1]; and so on.
    let corner_dots = [-e[2].dot(e[1]), -e[0].dot(e[2]), -e[1].dot(e[0])];
    TriangleShape::Proper {
        lengths,
        double_area,
        corner_dots,
    }
}

/// The shape measures of one proper triangle.
struct Measures {
    radius_ratio: f64,
    verdict_ratio: f64,
    min_angle_deg: f64,
}

fn measures(lengths: [f64; 3], double_area: f64, corner_dots: [f64; 3]) -> Measures {
    let [a, b, c] = lengths;
    let s = 0.5 * (a + b + c);
    let area = 0.5 * double_area;
    // R / (2r) with R = abc / (4A), r = A / s.
    let radius_ratio = a * b * c * s / (8.0 * area * area);
    let inradius = area / s;
    let l_max = a.max(b).max(c);
    let verdict_ratio = l_max / (2.0 * 3f64.sqrt() * inradius);
    // The smallest angle is opposite the shortest edge; |e1 x e2| is twice the area at every
    // corner.
    let shortest = if a <= b && a <= c {
        0
    } else if b <= c {
        1
    } else {
        2
    };
    let min_angle = double_area.atan2(corner_dots[shortest]);
    Measures {
        radius_ratio,
        verdict_ratio,
        min_angle_deg: min_angle.to_degrees(),
    }
}

/// Mean and population standard deviation (two passes, for accuracy); zeros when empty.
fn mean_sd(values: &[f64]) -> (f64, f64) {
    if values.is_empty() {
        return (0.0, 0.0);
    }
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n;
    (mean, var.sqrt())
}

/// Linear-interpolation percentile of an ascending sample (`p` in [0, 1]); 0 when empty.
fn percentile_sorted(sorted: &[f64], p: f64) -> f64 {
    match sorted.len() {
        0 => 0.0,
        1 => sorted[0],
        n => {
            let pos = p.clamp(0.0, 1.0) * (n - 1) as f64;
            let lo = pos.floor() as usize;
            let hi = (lo + 1).min(n - 1);
            let frac = pos - lo as f64;
            sorted[lo] + (sorted[hi] - sorted[lo]) * frac
        }
    }
}

/// Measures every triangle of `mesh`.
///
/// Ratios and angles exclude zero-area triangles, area statistics include them, and triangles
/// that cannot be measured (out-of-range index, non-finite coordinate) are only counted; see the
/// [module documentation](self) for the definitions and tolerance. An empty mesh gives an
/// all-zero report.
///
/// ```
/// use rmt_mesh::{quality, Mesh};
/// let h = 3f32.sqrt() / 2.0;
/// let corners = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, h, 0.0]];
/// let mesh = Mesh::from_triangles(corners, vec![0, 1, 2]);
/// let q = quality(&mesh);
/// assert!((q.ar_mean - 1.0).abs() < 1e-6 && (q.min_angle_deg_min - 60.0).abs() < 1e-4);
/// ```
pub fn quality(mesh: &Mesh) -> QualityReport {
    let triangle_count = mesh.triangle_count();
    let mut radius_ratios = Vec::with_capacity(triangle_count);
    let mut areas = Vec::with_capacity(triangle_count);
    let mut verdict_sum = 0.0;
    let mut min_angle_sum = 0.0;
    let mut min_angle_min = f64::INFINITY;
    let mut report = QualityReport::default();

    for t in mesh.triangles() {
        match triangle_shape(&mesh.positions, t) {
            TriangleShape::OutOfRange | TriangleShape::NonFinite => {
                report.unmeasurable_triangles += 1;
            }
            TriangleShape::ZeroArea { area } => {
                report.zero_area_triangles += 1;
                areas.push(area);
            }
            TriangleShape::Proper {
                lengths,
                double_area,
                corner_dots,
            } => {
                let m = measures(lengths, double_area, corner_dots);
                radius_ratios.push(m.radius_ratio);
                verdict_sum += m.verdict_ratio;
                min_angle_sum += m.min_angle_deg;
                min_angle_min = min_angle_min.min(m.min_angle_deg);
                areas.push(0.5 * double_area);
            }
        }
    }

    if !radius_ratios.is_empty() {
        let n = radius_ratios.len() as f64;
        (report.ar_mean, report.ar_sd) = mean_sd(&radius_ratios);
        report.ar_share_above_2 = radius_ratios.iter().filter(|&&r| r > 2.0).count() as f64 / n;
        radius_ratios.sort_unstable_by(f64::total_cmp);
        report.ar_median = percentile_sorted(&radius_ratios, 0.5);
        report.ar_p95 = percentile_sorted(&radius_ratios, 0.95);
        report.ar_p99 = percentile_sorted(&radius_ratios, 0.99);
        report.ar_max = radius_ratios[radius_ratios.len() - 1];
        report.verdict_ar_mean = verdict_sum / n;
        report.min_angle_deg_mean = min_angle_sum / n;
        report.min_angle_deg_min = min_angle_min;
    }
    if !areas.is_empty() {
        (report.area_mean, report.area_sd) = mean_sd(&areas);
        report.area_total = areas.iter().sum();
        report.area_min = areas.iter().copied().fold(f64::INFINITY, f64::min);
        report.area_max = areas.iter().copied().fold(0.0, f64::max);
    }
    report
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * (1.0 + b.abs())
    }

    fn equilateral(side: f32) -> Mesh {
        let h = side * 3f32.sqrt() / 2.0;
        Mesh::from_triangles(
            vec![[0.0, 0.0, 0.0], [side, 0.0, 0.0], [0.5 * side, h, 0.0]],
            vec![0, 1, 2],
        )
    }

    #[test]
    fn equilateral_triangle_has_unit_ratios_and_sixty_degree_angles() {
        let q = quality(&equilateral(2.0));
        assert!(close(q.ar_mean, 1.0, 1e-6), "{q:?}");
        assert!(close(q.ar_max, 1.0, 1e-6));
        assert!(close(q.ar_median, 1.0, 1e-6));
        assert!(close(q.verdict_ar_mean, 1.0, 1e-6));
        assert!(close(q.min_angle_deg_mean, 60.0, 1e-5));
        assert!(close(q.min_angle_deg_min, 60.0, 1e-5));
        assert_eq!(q.ar_sd, 0.0);
        assert_eq!(q.ar_share_above_2, 0.0);
        // Area of an equilateral triangle of side 2: sqrt(3).
        assert!(close(q.area_total, 3f64.sqrt(), 1e-6));
        assert_eq!(q.zero_area_triangles, 0);
    }

    #[test]
    fn right_isosceles_triangle_has_the_hand_computed_ratios() {
        // Legs 1, 1, hypotenuse sqrt(2). Area 1/2, semi-perimeter s = 1 + sqrt(2)/2.
        // R = sqrt(2)/2 (half the hypotenuse), r = A/s = 1/(2 + sqrt(2)).
        // R/(2r) = (sqrt(2)/2)(2 + sqrt(2))/2 = (sqrt(2) + 1)/2 ~ 1.2071.
        // Verdict: l_max/(2 sqrt(3) r) = sqrt(2)(2 + sqrt(2))/(2 sqrt(3)) = (sqrt(2) + 1)/sqrt(3).
        // Smallest angle: 45 degrees.
        let mesh = Mesh::from_triangles(
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![0, 1, 2],
        );
        let q = quality(&mesh);
        let sqrt2 = 2f64.sqrt();
        assert!(close(q.ar_mean, (sqrt2 + 1.0) / 2.0, 1e-12), "{q:?}");
        assert!(close(q.verdict_ar_mean, (sqrt2 + 1.0) / 3f64.sqrt(), 1e-12));
        assert!(close(q.min_angle_deg_min, 45.0, 1e-12));
        assert!(close(q.area_mean, 0.5, 1e-12));
    }

    #[test]
    fn radius_ratio_matches_the_heron_form_of_the_spec() {
        // abc / (8 (s-a)(s-b)(s-c)) for a 3-4-5 triangle: 60 / (8 * 1 * 2 * 3) = 1.25.
        let mesh = Mesh::from_triangles(
            vec![[0.0, 0.0, 0.0], [4.0, 0.0, 0.0], [0.0, 3.0, 0.0]],
            vec![0, 1, 2],
        );
        let (a, b, c) = (3.0f64, 4.0, 5.0);
        let s = (a + b + c) / 2.0;
        let heron = a * b * c / (8.0 * (s - a) * (s - b) * (s - c));
        assert!(close(quality(&mesh).ar_mean, heron, 1e-12));
    }

    #[test]
    fn zero_area_triangles_are_counted_apart_and_excluded_from_ratios() {
        let mut mesh = equilateral(1.0);
        // Collinear corners and a repeated index.
        mesh.positions
            .extend([[2.0, 0.0, 0.0], [3.0, 0.0, 0.0], [4.0, 0.0, 0.0]]);
        mesh.indices.extend([3, 4, 5, 0, 0, 1]);
        let q = quality(&mesh);
        assert_eq!(q.zero_area_triangles, 2);
        assert!(close(q.ar_max, 1.0, 1e-6), "{q:?}");
        assert!(close(q.min_angle_deg_min, 60.0, 1e-4));
        // Areas include them: the minimum is 0 and the mean is a third of the one real area.
        assert_eq!(q.area_min, 0.0);
        assert!(close(q.area_mean, q.area_total / 3.0, 1e-12));
    }

    #[test]
    fn a_thin_sliver_above_the_tolerance_is_measured() {
        // Height 1e-4 over a base of 1: far above the tolerance, so it counts, with a large ratio.
        let mesh = Mesh::from_triangles(
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 1e-4, 0.0]],
            vec![0, 1, 2],
        );
        let q = quality(&mesh);
        assert_eq!(q.zero_area_triangles, 0);
        assert!(q.ar_max > 1e3, "{q:?}");
        assert_eq!(q.ar_share_above_2, 1.0);
        assert!(q.min_angle_deg_min < 0.1);
    }

    #[test]
    fn empty_mesh_gives_all_zeros() {
        assert_eq!(quality(&Mesh::default()), QualityReport::default());
    }

    #[test]
    fn unmeasurable_triangles_are_only_counted() {
        let mut mesh = equilateral(1.0);
        mesh.positions.push([f32::NAN, 0.0, 0.0]);
        mesh.indices.extend([0, 1, 3, 0, 1, 99]);
        let q = quality(&mesh);
        assert_eq!(q.unmeasurable_triangles, 2);
        assert!(close(q.ar_mean, 1.0, 1e-6));
        assert!(q.area_total.is_finite());
    }

    #[test]
    fn percentiles_interpolate_linearly() {
        let sorted = [1.0, 2.0, 3.0, 4.0, 5.0];
        assert_eq!(percentile_sorted(&sorted, 0.5), 3.0);
        assert_eq!(percentile_sorted(&sorted, 0.95), 4.8);
        assert_eq!(percentile_sorted(&sorted, 1.0), 5.0);
        assert_eq!(percentile_sorted(&[], 0.5), 0.0);
        let (mean, sd) = mean_sd(&[2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0]);
        assert_eq!((mean, sd), (5.0, 2.0));
    }

    proptest! {
        #[test]
        fn statistics_are_finite_ordered_and_at_least_one(
            coords in prop::collection::vec(-10.0f32..10.0, 9..90),
        ) {
            let positions: Vec<[f32; 3]> =
                coords.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
            let n = positions.len() as u32 / 3 * 3;
            let mesh = Mesh::from_triangles(positions, (0..n).collect());
            let q = quality(&mesh);
            let all = [q.ar_mean, q.ar_sd, q.ar_median, q.ar_p95, q.ar_p99, q.ar_max,
                q.verdict_ar_mean, q.min_angle_deg_mean, q.area_mean, q.area_total];
            prop_assert!(all.iter().all(|v| v.is_finite()), "{q:?}");
            if q.zero_area_triangles < mesh.triangle_count() {
                // R >= 2r (Euler's inequality) and the smallest angle is at most 60 degrees.
                prop_assert!(q.ar_median >= 1.0 - 1e-9);
                prop_assert!(q.ar_median <= q.ar_p95 && q.ar_p95 <= q.ar_p99);
                prop_assert!(q.ar_p99 <= q.ar_max);
                prop_assert!(q.min_angle_deg_min <= 60.0 + 1e-9 && q.min_angle_deg_min > 0.0);
                prop_assert!(q.min_angle_deg_min <= q.min_angle_deg_mean + 1e-9);
            }
            prop_assert!(q.area_min <= q.area_mean + 1e-12 && q.area_mean <= q.area_max + 1e-12);
            prop_assert!(close(q.area_total, mesh.area(), 1e-9));
        }

        #[test]
        fn ratios_do_not_depend_on_scale_or_corner_order(
            c in prop::collection::vec(-5.0f32..5.0, 9),
            scale in 0.01f32..100.0,
        ) {
            let p = vec![[c[0], c[1], c[2]], [c[3], c[4], c[5]], [c[6], c[7], c[8]]];
            let a = quality(&Mesh::from_triangles(p.clone(), vec![0, 1, 2]));
            prop_assume!(a.zero_area_triangles == 0 && a.ar_max < 1e3);
            let rotated = quality(&Mesh::from_triangles(p.clone(), vec![2, 0, 1]));
            let scaled: Vec<[f32; 3]> = p.iter().map(|v| v.map(|x| x * scale)).collect();
            let b = quality(&Mesh::from_triangles(scaled, vec![0, 1, 2]));
            prop_assert!(close(a.ar_mean, rotated.ar_mean, 1e-12));
            prop_assert!(close(a.ar_mean, b.ar_mean, 1e-3), "{} vs {}", a.ar_mean, b.ar_mean);
            prop_assert!(close(a.min_angle_deg_min, b.min_angle_deg_min, 1e-3));
            prop_assert!(a.verdict_ar_mean >= 1.0 - 1e-9);
            // The smallest angle, found opposite the shortest edge, is the least of all three.
            let q = p.iter().map(|v| glam::DVec3::from(v.map(f64::from))).collect::<Vec<_>>();
            let brute_force = (0..3)
                .map(|k| (q[(k + 1) % 3] - q[k]).angle_between(q[(k + 2) % 3] - q[k]).to_degrees())
                .fold(f64::INFINITY, f64::min);
            prop_assert!(close(a.min_angle_deg_min, brute_force, 1e-6));
        }
    }
}
