//! Marching tetrahedra on both lattices: [`extract`] runs the passes in order, one module each.
//!
//! ```text
//!   samples --allocate--> tables sized to the lattice
//!           --crossings::vertex_pass--> inside bits, crossed points, owners, ids, positions,
//!                                        proposals                      (parallel over planes)
//!           --integrated::cluster-----> groups tested in the quotient, output vertices
//!                                        (with clustering)               (parallel rounds)
//!           --emission::emit----------> triangles, collapsed ones dropped (parallel over layers)
//! ```
//!
//! - `layout`: the lattice in storage terms (neighbour deltas, tetrahedron templates, the
//!   border table, the case table);
//! - `crossings`: the vertex pass;
//! - `integrated`: the clustering steps (proposals, group tables, quotient tests and repair in
//!   [`crate::mt::clustering::quotient`], [`crate::mt::clustering::repair`] and [`crate::mt::clustering::additions`]);
//! - `emission`: the geometry pass, and the listing of plain MT's triangles that the quotient
//!   test reads.
//!
//! Border rule: points on the box faces (whose lattice edges are cut by the box) cluster too, with
//! the missing neighbours counted as neither crossed nor uncrossed. A crossing whose edge lacks
//! some of its tetrahedra (it lies on the box face) is a vertex of the mesh boundary: integrated
//! clustering never groups it, so crossings on the box faces never move and the mesh stays
//! closed wherever the surface stays inside the box. (The unchecked mode has no such guarantee;
//! that is its point.)

use rayon::prelude::*;
use rmt_mesh::Mesh;

use crate::lattice::Offset;
use crate::lattice::FULL;
use crate::util::{bits_at, for_each_bit, overwritten};
use crate::{CellRange, Clustering, ExtractError, ExtractSettings, Lattice, Samples, Stats};
use clustering::proposal::{self, Candidate, ProposalCounts, Rules};

pub(crate) mod clustering;
mod crossings;
mod emission;
mod geometry;
pub(crate) mod layout;

pub(crate) use crossings::WELD;

use clustering::*;
use crossings::*;
use emission::*;
use geometry::*;
pub(crate) use layout::*;

/// Per-point working arrays kept between extractions.
#[derive(Default)]
pub struct MtBuffers {
    /// Which points have a crossed edge, and their owned crossings and ids ([`CrossedIndex`]).
    crossed: CrossedIndex,
    /// Per storage plane, its crossed points in slot order as `owned | crossed << 16` (the vertex
    /// pass's output, numbered into [`CrossedIndex::points`]).
    plane_points: Vec<Vec<u32>>,
    /// Proposed groups, in storage order of their owners.
    candidates: Vec<Candidate>,
    /// Positions of the crossings (plain MT's vertices), with clustering.
    cpos: Vec<[f32; 3]>,
    /// The groups' state: kept or not, each crossing's group, lone crossings, labels and
    /// vertex positions.
    groups: clustering::quotient::Groups,
    /// Every crossing's owner slot and edge (the direction from the owner), with clustering.
    edge_of: Vec<(u32, u8)>,
    /// Plain MT's triangles (three crossing ids each) and their source tetrahedra, and every
    /// crossing's triangles (CSR), with checked clustering: the stars of the quotient test.
    plain: Vec<u32>,
    plain_grad: Vec<[f32; 3]>,
    /// In a chunk: per plain triangle, 1 when its anchor's cell is kept (emitted by the chunk).
    plain_kept: Vec<u8>,
    /// When recording ([`crate::Extractor::set_recording`]): per plain triangle, its anchor
    /// cell (linear index, x fastest).
    plain_cell: Vec<u32>,
    /// Record the anchor cell of every output triangle and the clustering's activity
    /// (integrated clustering only).
    pub(crate) record: bool,
    /// Recorded: the anchor cell of every output triangle (linear index, x fastest).
    pub(crate) tri_cells: Vec<u32>,
    /// Recorded: the lattice points (grid-local lattice coordinates) whose crossings the
    /// clustering touched after its proposals, sorted, each once.
    pub(crate) activity: Vec<[i32; 3]>,
    inc_start: Vec<u32>,
    inc: Vec<u32>,
    /// Working memory of the incidence table's fill.
    inc_cursor: Vec<u32>,
    /// The parallel incidence table's per-part counts and cursors.
    inc_parts: Vec<Vec<u32>>,
    /// Output vertex of each crossing, with clustering.
    vertex_of: Vec<u32>,
    /// Working memory of the vertex compaction (integrated-unchecked).
    scratch: Vec<u32>,
    /// The emission's output, one part per run of listed triangles ([`emission::emit`]).
    emit_parts: Vec<Vec<u32>>,
    /// One bit per storage slot, set where the value is inside (`f < iso`), plus one zero word
    /// of padding: 64 points are tested for crossings at once with a few word operations.
    inside: Vec<u64>,
    /// [`crate::BufferPolicy::Lean`]: free every table when its last reader is done.
    pub(crate) lean: bool,
    /// The layout's border table of the last extraction.
    border: BorderCache,
}

