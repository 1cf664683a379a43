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
//!
//! **Sparse sampling** ([`Sampling::Sparse`], what [`crate::Extractor`] does by default): the
//! storage is cut into blocks of [`BLOCK`] cells per axis (`BLOCK` slots along x and y, `BLOCK`
//! storage planes along z, or `2 BLOCK` planes on the body-centred lattice, where each cell has
//! a centre plane and a corner plane). For each block the field is asked, through
//! [`ScalarField::side`] (by default from its [`ScalarField::range`]), whether it stays on one
//! side of `T` over the box of the block's points *and of all their lattice neighbours* (one
//! cell of margin: every neighbour of a point, on either lattice, and every corner of a
//! marching cube through it, is at most one cell away per axis; ghosts are taken at their
//! clamped positions). When it does, the block is not evaluated: its points get the placeholder
//! that `side` returns, on the known side (an end of the field's bound: `hi < T` inside,
//! `lo >= T` outside).
//! A block whose side is not known is split once into 8 sub-blocks of `BLOCK / 2`
//! cells per axis, each tested (with its own one-cell margin) and skipped or evaluated alone.
//!
//! Why the meshes are unchanged (byte for byte): (1) every stored value has the same side of
//! `T` as the true value (a skipped point's true value is within its block's bound), so the inside
//! bits, crossed edges, case indices and clustering masks are the same; (2) a crossed edge never
//! touches a skipped point: its other end lies in the skipped block's margin box, so its true
//! value is on the same side, and the edge would not be crossed; likewise every corner of a
//! crossed cube (marching cubes) is evaluated. The extractors read values (interpolation,
//! ownership of a crossing, the asymptotic decider) only at the ends of crossed edges and at
//! the corners of crossed cubes, and signs everywhere else, so they read true values wherever
//! the value matters. Positions are computed by the same functions as dense sampling, so the
//! evaluated values are the same too. A non-finite value inside a skipped block is not seen
//! (the field's range promised finite values there).
//!
//! The points left to evaluate are not evaluated block by block: each band of blocks (the
//! blocks sharing a range of y slots in a slab) hands its row segments to one pass that groups
//! them by storage row (a counting sort) and joins neighbours, so a row crossing several
//! evaluated blocks is one run of points with equal `y` and `z`, and the runs of neighbouring
//! rows of a plane with the same slots reach [`ScalarField::sample_rows`] together (by default
//! one [`ScalarField::sample_row`] per run). Fields that share work along rows (the asteroid's
//! noise) are faster on long runs, a height field computes each column's height once,
//! and since a field's value at a point does not depend on its batch, no value changes.

use glam::Vec3;
use rayon::prelude::*;

use crate::{Boundary, ExtractError, ExtractSettings, Lattice, Method, Stats};

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
    pub values: SampleValues,
    /// How the body-centred lattice closes the box: with [`Boundary::Pyramids`] the ghosts
    /// do not exist (their slots hold NaN and are never read).
    pub boundary: Boundary,
}

/// The values of a [`Samples`], one per storage slot: the sample array's own buffer, or, for
/// the one call of [`crate::Extractor::extract_borrowed`], the caller's slice read in place (no
/// copy). Both dereference to `[f32]`, so readers index it as a slice; writing to a borrowed
/// one ([`SampleValues::to_mut`], or any `&mut` access) copies it into a buffer of its own first,
/// as [`std::borrow::Cow::to_mut`] does, so the caller's values are never written.
pub struct SampleValues(Repr);

enum Repr {
    Owned(Vec<f32>),
    /// A caller's `&[f32]` whose lifetime is not in the type: only
    /// [`crate::Extractor::extract_borrowed`] makes one (with [`SampleValues::borrow`]) and
    /// takes it out of the extractor before that borrow ends.
    Borrowed(std::ptr::NonNull<f32>, usize),
}

// SAFETY: a `Borrowed` is a shared borrow of `[f32]` (which is `Send` and `Sync`), read only,
// and valid while it exists (see `SampleValues::borrow`); an `Owned` is a `Vec<f32>`.
unsafe impl Send for SampleValues {}
// SAFETY: as for `Send`: nothing writes through a `Borrowed`.
unsafe impl Sync for SampleValues {}

impl SampleValues {
    /// The values of `values`, read in place.
    ///
    /// # Safety
    ///
    /// The result (and every `&[f32]` taken from it) must not be used after the borrow of
    /// `values` ends: the caller drops it or replaces it before then, also when a panic unwinds.
    pub(crate) unsafe fn borrow(values: &[f32]) -> Self {
        Self(Repr::Borrowed(
            std::ptr::NonNull::from(values).cast(),
            values.len(),
        ))
    }

