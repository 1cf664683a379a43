//! Marching tetrahedra on both lattices: [`extract`] runs the passes in order, one module each.
//!
//! ```text
//!   samples --allocate--------------> tables sized to the lattice
//!           --crossings::vertex_pass-> inside bits, crossed points, owners, ids, positions,
//!                                      proposals                       (parallel over planes)
//!           --clustering::run--------> groups tested in the quotient, output vertices
//!                                      (with clustering)                (parallel rounds)
//!           --emission::emit---------> triangles, collapsed ones dropped (parallel over layers)
//! ```
//!
//! - `layout`: the lattice in storage terms (neighbour deltas, tetrahedron templates, the
//!   border table, the case table);
//! - `crossings`: the vertex pass, its tables ([`crossings::VertexTables`]);
//! - `geometry`: the walk over a layer's tetrahedra that the listing of plain MT's triangles
//!   and the emission share;
//! - `clustering`: integrated clustering, checked or not (proposals, group tables, plain MT's
//!   triangle list, quotient tests, repair rounds, additions), its tables
//!   ([`clustering::ClusterBuffers`]);
//! - `emission`: the final triangles, its buffers ([`emission::EmitBuffers`]).
//!
//! Each pass takes the tables it writes and borrows those it reads; [`MtBuffers`] only holds
//! them between extractions.
//!
//! Border rule: points on the box faces (whose lattice edges are cut by the box) cluster too, with
//! the missing neighbours counted as neither crossed nor uncrossed. A crossing whose edge lacks
//! some of its tetrahedra (it lies on the box face) is a vertex of the mesh boundary: integrated
//! clustering never groups it, so crossings on the box faces never move and the mesh stays
//! closed wherever the surface stays inside the box. (The unchecked mode has no such guarantee;
//! that is its point.)

use rmt_mesh::Mesh;

use crate::util::for_each_bit;
use crate::{Boundary, Clustering, ExtractError, ExtractSettings, Lattice, Samples, Stats};

pub(crate) mod clustering;
pub(crate) mod crossings;
pub(crate) mod emission;
pub(crate) mod geometry;
pub(crate) mod layout;
pub(crate) mod pyramids;

pub(crate) use crossings::WELD;

use clustering::proposal::{Candidate, Rules};
use clustering::ClusterBuffers;
use crossings::{vertex_pass, CrossedIndex, VertexOut, VertexTables, VertexWork};
use emission::{emit, Clustered, EmitBuffers, EmitIn};
use geometry::{Surface, LAYER_WINDOW};
use layout::{BorderCache, Layout};

/// The passes' tables, kept between extractions (one field per pass that writes them).
#[derive(Default)]
pub(crate) struct MtBuffers {
    /// The vertex pass's: inside bits, crossed points, per-plane lists.
    pub(crate) vertices: VertexTables,
    /// The clustering's: proposals, group state, plain MT's triangle list, vertex map.
    pub(crate) clustering: ClusterBuffers,
    /// The emission's: its output parts and the recorded triangle cells.
    pub(crate) emission: EmitBuffers,
    /// Record the anchor cell of every output triangle and the clustering's activity
    /// (integrated clustering only; [`crate::Extractor::set_recording`]).
    pub(crate) record: bool,
    /// [`crate::BufferPolicy::Lean`]: free every table when its last reader is done.
    pub(crate) lean: bool,
    /// Plain MT writes its triangles with their last two corners swapped, for a mesh in array
    /// order ([`crate::Extractor::set_array_order`]; the positions are turned after).
    pub(crate) flip: bool,
    /// The layout's border table of the last extraction.
    border: BorderCache,
}

impl MtBuffers {
    /// Bytes of the per-point tables (crossed points, per-plane lists, inside bits, candidates,
    /// the clustering's tables).
    fn table_bytes(&self) -> usize {
        self.vertices.bytes() + self.clustering.bytes()
    }
}

