//! The sample array: field values at every lattice point, and how points are laid out.
//!
//! **Simple cubic** (also used by marching cubes): cube corners `(x, y, z)`, `0 <= x <= nx`
//! etc., stored at `x + (nx + 1) * (y + (ny + 1) * z)`, world position `min + (x, y, z) * h`.
//!
//! **Body-centred**: integer coordinates `(X, Y, Z)` in half-cube units with `X = Y = Z (mod 2)`;
//! even points are cube corners (`0 ..= 2n`), odd points cube centres (`-1 ..= 2n + 1`). The centres
//! at `-1` and `2n + 1` are *ghosts*: the centres of the cubes just outside the box, needed by the
//! tetrahedra of the box's outer faces. A ghost is placed (and sampled) on the box face itself, at the
//! face centre, so the tetrahedra fill exactly the box and the mesh is closed wherever the surface
//! stays inside it. Only ghosts outside exactly one face exist; the others are never read.
//!
//! ```text
//!   Z = -1     0      1      2     ...   (planes alternate: centres, corners, centres, ...)
//!       ghost  corner centre corner
//! ```
//!
//! Every plane has `(nx + 2) * (ny + 2)` slots; the point `(X, Y, Z)` sits at
//! `((Z + 1) * (ny + 2) + (Y + 1) / 2) * (nx + 2) + (X + 1) / 2` (integer division rounding down).
//! Unused slots hold NaN and are never read. World position: `min + clamp(X, 0, 2n) * h / 2`.

use glam::Vec3;
use rayon::prelude::*;

use crate::{ExtractError, ExtractSettings, Lattice, Method, Stats};

/// Field values on a lattice, plus the layout needed to find a point.
#[derive(Clone, Debug, Default)]
pub struct Samples {
    /// The lattice these values belong to (`Simple` for marching cubes).
    pub lattice: Option<Lattice>,
    /// Cells per axis of the grid.
    pub cells: [usize; 3],
    /// Lower corner of the box.
    pub min: Vec3,
    /// Cube edge length per axis.
    pub spacing: Vec3,
    /// Storage dimensions (slots per axis): `n + 1` per axis for the simple lattice; for the
    /// body-centred lattice `[nx + 2, ny + 2, 2 nz + 3]` (x and y slots, z planes).
    pub dims: [usize; 3],
    /// The values, `dims[0] * dims[1] * dims[2]` of them.
    pub values: Vec<f32>,
}

/// The lattice that a method samples: marching cubes uses the simple cubic corners.
pub fn sampled_lattice(settings: &ExtractSettings) -> Lattice {
    match settings.method {
        Method::Mc => Lattice::Simple,
        Method::Mt => settings.lattice,
    }
}

impl Samples {
    /// Sets the layout for `settings` and sizes `values` (keeping its allocation when it is large
    /// enough). Values are left as they were or NaN; fill them before use.
    pub fn prepare(&mut self, settings: &ExtractSettings) {
        let lattice = sampled_lattice(settings);
        let [nx, ny, nz] = settings.grid.cells;
        self.lattice = Some(lattice);
        self.cells = settings.grid.cells;
        self.min = settings.grid.min;
        self.spacing = settings.grid.spacing();
        self.dims = match lattice {
            Lattice::Simple => [nx + 1, ny + 1, nz + 1],
            Lattice::BodyCentred => [nx + 2, ny + 2, 2 * nz + 3],
        };
        let len = self.dims.iter().product();
        self.values.resize(len, f32::NAN);
    }

    /// Errors unless the layout matches `settings` (for pre-sampled extraction).
    pub fn check_layout(&self, settings: &ExtractSettings) -> Result<(), ExtractError> {
        let lattice = sampled_lattice(settings);
        if self.lattice != Some(lattice)
            || self.cells != settings.grid.cells
            || self.values.len() != self.dims.iter().product::<usize>()
        {
            return Err(ExtractError::InvalidSettings(
                "the sample array was prepared for other settings; call Samples::prepare first"
                    .into(),
            ));
        }
        Ok(())
    }

    /// Number of real sample points (unused body-centred slots excluded).
    pub fn point_count(&self) -> usize {
        let [nx, ny, nz] = self.cells;
        match self.lattice {
            None => 0,
            Some(Lattice::Simple) => (nx + 1) * (ny + 1) * (nz + 1),
            // corners + inner centres + one layer of ghost centres on each face.
            Some(Lattice::BodyCentred) => {
                (nx + 1) * (ny + 1) * (nz + 1) + nx * ny * nz + 2 * (nx * ny + ny * nz + nz * nx)
            }
        }
    }

    /// Bytes held by the values.
    pub fn bytes(&self) -> usize {
        self.values.len() * std::mem::size_of::<f32>()
    }

    /// Storage index of simple-lattice corner `(x, y, z)`.
    #[inline]
    pub fn simple_index(&self, x: usize, y: usize, z: usize) -> usize {
        x + self.dims[0] * (y + self.dims[1] * z)
    }