    /// Whether these are a caller's values read in place (during
    /// [`crate::Extractor::extract_borrowed`]).
    pub fn is_borrowed(&self) -> bool {
        matches!(self.0, Repr::Borrowed(..))
    }

    /// The values as a buffer of their own, copied first when they are borrowed.
    pub fn to_mut(&mut self) -> &mut Vec<f32> {
        if let Repr::Borrowed(..) = self.0 {
            self.0 = Repr::Owned(self.to_vec());
        }
        match &mut self.0 {
            Repr::Owned(v) => v,
            Repr::Borrowed(..) => unreachable!("made owned above"),
        }
    }

    /// Resizes the buffer to `len` values, new ones `value` (as [`Vec::resize`]).
    pub fn resize(&mut self, len: usize, value: f32) {
        self.to_mut().resize(len, value);
    }

    /// The values as a vector (moved out when owned, copied when borrowed).
    pub fn into_vec(self) -> Vec<f32> {
        match self.0 {
            Repr::Owned(v) => v,
            Repr::Borrowed(..) => self.to_vec(),
        }
    }
}

impl std::ops::Deref for SampleValues {
    type Target = [f32];

    #[inline]
    fn deref(&self) -> &[f32] {
        match &self.0 {
            Repr::Owned(v) => v,
            // SAFETY: made from a `&[f32]` that outlives `self` (see `SampleValues::borrow`).
            Repr::Borrowed(ptr, len) => unsafe { std::slice::from_raw_parts(ptr.as_ptr(), *len) },
        }
    }
}

impl std::ops::DerefMut for SampleValues {
    #[inline]
    fn deref_mut(&mut self) -> &mut [f32] {
        self.to_mut()
    }
}

impl Default for SampleValues {
    fn default() -> Self {
        Self(Repr::Owned(Vec::new()))
    }
}

/// A clone owns its values (a borrowed one is copied).
impl Clone for SampleValues {
    fn clone(&self) -> Self {
        Self(Repr::Owned(self.to_vec()))
    }
}

impl std::fmt::Debug for SampleValues {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.iter()).finish()
    }
}

impl PartialEq for SampleValues {
    fn eq(&self, other: &Self) -> bool {
        self[..] == other[..]
    }
}

impl From<Vec<f32>> for SampleValues {
    fn from(values: Vec<f32>) -> Self {
        Self(Repr::Owned(values))
    }
}

impl<'a> IntoIterator for &'a SampleValues {
    type Item = &'a f32;
    type IntoIter = std::slice::Iter<'a, f32>;

    fn into_iter(self) -> Self::IntoIter {
        self.iter()
    }
}

/// Cells per axis of a block of sparse sampling.
pub const BLOCK: usize = 8;

/// How the field is sampled (see the module doc).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Sampling {
    /// Evaluate the field at every lattice point: every stored value is the field's value
    /// (what edits of stored values, e.g. terrain brushes, and peers fed our samples need).
    Dense,
    /// Skip blocks whose [`ScalarField::range`] excludes the isovalue; their points hold a
    /// placeholder on the right side. Same meshes as dense sampling; fields without a range
    /// are sampled densely (block by block).
    #[default]
    Sparse,
}

/// The lattice that a method samples: marching cubes and surface nets use the simple cubic
/// corners.
pub fn sampled_lattice(settings: &ExtractSettings) -> Lattice {
    match settings.method {
        Method::Mc | Method::SurfaceNets => Lattice::Simple,
        Method::Mt => settings.lattice,
    }
}

impl Samples {
    /// Sets the layout for `settings` and sizes `values` (keeping its allocation when it is large
    /// enough). Values are left as they were or NaN; fill them before use.
    pub fn prepare(&mut self, settings: &ExtractSettings) {
        self.set_layout(settings);
        let len = self.dims.iter().product();
        self.values.resize(len, f32::NAN);
    }

    /// Sets the layout for `settings` (lattice, cells, box, storage dimensions) and leaves the
    /// values alone.
    fn set_layout(&mut self, settings: &ExtractSettings) {
        let lattice = sampled_lattice(settings);
        let [nx, ny, nz] = settings.grid.cells;
        self.lattice = Some(lattice);
        self.boundary = match lattice {
            Lattice::BodyCentred => settings.boundary,
            Lattice::Simple => Boundary::Ghosts,
        };
        self.cells = settings.grid.cells;
        self.min = settings.grid.min;
        self.spacing = settings.grid.spacing();
        self.dims = match lattice {
            Lattice::Simple => [nx + 1, ny + 1, nz + 1],
            Lattice::BodyCentred => [nx + 2, ny + 2, 2 * nz + 3],
        };
    }