impl MtBuffers {
    /// Bytes of the per-point tables (crossed points, per-plane lists, inside bits, candidates).
    fn table_bytes(&self) -> usize {
        self.crossed.bytes()
            + self.plane_points.iter().map(|o| o.len() * 4).sum::<usize>()
            + self.inside.len() * 8
            + self.candidates.len() * std::mem::size_of::<Candidate>()
            + self.cpos.len() * 12
            + self.groups.bytes()
            + self.edge_of.len() * 8
            + self.plain.len() * 4
            + self.plain_grad.len() * 12
            + self.plain_kept.len()
            + self.plain_cell.len() * 4
            + self.inc_start.len() * 4
            + self.inc.len() * 4
            + self.inc_cursor.len() * 4
            + self.inc_parts.iter().map(|p| p.len() * 4).sum::<usize>()
            + self.vertex_of.len() * 4
    }
}

/// Extracts the surface of `samples` with marching tetrahedra (and clustering) into `mesh`:
/// allocation, the vertex pass (`crossings::vertex_pass`), clustering
/// (`integrated::cluster`), the emission (`emission::emit`). The post-processing modes run
/// after it, on the mesh ([`crate::post`]).
pub fn extract(
    samples: &Samples,
    settings: &ExtractSettings,
    pool: &rayon::ThreadPool,
    buf: &mut MtBuffers,
    mesh: &mut Mesh,
    stats: &mut Stats,
) -> Result<Emitted, ExtractError> {
    let layout = Layout::cached(samples, settings.lattice, &mut buf.border);
    let clustering = settings.clustering;
    let propose = matches!(
        clustering,
        Clustering::Integrated | Clustering::IntegratedUnchecked
    );
    let rules = if clustering == Clustering::Integrated {
        Rules::Islands
    } else {
        Rules::Dissertation
    };
    allocate(samples, buf, stats)?;
    buf.tri_cells.clear();
    buf.activity.clear();

    // Vertex pass: crossings, their ids and positions, and the proposals.
    let t = std::time::Instant::now();
    let near_points = vertex_pass(
        &layout,
        samples,
        settings.iso,
        propose.then_some(rules),
        pool,
        buf,
        mesh,
        stats,
    )?;
    let mut keys: Vec<u64> = Vec::new();
    tile_keys(samples, settings, buf, &mut keys);
    // Clustering: which proposals become one vertex (counted in the vertex pass).
    // Tetrahedra with a triangle, counted by the pass that wrote plain MT's triangles.
    let mut plain_processed = 0;
    if propose {
        cluster(
            buf,
            &layout,
            settings.iso,
            clustering,
            settings.keep_cells,
            mesh,
            stats,
            &mut plain_processed,
            pool,
        );
    }
    stats.t_vertex_s += t.elapsed().as_secs_f64();

    // Emission: the final triangles.
    let t = std::time::Instant::now();
    emit(
        &layout,
        samples,
        settings,
        propose,
        plain_processed,
        buf,
        mesh,
        pool,
        stats,
    );
    stats.t_geometry_s += t.elapsed().as_secs_f64();
    let lean_bytes = release_tables(buf, pool);
    stats.clusters_rejected = stats.clusters_rejected_prefilter + stats.clusters_rejected_check;
    let table_bytes = if buf.lean {
        // Measured before they were released.
        lean_bytes
    } else {
        buf.table_bytes()
    };
    if buf.lean {
        *buf = MtBuffers {
            lean: true,
            ..MtBuffers::default()
        };
    }
    Ok(Emitted {
        near_points,
        tile_keys: keys,
        table_bytes,
    })
}

