//! Distance from points to a set of triangles: a uniform grid over the triangles' boxes,
//! searched in growing shells around the query point. Used to measure how far a surface moves
//! (the *pop* when a terrain chunk changes its level of detail).
//!
//! ```text
//!   build:  every triangle is listed in each grid cell its bounding box overlaps
//!           (cells of edge `cell`, at most MAX_CELLS_PER_AXIS per axis: larger boxes
//!           get larger cells)
//!   query:  ring r = 0, 1, 2, ... of cells around the point's cell (Chebyshev distance r);
//!           every triangle of the ring is measured exactly (closest point on a triangle);
//!           stop before ring r once the best distance is <= (r - 1) cells, the least
//!           distance any cell of ring r or beyond can have
//! ```
//!
//! Rules: distances are exact (up to `f32` rounding) whatever the cell size, which only changes
//! the speed; a point outside the grid is measured as well (its shells start at the nearest
//! cell); no triangles means no distance (`None`).

use glam::Vec3;

/// Cells per axis at most; a larger extent gets larger cells.
pub const MAX_CELLS_PER_AXIS: usize = 256;

/// Triangles bucketed in a uniform grid for nearest-distance queries (see the module doc).
pub struct TriangleGrid {
    triangles: Vec<[Vec3; 3]>,
    min: Vec3,
    cell: f32,
    dims: [usize; 3],
    /// CSR: the triangles of cell `c` are `items[starts[c]..starts[c + 1]]`.
    starts: Vec<u32>,
    items: Vec<u32>,
}

impl TriangleGrid {
    /// Buckets `triangles` in cells of about `cell` world units (grown if the extent would need
    /// more than [`MAX_CELLS_PER_AXIS`] per axis). Triangles with a non-finite corner are left
    /// out.
    pub fn new(triangles: impl IntoIterator<Item = [[f32; 3]; 3]>, cell: f32) -> Self {
        let triangles: Vec<[Vec3; 3]> = triangles
            .into_iter()
            .map(|t| t.map(Vec3::from))
            .filter(|t| t.iter().all(|p| p.is_finite()))
            .collect();
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for t in &triangles {
            for p in t {
                lo = lo.min(*p);
                hi = hi.max(*p);
            }
        }
        if triangles.is_empty() {
            return Self {
                triangles,
                min: Vec3::ZERO,
                cell: 1.0,
                dims: [1; 3],
                starts: vec![0, 0],
                items: Vec::new(),
            };
        }
        let extent = (hi - lo).max_element();
        let mut cell = if cell.is_finite() && cell > 0.0 {
            cell
        } else {
            extent.max(1e-6)
        };
        cell = cell.max(extent / MAX_CELLS_PER_AXIS as f32).max(1e-12);
        let dims =
            [0, 1, 2].map(|i| (((hi[i] - lo[i]) / cell) as usize + 1).min(MAX_CELLS_PER_AXIS));
        let index = |c: [usize; 3]| c[0] + dims[0] * (c[1] + dims[1] * c[2]);
        let cell_of = |p: Vec3| -> [usize; 3] {
            [0, 1, 2].map(|i| (((p[i] - lo[i]) / cell) as usize).min(dims[i] - 1))
        };
        let count = dims[0] * dims[1] * dims[2];
        let mut starts = vec![0u32; count + 1];
        let ranges: Vec<([usize; 3], [usize; 3])> = triangles
            .iter()
            .map(|t| {
                let a = cell_of(t[0].min(t[1]).min(t[2]));
                let b = cell_of(t[0].max(t[1]).max(t[2]));
                (a, b)
            })
            .collect();
        let each = |(a, b): ([usize; 3], [usize; 3]), f: &mut dyn FnMut(usize)| {
            for z in a[2]..=b[2] {
                for y in a[1]..=b[1] {
                    for x in a[0]..=b[0] {
                        f(index([x, y, z]));
                    }
                }
            }
        };
        for r in &ranges {
            each(*r, &mut |c| starts[c + 1] += 1);
        }
        for c in 0..count {
            starts[c + 1] += starts[c];
        }
        let mut fill = starts.clone();
        let mut items = vec![0u32; starts[count] as usize];
        for (t, r) in ranges.iter().enumerate() {
            each(*r, &mut |c| {
                items[fill[c] as usize] = t as u32;
                fill[c] += 1;
            });
        }
        Self {
            triangles,
            min: lo,
            cell,
            dims,
            starts,
            items,
        }
    }

