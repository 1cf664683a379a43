//! Post-processing on the mesh that marching tetrahedra wrote, for the modes that simplify
//! after the fact: edge collapse under the exact check (post-processed clustering) or
//! meshoptimizer's simplifier (the QEM anchor). Not part of MT: [`crate::Extractor`] runs it
//! after [`crate::mt::extract`].
//!
//! - `merge`: the exact local check of merging vertices of a mesh (the link condition);
//! - `collapse`: edge collapses under that check, with the tile rule of chunks: what makes a
//!   triangle degenerate (post-processed clustering), or short edges (the weld before meshopt);
//! - `simplify`: meshoptimizer's simplifier.

use rmt_mesh::Mesh;

use crate::{Clustering, ExtractSettings, Stats};

pub(crate) mod collapse;
pub(crate) mod merge;
pub(crate) mod simplify;

pub use collapse::{CollapseAttempt, CollapseOutcome};
pub(crate) use merge::MergeBuffers;
pub(crate) use simplify::compact_vertices;

/// Post-processing (counted in the geometry pass, as in the dissertation): edge collapse of
/// short edges and slivers, or meshopt after welding coincident crossings.
pub(crate) fn process(
    settings: &ExtractSettings,
    keys: Option<&[u64]>,
    near_points: usize,
    merge: &mut MergeBuffers,
    mesh: &mut Mesh,
    stats: &mut Stats,
    log: Option<&mut Vec<CollapseAttempt>>,
) {
    let clustering = settings.clustering;
    if clustering == Clustering::Postprocessed {
        let t = std::time::Instant::now();
        let h = settings.grid.h();
        let (collapses, dropped) = collapse::collapse_degenerate_tiled(
            merge,
            mesh,
            settings.collapse_threshold * h,
            crate::mt::WELD * h,
            collapse::SLIVER_RATIO,
            keys,
            log,
        );
        stats.collapses = collapses;
        stats.discarded += dropped;
        stats.t_geometry_s += t.elapsed().as_secs_f64();
    } else if clustering == Clustering::Meshopt {
        let t = std::time::Instant::now();
        if near_points > 0 {
            // meshoptimizer tells vertices apart by index: crossings on top of each other (the
            // surface through sample points) would look like seams and open holes. Weld them
            // first, under the exact check (integrated clustering groups them as one island).
            weld_coincident(merge, mesh, settings, None, stats);
        }
        stats.discarded +=
            simplify::meshopt_simplify(mesh, settings.grid.h(), settings.collapse_threshold);
        stats.t_geometry_s += t.elapsed().as_secs_f64();
    }
}

/// Welds crossings closer than [`crate::mt::WELD`] grid spacings (crossings on top of each other
/// where the surface passes through sample points) under the exact check, following the tile rule
/// when `tile_keys` is given; counted as collapses.
fn weld_coincident(
    merge: &mut MergeBuffers,
    mesh: &mut Mesh,
    settings: &ExtractSettings,
    tile_keys: Option<&[u64]>,
    stats: &mut Stats,
) {
    let (welds, dropped) = collapse::collapse_short_edges_tiled(
        merge,
        mesh,
        crate::mt::WELD * settings.grid.h(),
        tile_keys,
    );
    stats.collapses += welds;
    stats.discarded += dropped;
}