/// What marching tetrahedra hands on besides the mesh: what the post-processing reads
/// ([`crate::post::process`]) and the bytes of its tables.
pub(crate) struct Emitted {
    /// Crossings within [`WELD`] of their owner (surfaces through sample points).
    pub(crate) near_points: usize,
    /// The tile rule's key of every crossing (chunked extraction with edge collapse); empty
    /// otherwise.
    pub(crate) tile_keys: Vec<u64>,
    /// Bytes of the per-point tables, measured before [`crate::BufferPolicy::Lean`] released
    /// them.
    pub(crate) table_bytes: usize,
}

/// Allocation: the per-slot tables sized to the sample array (timed as allocation).
fn allocate(samples: &Samples, buf: &mut MtBuffers, stats: &mut Stats) -> Result<(), ExtractError> {
    let t = std::time::Instant::now();
    let slots = samples.values.len();
    if slots > u32::MAX as usize {
        return Err(ExtractError::TooLarge {
            cells: samples.cells,
            limit: u32::MAX as usize,
        });
    }
    buf.candidates.clear();
    let words = slots.div_ceil(64);
    buf.inside.resize(words + 1, 0);
    let plane = samples.dims[0] * samples.dims[1];
    let planes = samples.dims[2];
    buf.crossed.reset(plane, planes);
    if buf.plane_points.len() < planes {
        buf.plane_points.resize_with(planes, Vec::new);
    }
    stats.t_allocation_s += t.elapsed().as_secs_f64();

    Ok(())
}

/// The tile rule's key of every crossing (chunked extraction with edge collapse), in `keys`;
/// empty otherwise.
fn tile_keys(samples: &Samples, settings: &ExtractSettings, buf: &MtBuffers, keys: &mut Vec<u64>) {
    let plane = samples.dims[0] * samples.dims[1];
    let planes = samples.dims[2];
    if let Some(tiling) = &settings.tiles {
        if settings.clustering == Clustering::Postprocessed {
            let crossed = &buf.crossed;
            crate::tiles::crossing_keys(
                samples,
                tiling,
                |visit| {
                    let mut r = 0;
                    for z in 0..planes {
                        for_each_bit(crossed.plane_bits(z), 0, plane, |local| {
                            visit(z * plane + local, crossed.points[r].owned);
                            r += 1;
                        });
                    }
                },
                keys,
            );
        }
    }
}