    /// Number of triangles held.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// Whether no triangle is held.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// Distance from `p` to the nearest triangle; `None` without triangles or for a non-finite
    /// point.
    pub fn distance(&self, p: [f32; 3]) -> Option<f32> {
        let p = Vec3::from(p);
        if self.triangles.is_empty() || !p.is_finite() {
            return None;
        }
        let d = self.dims;
        // The point's cell, clamped into the grid (a point outside only moves away from the
        // cells, so the ring bound below still holds).
        let rel = (p - self.min) / self.cell;
        let home = [0, 1, 2].map(|i| (rel[i].max(0.0) as usize).min(d[i] - 1));
        let mut best = f32::INFINITY;
        let max_ring = d[0].max(d[1]).max(d[2]);
        for r in 0..=max_ring {
            // Every cell of ring r (and beyond) differs from the home cell by r along some
            // axis, so it is at least (r - 1) cells from the point along that axis.
            let bound = (r as f32 - 1.0).max(0.0) * self.cell;
            if r > 0 && best <= bound {
                break;
            }
            let lo = home.map(|h| h.saturating_sub(r));
            let hi = [0, 1, 2].map(|i| (home[i] + r).min(d[i] - 1));
            for z in lo[2]..=hi[2] {
                for y in lo[1]..=hi[1] {
                    // Inside the ring's cube on y and z: only its two x faces belong to ring r.
                    let inner = z.abs_diff(home[2]) < r && y.abs_diff(home[1]) < r;
                    let xs: [Option<usize>; 2] = if inner {
                        [
                            home[0].checked_sub(r),
                            Some(home[0] + r).filter(|&x| x < d[0]),
                        ]
                    } else {
                        [None, None]
                    };
                    let mut visit = |x: usize| {
                        let c = x + d[0] * (y + d[1] * z);
                        for &t in &self.items[self.starts[c] as usize..self.starts[c + 1] as usize]
                        {
                            let [a, b, cc] = self.triangles[t as usize];
                            best = best.min(point_triangle_distance(p, a, b, cc));
                        }
                    };
                    if inner {
                        xs.into_iter().flatten().for_each(&mut visit);
                    } else {
                        (lo[0]..=hi[0]).for_each(&mut visit);
                    }
                }
            }
        }
        Some(best)
    }
}

/// The largest and the mean distance from `points` to the triangles of `grid` (one side of a
/// Hausdorff distance); `None` without points or triangles.
pub fn one_sided(points: &[[f32; 3]], grid: &TriangleGrid) -> Option<(f32, f32)> {
    let mut max = 0.0f32;
    let mut sum = 0.0f64;
    let mut n = 0usize;
    for p in points {
        if let Some(d) = grid.distance(*p) {
            max = max.max(d);
            sum += f64::from(d);
            n += 1;
        }
    }
    (n > 0).then(|| (max, (sum / n as f64) as f32))
}