    /// The layout for `settings` over the caller's `values`, read in place: the values of the
    /// slots as [`Samples::prepare`] lays them out (on the simple lattice, and for marching
    /// cubes and surface nets, corner `(x, y, z)` at `x + (nx + 1) * (y + (ny + 1) * z)`: a
    /// C-ordered `(z, y, x)` array). Errors when `values` has another length.
    ///
    /// # Safety
    ///
    /// As [`SampleValues::borrow`]: the result must not be used after the borrow of `values`
    /// ends.
    pub(crate) unsafe fn borrowing(
        values: &[f32],
        settings: &ExtractSettings,
    ) -> Result<Self, ExtractError> {
        let mut s = Samples::default();
        s.set_layout(settings);
        let len: usize = s.dims.iter().product();
        if values.len() != len {
            return Err(ExtractError::InvalidSettings(format!(
                "{} values given for a sample array of {:?} slots ({len}) on the {:?} lattice",
                values.len(),
                s.dims,
                sampled_lattice(settings)
            )));
        }
        // SAFETY: passed on to the caller.
        s.values = unsafe { SampleValues::borrow(values) };
        Ok(s)
    }

    /// Sets the layout for `settings` (as [`Samples::prepare`]) and fills it with the values of
    /// `whole` for the box of `settings.grid.cells` cells whose corner is cell `s0` of `whole`:
    /// a chunk's input, cut from a larger sampled volume with no value computed again. Storage
    /// slots shift by `s0` per axis, and body-centred storage planes by `2 s0` (every lattice
    /// point of the box keeps its value). Errors when `whole` is not sampled on the same lattice
    /// or does not hold the box.
    pub fn copy_box(
        &mut self,
        whole: &Samples,
        settings: &ExtractSettings,
        s0: [usize; 3],
    ) -> Result<(), ExtractError> {
        let lattice = sampled_lattice(settings);
        let cells = settings.grid.cells;
        if whole.lattice != Some(lattice)
            || (0..3).any(|a| s0[a].saturating_add(cells[a]) > whole.cells[a])
            || whole.values.len() != whole.dims.iter().product::<usize>()
        {
            return Err(ExtractError::InvalidSettings(format!(
                "a box of {cells:?} cells at cell {s0:?} is not inside the {:?} cells of the \
                 sampled volume on the {lattice:?} lattice",
                whole.cells
            )));
        }
        self.prepare(settings);
        let (wd, ld) = (whole.dims, self.dims);
        let zoff = match lattice {
            Lattice::BodyCentred => 2 * s0[2],
            Lattice::Simple => s0[2],
        };
        for z in 0..ld[2] {
            for y in 0..ld[1] {
                let src = ((z + zoff) * wd[1] + y + s0[1]) * wd[0] + s0[0];
                let at = (z * ld[1] + y) * ld[0];
                self.values[at..at + ld[0]].copy_from_slice(&whole.values[src..src + ld[0]]);
            }
        }
        Ok(())
    }

    /// Errors unless the layout matches `settings` (for pre-sampled extraction).
    pub fn check_layout(&self, settings: &ExtractSettings) -> Result<(), ExtractError> {
        let lattice = sampled_lattice(settings);
        let boundary = match lattice {
            Lattice::BodyCentred => settings.boundary,
            Lattice::Simple => Boundary::Ghosts,
        };
        if self.lattice != Some(lattice)
            || self.cells != settings.grid.cells
            || self.boundary != boundary
            || self.values.len() != self.dims.iter().product::<usize>()
        {
            return Err(ExtractError::InvalidSettings(
                "the sample array was prepared for other settings; call Samples::prepare first"
                    .into(),
            ));
        }
        Ok(())
    }