/// Extracts the surface of `samples` with marching tetrahedra (and clustering) into `mesh`:
/// allocation, the vertex pass ([`crossings::vertex_pass`]), clustering
/// ([`clustering::run`]), the emission ([`emission::emit`]). The post-processing modes run
/// after it, on the mesh ([`crate::post`]).
pub(crate) fn extract(
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
    allocate(
        samples,
        &mut buf.vertices,
        &mut buf.clustering.candidates,
        stats,
    )?;
    buf.emission.tri_cells.clear();
    buf.clustering.activity.clear();

    // Vertex pass: crossings, their ids and positions, and the proposals.
    let t = std::time::Instant::now();
    let out = VertexOut {
        proposals: &mut buf.clustering.candidates,
        positions: &mut mesh.positions,
    };
    let near_points = vertex_pass(
        &layout,
        settings.iso,
        VertexWork {
            propose: propose.then_some(rules),
            known_edges: buf.border.edges,
        },
        pool,
        &mut buf.vertices,
        out,
        stats,
    )?;
    buf.border.edges = Some(stats.edges);
    let mut keys: Vec<u64> = Vec::new();
    tile_keys(samples, settings, &buf.vertices.crossed, &mut keys);
    let surface = Surface {
        l: &layout,
        iso: settings.iso,
        keep: settings.keep_cells,
        crossed: &buf.vertices.crossed,
    };
    // Clustering: which proposals become one vertex (counted in the vertex pass).
    // Tetrahedra with a triangle, counted by the pass that wrote plain MT's triangles.
    let mut plain_processed = 0;
    if propose {
        plain_processed = clustering::run(
            &surface,
            clustering,
            buf.record,
            &mut buf.clustering,
            &mut mesh.positions,
            pool,
            stats,
        );
    }
    stats.t_vertex_s += t.elapsed().as_secs_f64();

    // Emission: the final triangles.
    let t = std::time::Instant::now();
    let clustered = propose.then_some(Clustered {
        cpos: &buf.clustering.cpos,
        vertex_of: &buf.clustering.vertex_of,
        plain: &buf.clustering.plain,
        processed: plain_processed,
    });
    let input = EmitIn {
        surface,
        clustering,
        record: buf.record,
        clustered,
        flip: buf.flip,
    };
    emit(input, &mut buf.emission, mesh, pool, stats);
    if layout.lattice == Lattice::BodyCentred && samples.boundary == Boundary::Pyramids {
        // The box faces' pyramids, after the walk's tetrahedra.
        let made = pyramids::pyramids(
            &pyramids::PyramidIn {
                l: &layout,
                iso: settings.iso,
                crossed: &buf.vertices.crossed,
                cpos: if propose {
                    &buf.clustering.cpos
                } else {
                    &mesh.positions
                },
                vertex_of: propose.then_some(&buf.clustering.vertex_of[..]),
                first_new: mesh.positions.len() as u32,
            },
            stats,
        );
        mesh.positions.extend_from_slice(&made.positions);
        mesh.indices.extend_from_slice(&made.indices);
        if buf.record
            && matches!(
                clustering,
                Clustering::None | Clustering::Integrated | Clustering::IntegratedUnchecked
            )
        {
            buf.emission.tri_cells.extend_from_slice(&made.cells);
        }
        stats.tetrahedra_total -= pyramids::pyramid_tetrahedra(samples.cells);
    }
    if clustering == Clustering::IntegratedUnchecked {
        // Without the test a vertex may lose all its triangles.
        mesh.drop_unused_vertices(&mut buf.emission.scratch);
    }
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
fn allocate(
    samples: &Samples,
    vertices: &mut VertexTables,
    candidates: &mut Vec<Candidate>,
    stats: &mut Stats,
) -> Result<(), ExtractError> {
    let t = std::time::Instant::now();
    let slots = samples.values.len();
    if slots > u32::MAX as usize {
        return Err(ExtractError::TooLarge {
            cells: samples.cells,
            limit: u32::MAX as usize,
        });
    }
    candidates.clear();
    vertices.allocate(samples);
    stats.t_allocation_s += t.elapsed().as_secs_f64();

    Ok(())
}

/// The tile rule's key of every crossing (chunked extraction with edge collapse), in `keys`;
/// empty otherwise.
fn tile_keys(
    samples: &Samples,
    settings: &ExtractSettings,
    crossed: &CrossedIndex,
    keys: &mut Vec<u64>,
) {
    let plane = samples.dims[0] * samples.dims[1];
    let planes = samples.dims[2];
    if let Some(tiling) = &settings.tiles {
        if settings.clustering == Clustering::Postprocessed {
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
        buf.vertices = VertexTables::default();
        let tables = &mut buf.clustering;
        tables.plain = Default::default();
        tables.edge_of = Vec::new();
        tables.groups = Default::default();
        pool.broadcast(|_| LAYER_WINDOW.with_borrow_mut(|w| *w = Vec::new()));
    }
    lean_bytes
}

#[cfg(test)]
pub(crate) mod testing;