    /// Storage index of body-centred point `(X, Y, Z)` (half-cube units, see the module doc).
    #[inline]
    pub fn bcdl_index(&self, p: [i32; 3]) -> usize {
        let sx = ((p[0] + 1) >> 1) as usize;
        let sy = ((p[1] + 1) >> 1) as usize;
        let sz = (p[2] + 1) as usize;
        (sz * self.dims[1] + sy) * self.dims[0] + sx
    }

    /// Whether body-centred point `(X, Y, Z)` exists: a corner inside the box, a centre of a cube
    /// in the box, or a ghost centre outside exactly one face.
    #[inline]
    pub fn bcdl_exists(&self, p: [i32; 3]) -> bool {
        let odd = p[0] & 1;
        if (p[1] & 1) != odd || (p[2] & 1) != odd {
            return false;
        }
        let mut outside = 0;
        for (&c, &cells) in p.iter().zip(&self.cells) {
            let n2 = 2 * cells as i32;
            if c < -1 || c > n2 + 1 {
                return false;
            }
            if c < 0 || c > n2 {
                outside += 1;
            }
        }
        outside == 0 || (odd == 1 && outside == 1)
    }

    /// World position of body-centred point `(X, Y, Z)`; ghosts land on the box face.
    #[inline]
    pub fn bcdl_position(&self, p: [i32; 3]) -> Vec3 {
        let h = self.spacing * 0.5;
        let c = |a: usize| p[a].clamp(0, 2 * self.cells[a] as i32) as f32 * h[a];
        self.min + Vec3::new(c(0), c(1), c(2))
    }

    /// World position of simple-lattice corner `(x, y, z)`.
    #[inline]
    pub fn simple_position(&self, x: usize, y: usize, z: usize) -> Vec3 {
        self.min + Vec3::new(x as f32, y as f32, z as f32) * self.spacing
    }

    /// Samples `field` at every point for `settings`, on `pool`'s threads, one z-plane per task.
    /// Fails on the first non-finite value (the lowest storage index, whatever the thread count).
    pub fn sample(
        &mut self,
        field: &dyn ScalarField,
        settings: &ExtractSettings,
        pool: &rayon::ThreadPool,
        stats: &mut Stats,
    ) -> Result<(), ExtractError> {
        let t = std::time::Instant::now();
        self.prepare(settings);
        stats.t_allocation_s += t.elapsed().as_secs_f64();
        let t = std::time::Instant::now();
        let plane = self.dims[0] * self.dims[1];
        let mut values = std::mem::take(&mut self.values);
        let this = &*self;
        let bad = pool.install(|| {
            values
                .par_chunks_mut(plane)
                .enumerate()
                .map_init(Vec::new, |points: &mut Vec<Vec3>, (z, out)| {
                    this.sample_plane(field, z, out, points)
                })
                .find_first(|r| r.is_some())
                .flatten()
        });
        self.values = values;
        stats.t_sampling_s += t.elapsed().as_secs_f64();
        stats.sample_points = self.point_count();
        stats.bytes_lattice = self.bytes();
        match bad {
            Some((p, value)) => Err(ExtractError::NonFiniteSample {
                x: p.x,
                y: p.y,
                z: p.z,
                value,
            }),
            None => Ok(()),
        }
    }

    /// Fills one storage plane; returns the first non-finite sample.
    fn sample_plane(
        &self,
        field: &dyn ScalarField,
        z: usize,
        out: &mut [f32],
        points: &mut Vec<Vec3>,
    ) -> Option<(Vec3, f32)> {
        points.clear();
        let [dx, dy, _] = self.dims;
        // Slots that hold a real point, in storage order.
        let mut slots: Vec<usize> = Vec::new();
        match self.lattice {
            Some(Lattice::Simple) | None => {
                for y in 0..dy {
                    for x in 0..dx {
                        points.push(self.simple_position(x, y, z));
                    }
                }
            }
            Some(Lattice::BodyCentred) => {
                let zz = z as i32 - 1;
                let odd = zz & 1;
                for sy in 0..dy {
                    for sx in 0..dx {
                        let p = [2 * sx as i32 - odd, 2 * sy as i32 - odd, zz];
                        if self.bcdl_exists(p) {
                            slots.push(sy * dx + sx);
                            points.push(self.bcdl_position(p));
                        } else {
                            out[sy * dx + sx] = f32::NAN;
                        }
                    }
                }
            }
        }
        if slots.is_empty() && !matches!(self.lattice, Some(Lattice::BodyCentred)) {
            field.sample_batch(points, out);
            return out
                .iter()
                .zip(points.iter())
                .find(|(v, _)| !v.is_finite())
                .map(|(v, p)| (*p, *v));
        }
        let mut vals = vec![0.0f32; points.len()];
        field.sample_batch(points, &mut vals);
        for ((&s, &v), &p) in slots.iter().zip(&vals).zip(points.iter()) {
            if !v.is_finite() {
                return Some((p, v));
            }
            out[s] = v;
        }
        None
    }
}

use rmt_fields::ScalarField;