    /// The error for the first non-finite value of a simple-lattice sample array, for a pass
    /// that found one (its own check is per plane or per block; this search, in storage order,
    /// runs only then). `None` when every value is finite.
    pub(crate) fn non_finite_error(&self) -> Option<ExtractError> {
        let slot = self.values.iter().position(|v| !v.is_finite())?;
        let [dx, dy, _] = self.dims;
        Some(ExtractError::NonFiniteValue {
            slot,
            point: [slot % dx, (slot / dx) % dy, slot / (dx * dy)],
            value: self.values[slot],
        })
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
    /// in the box, or a ghost centre outside exactly one face (with [`Boundary::Ghosts`]).
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
        outside == 0 || (odd == 1 && outside == 1 && self.boundary == Boundary::Ghosts)
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
        stats.points_sampled = stats.sample_points;
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

    /// Samples `field` for `settings` as `sampling` says: [`Samples::sample`] for
    /// [`Sampling::Dense`], else block-sparse sampling (see the module doc). Fills
    /// `stats.points_sampled`, `stats.blocks` and `stats.blocks_skipped`.
    pub fn sample_with(
        &mut self,
        field: &dyn ScalarField,
        settings: &ExtractSettings,
        pool: &rayon::ThreadPool,
        stats: &mut Stats,
        sampling: Sampling,
    ) -> Result<(), ExtractError> {
        if sampling == Sampling::Dense {
            return self.sample(field, settings, pool, stats);
        }
        let t = std::time::Instant::now();
        self.prepare(settings);
        stats.t_allocation_s += t.elapsed().as_secs_f64();
        let t = std::time::Instant::now();
        let [dx, dy, _] = self.dims;
        let slab = dx * dy * self.block_planes();
        let iso = settings.iso;
        let mut values = std::mem::take(&mut self.values);
        let this = &*self;
        let slabs: Vec<SlabResult> = pool.install(|| {
            values
                .par_chunks_mut(slab)
                .enumerate()
                .map_init(Scratch::default, |scratch, (j, out)| {
                    this.sample_slab(field, iso, j, out, scratch)
                })
                .collect()
        });
        self.values = values;
        stats.t_sampling_s += t.elapsed().as_secs_f64();
        stats.sample_points = self.point_count();
        stats.bytes_lattice = self.bytes();
        stats.points_sampled = slabs.iter().map(|r| r.evaluated).sum();
        stats.blocks = slabs.iter().map(|r| r.blocks).sum();
        stats.blocks_skipped = slabs.iter().map(|r| r.skipped).sum();
        // Slabs are consecutive in storage and each reports its lowest bad index: the first
        // slab with one holds the lowest overall, whatever the thread count.
        match slabs.iter().find_map(|r| r.bad) {
            Some((_, p, value)) => Err(ExtractError::NonFiniteSample {
                x: p.x,
                y: p.y,
                z: p.z,
                value,
            }),
            None => Ok(()),
        }
    }

    /// Storage planes per block along z.
    fn block_planes(&self) -> usize {
        match self.lattice {
            Some(Lattice::BodyCentred) => 2 * BLOCK,
            _ => BLOCK,
        }
    }

    /// The slots `[lo, hi)` of storage row `y` of plane `z` that hold a real point (they are
    /// contiguous on both lattices).
    #[inline]
    pub fn row_span(&self, y: usize, z: usize) -> (usize, usize) {
        let [dx, _, _] = self.dims;
        match self.lattice {
            Some(Lattice::BodyCentred) => {
                let [nx, ny, nz] = self.cells;
                if z % 2 == 1 {
                    // Corner plane (Z = z - 1 even): corners with X, Y in 0 ..= 2n.
                    if y <= ny {
                        (0, nx + 1)
                    } else {
                        (0, 0)
                    }
                } else {
                    // Centre plane: at most one of the three coordinates may be a ghost's
                    // (none without ghosts).
                    let outside =
                        usize::from(y == 0 || y == ny + 1) + usize::from(z == 0 || z == 2 * nz + 2);
                    match (outside, self.boundary) {
                        (0, Boundary::Ghosts) => (0, dx),
                        (0, Boundary::Pyramids) => (1, nx + 1),
                        (1, Boundary::Ghosts) => (1, nx + 1),
                        _ => (0, 0),
                    }
                }
            }
            _ => (0, dx),
        }
    }

    /// The box of the points of the block with slots `x`, `y` and planes `z` (half-open ranges)
    /// and of all their lattice neighbours, from the same position functions as the samples
    /// (positions grow with the index, so the extreme indices give the extreme positions).
    fn block_box(&self, x: [usize; 2], y: [usize; 2], z: [usize; 2]) -> (Vec3, Vec3) {
        match self.lattice {
            Some(Lattice::BodyCentred) => {
                // Slot s holds X = 2 s - 1 (centres) and 2 s (corners); plane z holds Z = z - 1.
                // Neighbours are at most 2 half-cells away per axis.
                let lo = |s: usize| 2 * s as i32 - 3;
                let hi = |s: usize| 2 * s as i32;
                (
                    self.bcdl_position([lo(x[0]), lo(y[0]), z[0] as i32 - 3]),
                    self.bcdl_position([hi(x[1]), hi(y[1]), z[1] as i32]),
                )
            }
            _ => {
                let [nx, ny, nz] = self.cells;
                (
                    self.simple_position(
                        x[0].saturating_sub(1),
                        y[0].saturating_sub(1),
                        z[0].saturating_sub(1),
                    ),
                    self.simple_position(x[1].min(nx), y[1].min(ny), z[1].min(nz)),
                )
            }
        }
    }

    /// World position of the point in slot `(sx, sy)` of storage plane `z`.
    #[inline]
    fn slot_position(&self, sx: usize, sy: usize, z: usize) -> Vec3 {
        match self.lattice {
            Some(Lattice::BodyCentred) => {
                let zz = z as i32 - 1;
                let odd = zz & 1;
                self.bcdl_position([2 * sx as i32 - odd, 2 * sy as i32 - odd, zz])
            }
            _ => self.simple_position(sx, sy, z),
        }
    }

    /// Samples the blocks of slab `j` (storage planes `j * block_planes ..`) into `out`.
    fn sample_slab(
        &self,
        field: &dyn ScalarField,
        iso: f32,
        j: usize,
        out: &mut [f32],
        scratch: &mut Scratch,
    ) -> SlabResult {
        let [dx, dy, _] = self.dims;
        let plane = dx * dy;
        let z0 = j * self.block_planes();
        let planes = out.len() / plane;
        let mut result = SlabResult::default();
        let mut slab = Slab {
            z0,
            out,
            scratch,
            result: &mut result,
        };
        for y0 in (0..dy).step_by(BLOCK) {
            let y1 = (y0 + BLOCK).min(dy);
            for x0 in (0..dx).step_by(BLOCK) {
                let x1 = (x0 + BLOCK).min(dx);
                slab.result.blocks += self.leaves([x0, x1], [y0, y1], [0, planes]);
                let block = [[x0, x1], [y0, y1], [0, planes]];
                self.sample_block(field, iso, block, true, &mut slab);
            }
            // The band of rows y0..y1 is done: evaluate what its blocks left.
            self.evaluate_runs(field, &mut slab);
        }
        result
    }

    /// Evaluates the row segments that a band of blocks left to evaluate, as runs along
    /// storage rows: segments grouped by row (in order within a row), neighbours joined, so that a row
    /// crossing several evaluated blocks is one run of points with the same `y` and `z`; runs
    /// of neighbouring rows with the same slots go together to [`ScalarField::sample_rows`].
    /// Row-aware fields (the asteroid's noise) evaluate a run faster, a height field (the
    /// Svoboda terrain) computes its heights once for the rows. A point's value does not
    /// depend on how points are grouped, so this changes no value.
    fn evaluate_runs(&self, field: &dyn ScalarField, slab: &mut Slab<'_>) {
        let [dx, dy, _] = self.dims;
        let plane = dx * dy;
        let z0 = slab.z0;
        let scratch = &mut *slab.scratch;
        // Group the segments by row with a counting sort over the band's rows (`BLOCK` rows
        // per plane): stable, and within a row the segments arrive in increasing order (blocks
        // and leaves go along x), so each row's segments end up in order.
        let rows = slab.out.len() / plane * BLOCK;
        scratch.counts.clear();
        scratch.counts.resize(rows + 1, 0);
        for &(key, _, _, _) in &scratch.segments {
            scratch.counts[key + 1] += 1;
        }
        for k in 1..=rows {
            scratch.counts[k] += scratch.counts[k - 1];
        }
        scratch.sorted.clear();
        scratch.sorted.resize(scratch.segments.len(), (0, 0, 0, 0));
        for &seg in &scratch.segments {
            scratch.sorted[scratch.counts[seg.0]] = seg;
            scratch.counts[seg.0] += 1;
        }
        std::mem::swap(&mut scratch.segments, &mut scratch.sorted);
        // The rows' runs, each joined from its segments: (plane in the slab, y, first slot, end).
        scratch.runs.clear();
        let mut i = 0;
        while i < scratch.segments.len() {
            let (key, y, a, mut b) = scratch.segments[i];
            i += 1;
            while i < scratch.segments.len()
                && scratch.segments[i].0 == key
                && scratch.segments[i].2 == b
            {
                b = scratch.segments[i].3;
                i += 1;
            }
            scratch.runs.push((key / BLOCK, y, a, b));
        }
        // Runs of neighbouring rows of one plane with the same slots share their x coordinates
        // (and z): they go to the field together ([`ScalarField::sample_rows`]; a height field
        // computes its heights once for them).
        let mut j = 0;
        while j < scratch.runs.len() {
            let (zl, y0, a, b) = scratch.runs[j];
            let mut rows = 1;
            while j + rows < scratch.runs.len() && scratch.runs[j + rows] == (zl, y0 + rows, a, b) {
                rows += 1;
            }
            j += rows;
            // The same position function as dense sampling gives every coordinate.
            let z = z0 + zl;
            let first = self.slot_position(a, y0, z);
            scratch.xs.clear();
            scratch
                .xs
                .extend((a..b).map(|x| self.slot_position(x, y0, z).x));
            scratch.ys.clear();
            scratch
                .ys
                .extend((y0..y0 + rows).map(|y| self.slot_position(a, y, z).y));
            let n = b - a;
            // The rows' slots, `dx` apart in the slab.
            let row0 = zl * plane + y0 * dx;
            let out = &mut slab.out[row0 + a..row0 + (rows - 1) * dx + b];
            field.sample_rows(&scratch.xs, &scratch.ys, first.z, out, dx);
            slab.result.evaluated += rows * n;
            for r in 0..rows {
                let vals = &out[r * dx..r * dx + n];
                if let Some(k) = vals.iter().position(|v| !v.is_finite()) {
                    let s = row0 + r * dx + a + k;
                    if slab.result.bad.is_none_or(|(bs, _, _)| s < bs) {
                        let p = self.slot_position(a + k, y0 + r, z);
                        slab.result.bad = Some((s, p, vals[k]));
                    }
                }
            }
        }
        scratch.segments.clear();
    }

    /// Sub-blocks (of `BLOCK / 2` cells per axis) in the block of slots `x`, `y`, planes `z`.
    fn leaves(&self, x: [usize; 2], y: [usize; 2], z: [usize; 2]) -> usize {
        let (s, p) = (BLOCK / 2, self.block_planes() / 2);
        (x[1] - x[0]).div_ceil(s) * (y[1] - y[0]).div_ceil(s) * (z[1] - z[0]).div_ceil(p)
    }

    /// Samples the block `[x, y, z]` of slots `x`, `y` and planes `z` (local to the slab):
    /// skipped when its range excludes the isovalue, else split once into sub-blocks of half
    /// the size (when `split`), else evaluated.
    fn sample_block(
        &self,
        field: &dyn ScalarField,
        iso: f32,
        block: [[usize; 2]; 3],
        split: bool,
        slab: &mut Slab<'_>,
    ) {
        let [x, y, z] = block;
        let [dx, dy, _] = self.dims;
        let plane = dx * dy;
        let z0 = slab.z0;
        let (lo, hi) = self.block_box(x, y, [z0 + z[0], z0 + z[1]]);
        // The side of the whole block, when its range excludes the isovalue: a placeholder no
        // closer to iso than any true value there.
        let known = field.side(lo, hi, iso);
        let (x0, x1) = (x[0], x[1]);
        // Each row of the block: its real points `a..b`, unused slots (NaN, as dense sampling
        // leaves them) on either side.
        let rows = (z[0]..z[1]).flat_map(|z| (y[0]..y[1]).map(move |y| (y, z)));
        let rows = rows.map(|(y, z)| {
            let (s0, s1) = self.row_span(y, z0 + z);
            let a = s0.clamp(x0, x1);
            let b = s1.clamp(a, x1);
            (y, z, z * plane + y * dx, a, b)
        });
        let out = &mut *slab.out;
        if let Some(v) = known {
            slab.result.skipped += self.leaves(x, y, z);
            for (_, _, row, a, b) in rows {
                out[row + x0..row + a].fill(f32::NAN);
                out[row + a..row + b].fill(v);
                out[row + b..row + x1].fill(f32::NAN);
            }
            return;
        }
        if split {
            let (s, p) = (BLOCK / 2, self.block_planes() / 2);
            for zz in (z[0]..z[1]).step_by(p) {
                for yy in (y[0]..y[1]).step_by(s) {
                    for xx in (x0..x1).step_by(s) {
                        let block = [
                            [xx, (xx + s).min(x1)],
                            [yy, (yy + s).min(y[1])],
                            [zz, (zz + p).min(z[1])],
                        ];
                        self.sample_block(field, iso, block, false, slab);
                    }
                }
            }
            return;
        }
        // Evaluated at the end of the slab, in runs along rows (see `evaluate_runs`).
        for (y, z, row, a, b) in rows {
            out[row + x0..row + a].fill(f32::NAN);
            out[row + b..row + x1].fill(f32::NAN);
            if a < b {
                // Blocks start at multiples of `BLOCK` along y: the row's place in its band.
                slab.scratch.segments.push((z * BLOCK + y % BLOCK, y, a, b));
            }
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

/// Per-thread working memory of sparse sampling (reused across blocks).
#[derive(Default)]
struct Scratch {
    /// Row segments left to evaluate in the current band of rows: (the row's index in the band,
    /// `z * BLOCK + y % BLOCK` with `z` local to the slab; `y`; first slot; end).
    segments: Vec<(usize, usize, usize, usize)>,
    /// The segments grouped by row, and the counting sort's counters.
    sorted: Vec<(usize, usize, usize, usize)>,
    counts: Vec<usize>,
    /// The band's runs: (plane in the slab, y, first slot, end).
    runs: Vec<(usize, usize, usize, usize)>,
    /// The `x` coordinates of the rows being evaluated, and their `y` coordinates.
    xs: Vec<f32>,
    ys: Vec<f32>,
}

/// One slab's output and working memory, passed down the blocks.
struct Slab<'a> {
    /// First storage plane of the slab.
    z0: usize,
    out: &'a mut [f32],
    scratch: &'a mut Scratch,
    result: &'a mut SlabResult,
}

/// What one slab of blocks did.
#[derive(Default)]
struct SlabResult {
    /// Points evaluated.
    evaluated: usize,
    /// Sub-blocks visited and skipped.
    blocks: usize,
    skipped: usize,
    /// The non-finite value at the lowest slot of the slab: (slot, position, value).
    bad: Option<(usize, Vec3, f32)>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Clustering, Grid};

    #[test]
    fn the_first_pass_of_every_simple_lattice_method_reports_the_first_non_finite_value() {
        // A sphere on an anisotropic grid (rows of 70 points: a full word and a partial one),
        // bad values planted early, in the middle, last, and two at once; marching cubes,
        // surface nets, plain and integrated MT, on 1 and 2 threads, in place and copied.
        let cells = [69, 12, 9];
        let grid = Grid::new(cells, Vec3::splat(-1.0), Vec3::splat(1.0));
        let mut sphere = Samples::default();
        let dense = ExtractSettings::new(grid, Lattice::Simple, Clustering::None);
        sphere.prepare(&dense);
        let field = rmt_fields::Sphere::new(Vec3::ZERO, 0.6);
        for z in 0..=cells[2] {
            for y in 0..=cells[1] {
                for x in 0..=cells[0] {
                    let i = sphere.simple_index(x, y, z);
                    sphere.values[i] = field.sample(sphere.simple_position(x, y, z));
                }
            }
        }
        let finite: Vec<f32> = sphere.values.to_vec();
        let len = finite.len();
        let modes = [
            (Method::Mc, Clustering::None),
            (Method::SurfaceNets, Clustering::None),
            (Method::Mt, Clustering::None),
            (Method::Mt, Clustering::Integrated),
        ];
        let mut ex = crate::Extractor::new();
        let mut mesh = rmt_mesh::Mesh::default();
        for (method, clustering) in modes {
            for threads in [1, 2] {
                let mut s = ExtractSettings::new(grid, Lattice::Simple, clustering);
                s.method = method;
                s.threads = threads;
                let stats = ex.extract_borrowed(&finite, &s, &mut mesh).unwrap();
                assert!(stats.triangles > 0);
                for (first, second) in [(0, None), (len / 2 + 3, Some(len - 1)), (len - 1, None)] {
                    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
                        let mut v = finite.clone();
                        v[first] = bad;
                        if let Some(at) = second {
                            v[at] = f32::NAN;
                        }
                        let dx = cells[0] + 1;
                        let dy = cells[1] + 1;
                        let point = [first % dx, (first / dx) % dy, first / (dx * dy)];
                        let what = format!("{method:?} {clustering:?} {threads} {first} {bad}");
                        match ex.extract_borrowed(&v, &s, &mut mesh) {
                            Err(ExtractError::NonFiniteValue {
                                slot,
                                point: p,
                                value,
                            }) => {
                                assert_eq!((slot, p), (first, point), "{what}");
                                assert_eq!(value.to_bits(), bad.to_bits(), "{what}");
                            }
                            other => panic!("{what}: {other:?}"),
                        }
                        ex.samples_mut().prepare(&s);
                        ex.samples_mut().values.copy_from_slice(&v);
                        let copied = ex.extract_presampled(&s, &mut mesh);
                        assert!(
                            matches!(copied, Err(ExtractError::NonFiniteValue { slot, .. }) if slot == first),
                            "{what}: {copied:?}"
                        );
                    }
                }
            }
        }
    }

    /// A different value at every lattice point (exact in these lattice units).
    struct Coords;

    impl ScalarField for Coords {
        fn sample(&self, p: Vec3) -> f32 {
            p.x + 16.0 * p.y + 256.0 * p.z
        }
    }

    fn settings(cells: [usize; 3], lo: [usize; 3], lattice: Lattice) -> ExtractSettings {
        let v = |c: [usize; 3]| Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32);
        let hi = [0, 1, 2].map(|a| lo[a] + cells[a]);
        ExtractSettings::new(Grid::new(cells, v(lo), v(hi)), lattice, Clustering::None)
    }