/// [`crate::BufferPolicy::Lean`]: frees the per-point tables (no reader is left); returns
/// their bytes, measured before.
fn release_tables(buf: &mut MtBuffers, pool: &rayon::ThreadPool) -> usize {
    if !buf.lean {
        return 0;
    }
    let lean_bytes = buf.table_bytes();
    {
        buf.crossed = CrossedIndex::default();
        buf.inside = Vec::new();
        buf.plane_points = Vec::new();
        buf.plain = Vec::new();
        buf.plain_grad = Vec::new();
        buf.plain_kept = Vec::new();
        buf.plain_cell = Vec::new();
        buf.inc_start = Vec::new();
        buf.inc = Vec::new();
        buf.inc_cursor = Vec::new();
        buf.inc_parts = Vec::new();
        buf.edge_of = Vec::new();
        buf.groups = clustering::quotient::Groups::default();
        pool.broadcast(|_| LAYER_WINDOW.with_borrow_mut(|w| *w = Vec::new()));
    }
    lean_bytes
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Plain MT of `field` on `cells` in [-1, 1]^3: the settings, samples, the pass buffers as the
    /// extraction left them, and the mesh.
    /// A smooth field with many surface sheets in [-1, 1]^3.
    fn wavy() -> rmt_fields::FnField<impl Fn(glam::Vec3) -> f32> {
        rmt_fields::FnField(|p: glam::Vec3| {
            (p.x * 6.3).sin() * (p.y * 4.1 + 0.3).cos() + (p.z * 5.7).sin() * 0.8 - 0.1
        })
    }

    /// A pool of `threads` threads for a test.
    fn test_pool(threads: usize) -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a thread pool")
    }

    /// Settings for `cells` in [-1, 1]^3.
    fn settings_on(
        cells: [usize; 3],
        lattice: Lattice,
        clustering: crate::Clustering,
    ) -> crate::ExtractSettings {
        crate::ExtractSettings::new(
            crate::Grid::new(cells, glam::Vec3::splat(-1.0), glam::Vec3::splat(1.0)),
            lattice,
            clustering,
        )
    }

    /// `field` sampled and extracted with `settings`: the samples, the pass buffers as the
    /// extraction left them, the mesh and the counters.
    fn extracted(
        field: &impl rmt_fields::ScalarField,
        settings: &crate::ExtractSettings,
        pool: &rayon::ThreadPool,
    ) -> (Samples, MtBuffers, Mesh, Stats) {
        let mut stats = Stats::default();
        let mut samples = Samples::default();
        samples
            .sample(field, settings, pool, &mut stats)
            .expect("a finite field");
        let (mut buf, mut mesh) = (MtBuffers::default(), Mesh::default());
        let mut counted = Stats::default();
        extract(&samples, settings, pool, &mut buf, &mut mesh, &mut counted).expect("extraction");
        (samples, buf, mesh, counted)
    }

    fn plain_mt(
        field: &impl rmt_fields::ScalarField,
        lattice: Lattice,
        cells: [usize; 3],
        pool: &rayon::ThreadPool,
    ) -> (crate::ExtractSettings, Samples, MtBuffers, Mesh) {
        let settings = settings_on(cells, lattice, crate::Clustering::None);
        let (samples, buf, mesh, _) = extracted(field, &settings, pool);
        (settings, samples, buf, mesh)
    }

    #[test]
    fn crossed_index_finds_every_point_and_its_owned_crossings() {
        // Grids whose storage planes hold fewer slots than a word of bits, about as many, and
        // many more; the reference is each point's 14 edges tested one by one.
        let field = rmt_fields::FnField(|p: glam::Vec3| {
            (p.x * 7.1).sin() + (p.y * 5.3).cos() * (p.z * 3.7 + 0.4).sin() - 0.2
        });
        let pool = test_pool(2);
        let mut checked = 0;
        for lattice in [Lattice::BodyCentred, Lattice::Simple] {
            for cells in [
                [1, 1, 6],
                [2, 1, 5],
                [1, 3, 4],
                [3, 3, 3],
                [5, 2, 7],
                [9, 8, 6],
                [40, 3, 5],
            ] {
                let (settings, samples, buf, mesh) = plain_mt(&field, lattice, cells, &pool);
                let l = Layout::new(&samples, lattice);
                let [dx, dy, dz] = samples.dims;
                let iso = settings.iso;
                let (mut before, mut rank) = (0u32, 0usize);
                for z in 0..dz {
                    for sy in 0..dy {
                        for sx in 0..dx {
                            let slot = (z * dy + sy) * dx + sx;
                            let (p, exists) = l.point(sx, sy, z);
                            let (mut crossed, mut own) = (0u16, 0u16);
                            if exists {
                                let f = samples.values[slot];
                                let valid = l.valid_neighbours(p);
                                for d in (0..14).filter(|d| valid & (1 << d) != 0) {
                                    let q =
                                        (slot as isize + l.delta[(p[0] & 1) as usize][d]) as usize;
                                    let g = samples.values[q];
                                    if (g < iso) != (f < iso) {
                                        crossed |= 1 << d;
                                        if owns(f, g, iso) {
                                            own |= 1 << d;
                                        }
                                    }
                                }
                            }
                            let what = format!("{lattice:?} {cells:?} slot {slot}");
                            assert_eq!(buf.crossed.plane_of(slot), z, "{what}");
                            assert_eq!(buf.crossed.is_crossed(slot), crossed != 0, "{what}");
                            if crossed != 0 {
                                let expected = CrossedPoint {
                                    first: before,
                                    owned: own,
                                    crossed,
                                };
                                assert_eq!(buf.crossed.get(slot), expected, "{what}");
                                assert_eq!(buf.crossed.points[rank], expected, "{what}");
                                rank += 1;
                                checked += usize::from(own != 0);
                            }
                            before += own.count_ones();
                        }
                    }
                }
                assert_eq!(rank, buf.crossed.points.len(), "{lattice:?} {cells:?}");
                assert_eq!(
                    before as usize,
                    mesh.positions.len(),
                    "{lattice:?} {cells:?}"
                );
            }
        }
        assert!(checked > 100, "only {checked} points own crossings");
    }

    #[test]
    fn the_tetrahedra_around_the_points_give_exactly_the_emitted_triangles() {
        // Every point sees 24 tetrahedra; over all points each tetrahedron of the extraction is
        // seen from its 4 corners, and their triangles (the quotient test's view) are exactly
        // the triangles the geometry pass writes, with the same orientation.
        let field = rmt_fields::FnField(|p: glam::Vec3| {
            (p.x * 5.3).sin() * (p.y * 3.9 + 0.2).cos() + (p.z * 4.7).sin() * 0.7 - 0.15
        });
        let pool = test_pool(1);
        for lattice in [Lattice::BodyCentred, Lattice::Simple] {
            for cells in [[3, 4, 5], [9, 8, 7]] {
                let (settings, samples, buf, mesh) = plain_mt(&field, lattice, cells, &pool);
                let l = Layout::new(&samples, lattice);
                assert_eq!(l.around[0].len(), 24, "{lattice:?}");
                assert_eq!(l.around[1].len(), 24, "{lattice:?}");
                for tet in l.around.iter().flatten() {
                    assert_eq!(crate::lattice::det(&tet.off).signum(), 1, "{lattice:?}");
                    assert_eq!(tet.from_point.count_ones(), 3);
                }
                let canonical = |t: [u32; 3]| {
                    let k = (0..3).min_by_key(|&i| t[i]).unwrap_or(0);
                    [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
                };
                let mut seen = std::collections::HashMap::new();
                let mut tets = 0;
                let [dx, dy, dz] = samples.dims;
                for z in 0..dz {
                    for sy in 0..dy {
                        for sx in 0..dx {
                            let (p, exists) = l.point(sx, sy, z);
                            if !exists {
                                continue;
                            }
                            let slot = (z * dy + sy) * dx + sx;
                            for tet in &l.around[(p[0] & 1) as usize] {
                                if !l.has_tet(p, tet) {
                                    continue;
                                }
                                tets += 1;
                                let idx = tet.delta.map(|d| (slot as isize + d) as usize);
                                let val = idx.map(|i| samples.values[i]);
                                let id = |o: usize, d: u8| buf.crossed.get(idx[o]).id(d);
                                let mut tris = [[0; 3]; 2];
                                let n = tet_triangles(
                                    val,
                                    settings.iso,
                                    &tet.dir,
                                    id,
                                    &mesh.positions,
                                    &mut tris,
                                );
                                for t in &tris[..n] {
                                    *seen.entry(canonical(*t)).or_insert(0) += 1;
                                }
                            }
                        }
                    }
                }
                let stats_tets = match lattice {
                    Lattice::BodyCentred => {
                        let [nx, ny, nz] = cells;
                        4 * ((nx + 1) * ny * nz + nx * (ny + 1) * nz + nx * ny * (nz + 1))
                    }
                    Lattice::Simple => 6 * cells.iter().product::<usize>(),
                };
                assert_eq!(tets, 4 * stats_tets, "{lattice:?} {cells:?}");
                let emitted: std::collections::HashSet<[u32; 3]> = mesh
                    .indices
                    .chunks_exact(3)
                    .map(|t| canonical([t[0], t[1], t[2]]))
                    .collect();
                assert_eq!(emitted.len() * 3, mesh.indices.len());
                assert!(seen.values().all(|&c| c == 4), "{lattice:?} {cells:?}");
                let seen: std::collections::HashSet<[u32; 3]> = seen.into_keys().collect();
                assert_eq!(seen, emitted, "{lattice:?} {cells:?}");
            }
        }
    }

    #[test]
    fn layer_triangle_counts_match_the_tetrahedra_of_every_group() {
        // The count reads only the anchor's crossed edges through the group tables; here each
        // group's tetrahedra are evaluated from the sample values instead, with and without
        // kept cells.
        let field = wavy();
        let pool = test_pool(1);
        let mut triangles = 0;
        // Anchors visited as not inner / inner.
        let mut flags = [0usize; 2];
        for lattice in [Lattice::BodyCentred, Lattice::Simple] {
            for cells in [[3, 2, 4], [9, 8, 6], [13, 11, 12]] {
                let (settings, samples, buf, mesh) = plain_mt(&field, lattice, cells, &pool);
                let l = Layout::new(&samples, lattice);
                let (expected_len, dirs_from) = match lattice {
                    Lattice::BodyCentred => (6, 1),
                    Lattice::Simple => (8, 0),
                };
                for g in &l.groups {
                    assert_eq!(g.len, expected_len, "{lattice:?}");
                    assert_eq!(g.points[0], 0, "the anchor comes first");
                    for i in 1..g.len {
                        let d = l.delta[dirs_from][g.dirs[i] as usize];
                        assert_eq!(d, g.points[i], "{lattice:?} point {i}");
                    }
                    for code in 0..1usize << g.len {
                        let swapped = !code & ((1 << g.len) - 1);
                        assert_eq!(g.triangles[code], g.triangles[swapped], "side swap");
                    }
                }
                let layers = match lattice {
                    Lattice::BodyCentred => cells[2] + 1,
                    Lattice::Simple => cells[2],
                };
                let keeps = [
                    None,
                    Some(CellRange {
                        lo: [1, 0, 1],
                        hi: [cells[0] - 1, cells[1], cells[2] - 1],
                    }),
                ];
                for keep in keeps {
                    let mut total = 0;
                    for k in 0..layers {
                        let mut direct = 0;
                        for_each_group(&l, k, keep, &buf.crossed, |anchor, _, g, q| {
                            let tets = match lattice {
                                Lattice::BodyCentred => &l.tets[4 * g..4 * g + 4],
                                Lattice::Simple => &l.tets[..],
                            };
                            // The walk's coordinates are the anchor's, and `inner_anchor`
                            // promises every corner in the box (no ghost).
                            let p = l.coords_of(anchor);
                            assert_eq!(q, p, "{lattice:?} {cells:?}");
                            let inner = l.inner_anchor(p);
                            let in_box = tets.iter().all(|tpl| {
                                tpl.off.iter().all(|o| {
                                    (0..3)
                                        .all(|a| p[a] + o[a] >= 0 && p[a] + o[a] <= l.max_coord(a))
                                })
                            });
                            assert!(!inner || in_box, "{lattice:?} {cells:?} anchor {p:?}");
                            flags[usize::from(inner)] += 1;
                            for tpl in tets {
                                let case = (0..4).fold(0, |case, i| {
                                    let slot = (anchor as isize + tpl.delta[i]) as usize;
                                    case | usize::from(samples.values[slot] < settings.iso) << i
                                });
                                direct += usize::from(case_triangles(case));
                            }
                        });
                        let counted = count_layer(&l, k, keep, &buf.crossed);
                        assert_eq!(counted, direct, "{lattice:?} {cells:?} layer {k} {keep:?}");
                        total += counted;
                    }
                    if keep.is_none() {
                        assert_eq!(total * 3, mesh.indices.len(), "{lattice:?} {cells:?}");
                    }
                    triangles += total;
                }
            }
        }
        assert!(
            triangles > 1000,
            "only {triangles} triangles: the fields miss the grids"
        );
        assert!(
            flags[0] > 50 && flags[1] > 50,
            "anchors by inner: {flags:?}"
        );
    }

    #[test]
    fn unchecked_numbering_by_planes_is_the_group_tables_numbering() {
        // `keep_all` (integrated-unchecked: every proposal kept, numbered plane by plane in
        // parallel) against the group tables and the serial `vertex_map` of integrated
        // clustering with every group kept: the same vertex of every crossing and the same
        // positions, bit for bit.
        let field = wavy();
        let mut compared = 0;
        for threads in [1, 2] {
            let pool = test_pool(threads);
            for lattice in [Lattice::BodyCentred, Lattice::Simple] {
                for cells in [[12, 10, 14], [16, 16, 16], [5, 23, 9]] {
                    let settings =
                        settings_on(cells, lattice, crate::Clustering::IntegratedUnchecked);
                    let (samples, mut buf, _, _) = extracted(&field, &settings, &pool);
                    let what = format!("{lattice:?} {cells:?} threads={threads}");
                    assert!(buf.candidates.len() > 20, "{what}: few proposals");
                    let l = Layout::new(&samples, lattice);
                    let mut by_planes = Vec::new();
                    keep_all(&mut buf, &l, &mut by_planes, &pool);
                    let planes_map = buf.vertex_of.clone();
                    build_groups(&mut buf, &l, &pool);
                    let (mut tables_map, mut by_tables) = (Vec::new(), Vec::new());
                    let fixed = clustering::quotient::Fixed {
                        l: &l,
                        cpos: &buf.cpos,
                        groups: &buf.candidates,
                        tris: &[],
                        grad: &[],
                        inc_start: &[],
                        inc: &[],
                    };
                    // Every crossing's quotient vertex, which the numbering reads.
                    buf.groups.relabel(&fixed, &pool);
                    let q = clustering::quotient::Quotient::new(&fixed, &buf.groups);
                    vertex_map(&q, &mut tables_map, &mut by_tables, &pool);
                    assert_eq!(planes_map, tables_map, "{what}");
                    let bits = |p: &[[f32; 3]]| -> Vec<[u32; 3]> {
                        p.iter().map(|v| v.map(f32::to_bits)).collect()
                    };
                    assert_eq!(bits(&by_planes), bits(&by_tables), "{what}");
                    // Merged groups: fewer vertices than crossings.
                    assert!(by_planes.len() < buf.cpos.len(), "{what}");
                    compared += buf.cpos.len();
                }
            }
        }
        assert!(compared > 5000, "only {compared} crossings compared");
    }

    #[test]
    fn a_chunk_maps_its_triangles_from_the_list_as_the_geometry_pass_walks_its_cells() {
        // Integrated clustering in a chunk emits the kept cells' triangles from plain MT's
        // list; the geometry pass over the kept cells, through the same vertex map, is the
        // reference (triangles, their order, and the counters).
        let field = wavy();
        let pool = test_pool(2);
        let mut compared = 0;
        for lattice in [Lattice::BodyCentred, Lattice::Simple] {
            for (cells, lo, hi) in [
                ([12, 10, 14], [1, 1, 1], [11, 9, 13]),
                ([16, 16, 16], [0, 3, 5], [9, 16, 12]),
                ([9, 13, 11], [2, 0, 0], [9, 7, 6]),
            ] {
                let mut settings = settings_on(cells, lattice, crate::Clustering::Integrated);
                settings.keep_cells = Some(CellRange { lo, hi });
                let (samples, buf, mesh, listed) = extracted(&field, &settings, &pool);
                let l = Layout::new(&samples, lattice);
                let mut walked = Mesh::default();
                let mut reference = Stats::default();
                emit_layers(
                    &l,
                    settings.iso,
                    settings.keep_cells,
                    &buf.crossed,
                    true,
                    &buf,
                    &mut walked,
                    None,
                    &pool,
                    &mut reference,
                );
                let what = format!("{lattice:?} {cells:?} {lo:?}..{hi:?}");
                assert_eq!(mesh.indices, walked.indices, "{what}");
                assert_eq!(
                    listed.tetrahedra_processed, reference.tetrahedra_processed,
                    "{what}"
                );
                assert_eq!(listed.discarded, reference.discarded, "{what}");
                compared += mesh.indices.len() / 3;
            }
        }
        assert!(compared > 500, "only {compared} triangles compared");
    }

    #[test]
    fn a_cached_border_table_is_the_one_built_for_the_same_lattice_and_cells() {
        let mut cache = BorderCache::default();
        let mut built = 0;
        for (lattice, cells) in [
            (Lattice::BodyCentred, [12, 14, 16]),
            (Lattice::BodyCentred, [12, 14, 16]),
            (Lattice::BodyCentred, [16, 14, 12]),
            (Lattice::Simple, [16, 14, 12]),
            (Lattice::BodyCentred, [16, 14, 12]),
            (Lattice::BodyCentred, [3, 4, 5]),
            (Lattice::Simple, [20, 12, 11]),
        ] {
            let settings = ExtractSettings::new(
                crate::Grid::new(cells, glam::Vec3::ZERO, glam::Vec3::ONE),
                lattice,
                Clustering::None,
            );
            let mut samples = Samples::default();
            samples.prepare(&settings);
            let fresh = Layout::new(&samples, lattice).border_table;
            let cached = Layout::cached(&samples, lattice, &mut cache).border_table;
            assert_eq!(cached, fresh, "{lattice:?} {cells:?}");
            built += usize::from(!fresh.is_empty());
        }
        // Six of the seven grids are large enough for the classes to have a table.
        assert_eq!(built, 6);
    }

    #[test]
    fn inside_words_set_exactly_the_bits_of_values_below_the_isovalue() {
        let mut state = 7u64;
        for len in [0, 1, 5, 63, 64] {
            for iso in [0.0f32, 0.25, -0.5] {
                let values: Vec<f32> = (0..len)
                    .map(|k| match k % 7 {
                        0 => iso,
                        1 => f32::NAN,
                        2 => -0.0,
                        _ => lcg(&mut state) * 2.0 - 1.0,
                    })
                    .collect();
                let word = inside_word(&values, iso);
                for (k, &f) in values.iter().enumerate() {
                    assert_eq!(
                        word >> k & 1 == 1,
                        f < iso,
                        "len {len} iso {iso} k {k} f {f}"
                    );
                }
                assert_eq!(
                    word >> len.min(63) >> u32::from(len == 64),
                    0,
                    "no bit past the end"
                );
            }
        }
    }

    #[test]
    fn plane_of_divides_exactly_for_every_slot_below_2_pow_32() {
        let mut index = CrossedIndex::default();
        let mut x = 0x9E37_79B9_7F4A_7C15u64;
        for plane in (1..600).chain([4096, 65_537, 66_049, 1 << 20, 3_000_017]) {
            index.reset(plane, 0);
            let mut slots: Vec<usize> = (0..2000).collect();
            for k in [1usize, 2, 7, 1000, 65_000, (u32::MAX as usize) / plane] {
                slots.extend([k * plane - 1, k * plane, k * plane + 1]);
            }
            slots.push(u32::MAX as usize);
            for _ in 0..2000 {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                slots.push((x >> 32) as usize);
            }
            for slot in slots.into_iter().filter(|&s| s <= u32::MAX as usize) {
                assert_eq!(
                    index.plane_of(slot),
                    slot / plane,
                    "slot {slot}, plane {plane}"
                );
            }
        }
    }

    #[test]
    fn border_table_agrees_with_the_point_by_point_rules() {
        for lattice in [Lattice::BodyCentred, Lattice::Simple] {
            for cells in [[4, 5, 6], [5, 5, 5], [6, 11, 7], [12, 10, 13], [17, 16, 5]] {
                let settings = crate::ExtractSettings::new(
                    crate::Grid::new(cells, glam::Vec3::ZERO, glam::Vec3::ONE),
                    lattice,
                    crate::Clustering::None,
                );
                let mut samples = Samples::default();
                samples.prepare(&settings);
                let l = Layout::new(&samples, lattice);
                let big = (0..3).all(|a| l.max_coord(a) >= 10);
                assert_eq!(l.border_table.is_empty(), !big, "{cells:?}");
                let [dx, dy, dz] = samples.dims;
                for z in 0..dz {
                    for sy in 0..dy {
                        for sx in 0..dx {
                            let (p, exists) = l.point(sx, sy, z);
                            let valid = if exists { l.valid_neighbours(p) } else { 0 };
                            assert_eq!(
                                l.border_info(p),
                                (exists, valid),
                                "{lattice:?} {cells:?} at {p:?}"
                            );
                            if exists {
                                assert_eq!(
                                    l.inner_dirs(p),
                                    l.inner_dirs_of(p),
                                    "inner edges, {lattice:?} {cells:?} at {p:?}"
                                );
                            }
                        }
                    }
                }
            }
        }
    }

    /// A tiny deterministic generator for the table test (no dependency needed).
    fn lcg(state: &mut u64) -> f32 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*state >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
    }

    #[test]
    fn case_table_orients_triangles_along_the_gradient() {
        let mut s = 12345u64;
        let mut checked = 0;
        for _ in 0..2000 {
            let mut p: [glam::Vec3; 4] =
                [0; 4].map(|_| glam::Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)));
            let vol = (p[1] - p[0]).dot((p[2] - p[0]).cross(p[3] - p[0]));
            if vol.abs() < 1e-3 {
                continue;
            }
            if vol < 0.0 {
                p.swap(2, 3);
            }
            let grad = glam::Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s));
            let off = lcg(&mut s) * 0.5;
            let f: Vec<f32> = p.iter().map(|q| q.dot(grad) + off).collect();
            let case = (0..4).filter(|&i| f[i] < 0.0).fold(0, |c, i| c | 1 << i);
            if case == 0 || case == 15 {
                continue;
            }
            let cycle = &CASES[case];
            let n = if cycle[3] == u8::MAX { 3 } else { 4 };
            let pts: Vec<glam::Vec3> = cycle[..n]
                .iter()
                .map(|&e| {
                    let (a, b) = TET_EDGES[e as usize];
                    // Each edge of the cycle must really be crossed.
                    assert_ne!(f[a] < 0.0, f[b] < 0.0, "case {case} edge {e} not crossed");
                    p[a].lerp(p[b], f[a] / (f[a] - f[b]))
                })
                .collect();
            for tri in [[0, 1, 2], [0, 2, 3]].iter().take(n - 2) {
                let nrm = (pts[tri[1]] - pts[tri[0]]).cross(pts[tri[2]] - pts[tri[0]]);
                if nrm.length() > 1e-6 {
                    assert!(
                        nrm.dot(grad) > 0.0,
                        "case {case} faces against the gradient"
                    );
                    checked += 1;
                }
            }
            // Every crossed edge of the tetrahedron appears in the cycle.
            let crossed = TET_EDGES
                .iter()
                .filter(|(a, b)| (f[*a] < 0.0) != (f[*b] < 0.0))
                .count();
            assert_eq!(crossed, n, "case {case}");
        }
        assert!(checked > 1000);
    }
}