/// Distance from `p` to triangle `abc` (the closest point by Voronoi regions, as in Ericson,
/// *Real-Time Collision Detection*, 5.1.5); a degenerate triangle is measured as its edges.
pub fn point_triangle_distance(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> f32 {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return ap.length();
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return bp.length();
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (p - (a + ab * v)).length();
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return cp.length();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (p - (a + ac * w)).length();
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (p - (b + (c - b) * w)).length();
    }
    let denom = va + vb + vc;
    if denom.abs() <= f32::MIN_POSITIVE {
        // Degenerate (collinear) triangle: the nearest of its three edges.
        let seg = |s: Vec3, e: Vec3| {
            let d = e - s;
            let t = if d.length_squared() > 0.0 {
                ((p - s).dot(d) / d.length_squared()).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (p - (s + d * t)).length()
        };
        return seg(a, b).min(seg(b, c)).min(seg(c, a));
    }
    let v = vb / denom;
    let w = vc / denom;
    (p - (a + ab * v + ac * w)).length()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute(p: [f32; 3], tris: &[[[f32; 3]; 3]]) -> f32 {
        tris.iter()
            .map(|t| point_triangle_distance(Vec3::from(p), t[0].into(), t[1].into(), t[2].into()))
            .fold(f32::INFINITY, f32::min)
    }

    #[test]
    fn distances_to_one_triangle_by_region() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        let d = |p: Vec3| point_triangle_distance(p, a, b, c);
        assert!((d(Vec3::new(0.2, 0.2, 3.0)) - 3.0).abs() < 1e-6); // face
        assert!((d(Vec3::new(-1.0, -1.0, 0.0)) - 2f32.sqrt()).abs() < 1e-6); // vertex a
        assert!((d(Vec3::new(0.5, -2.0, 0.0)) - 2.0).abs() < 1e-6); // edge ab
        assert!((d(Vec3::new(1.0, 1.0, 0.0)) - 0.5f32.sqrt()).abs() < 1e-6); // edge bc
        assert!((d(Vec3::new(3.0, 0.0, 4.0)) - (4.0f32 + 16.0).sqrt()).abs() < 1e-6); // vertex b
                                                                                      // A degenerate triangle is its segment.
        let flat =
            point_triangle_distance(Vec3::new(0.5, 1.0, 0.0), a, b, Vec3::new(2.0, 0.0, 0.0));
        assert!((flat - 1.0).abs() < 1e-6, "{flat}");
    }

    /// The grid gives the brute-force distance for points inside, near and far outside the
    /// triangles' box, whatever the cell size.
    #[test]
    fn the_grid_matches_brute_force() {
        let mut s = 12345u64;
        let mut rnd = move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 33) as f32 / (1u64 << 31) as f32) * 2.0 - 1.0
        };
        let tris: Vec<[[f32; 3]; 3]> = (0..300)
            .map(|_| {
                let c = [rnd() * 4.0, rnd(), rnd() * 4.0];
                [0, 1, 2].map(|_| [c[0] + rnd() * 0.2, c[1] + rnd() * 0.2, c[2] + rnd() * 0.2])
            })
            .collect();
        for cell in [0.05, 0.3, 2.0, 100.0] {
            let grid = TriangleGrid::new(tris.iter().copied(), cell);
            assert_eq!(grid.len(), 300);
            for _ in 0..200 {
                let scale = if rnd() > 0.0 { 5.0 } else { 30.0 };
                let p = [rnd() * scale, rnd() * scale, rnd() * scale];
                let (g, b) = (grid.distance(p).unwrap(), brute(p, &tris));
                assert!(
                    (g - b).abs() <= 1e-5 * b.max(1.0),
                    "cell {cell}: {p:?} grid {g} brute {b}"
                );
            }
        }
    }

    #[test]
    fn empty_and_non_finite_inputs_give_no_distance() {
        let grid = TriangleGrid::new(std::iter::empty(), 1.0);
        assert!(grid.is_empty() && grid.distance([0.0; 3]).is_none());
        let grid = TriangleGrid::new([[[0.0; 3], [1.0, 0.0, 0.0], [f32::NAN, 0.0, 0.0]]], 1.0);
        assert!(grid.is_empty());
        let grid = TriangleGrid::new([[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]], 1.0);
        assert!(grid.distance([f32::NAN, 0.0, 0.0]).is_none());
        assert_eq!(one_sided(&[], &grid), None);
        let (max, mean) = one_sided(&[[0.2, 0.2, 1.0], [0.2, 0.2, 3.0]], &grid).unwrap();
        assert!((max - 3.0).abs() < 1e-6 && (mean - 2.0).abs() < 1e-6);
    }
}