    fn sampled(st: &ExtractSettings) -> Samples {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .expect("a pool");
        let mut s = Samples::default();
        s.sample(&Coords, st, &pool, &mut Stats::default())
            .expect("finite values");
        s
    }

    #[test]
    fn a_copied_box_holds_the_values_the_box_samples_itself() {
        for lattice in [Lattice::BodyCentred, Lattice::Simple] {
            let whole = sampled(&settings([7, 6, 8], [0; 3], lattice));
            for (s0, cells) in [
                ([1, 2, 3], [3, 2, 4]),
                ([0, 0, 0], [7, 6, 8]),
                ([2, 1, 0], [5, 5, 5]),
            ] {
                let st = settings(cells, s0, lattice);
                let direct = sampled(&st);
                let mut copied = Samples::default();
                copied.copy_box(&whole, &st, s0).expect("inside");
                assert_eq!(copied.dims, direct.dims, "{lattice:?} {s0:?}");
                // Every slot of a lattice point of the box holds that point's value. (The
                // body-centred ghost slots outside the box hold the whole volume's values
                // there, where the box's own sampling clamps them onto its faces: they only
                // shape triangles outside the box.)
                let [dx, dy, _] = direct.dims;
                let mut points = 0;
                for (k, (c, d)) in copied.values.iter().zip(&direct.values).enumerate() {
                    let (sx, sy, z) = (k % dx, k / dx % dy, k / (dx * dy));
                    let inside = match lattice {
                        Lattice::BodyCentred => {
                            let zz = z as i64 - 1;
                            let odd = zz & 1;
                            let p = [2 * sx as i64 - odd, 2 * sy as i64 - odd, zz];
                            (0..3).all(|a| p[a] >= 0 && p[a] <= 2 * cells[a] as i64)
                        }
                        Lattice::Simple => true,
                    };
                    if inside {
                        assert_eq!(c.to_bits(), d.to_bits(), "{lattice:?} {s0:?} slot {k}");
                        points += 1;
                    }
                }
                // Each lattice point of the box once: the corners, and the centres.
                let corners: usize = cells.iter().map(|c| c + 1).product();
                let centres: usize = cells.iter().product();
                let expected = match lattice {
                    Lattice::BodyCentred => corners + centres,
                    Lattice::Simple => corners,
                };
                assert_eq!(points, expected, "{lattice:?} {s0:?} {cells:?}");
            }
        }
    }

    #[test]
    fn boxes_outside_the_volume_or_on_another_lattice_are_refused() {
        let whole = sampled(&settings([4, 4, 4], [0; 3], Lattice::BodyCentred));
        let mut out = Samples::default();
        for (s0, cells) in [
            ([1, 0, 0], [4, 4, 4]),
            ([0, 0, 3], [2, 2, 2]),
            ([usize::MAX, 0, 0], [1, 1, 1]),
        ] {
            let st = settings(cells.map(|c: usize| c.max(1)), [0; 3], Lattice::BodyCentred);
            let err = out.copy_box(&whole, &st, s0).expect_err("outside");
            assert!(err.to_string().contains("not inside"), "{err}");
        }
        let st = settings([2, 2, 2], [0; 3], Lattice::Simple);
        assert!(
            out.copy_box(&whole, &st, [0; 3]).is_err(),
            "another lattice"
        );
    }
}
