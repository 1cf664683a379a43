//! The listing of plain MT's triangles that integrated clustering reads: every triangle of
//! the box once, in the order of the geometry pass, with its source tetrahedron (and, in a
//! chunk, whether its cell is kept), then every crossing's triangles (the incidence table): the
//! stars of the quotient test. The emission later maps the same list through the output
//! vertices ([`crate::mt::emission::emit`]).

use rayon::prelude::*;

use crate::incidence::{incidence_parallel, Incidence};
use crate::mt::geometry::{geometry_layer, layer_counts, LayerOut, ListOut, Surface, Vertices};
use crate::util::overwritten;

/// Plain MT's triangles and every crossing's triangles: the stars of the quotient tests, kept
/// between extractions.
#[derive(Default)]
pub(crate) struct PlainList {
    /// Three crossing ids per triangle, in the order of the geometry pass.
    pub(crate) tris: Vec<u32>,
    /// Per triangle, its source tetrahedron: the anchor slot and the template index (bits
    /// 0-6; bit 7 set when no corner is a ghost). Test (c) computes the gradient from it
    /// ([`crate::mt::layout::Layout::gradient`]) for the few triangles it reads.
    pub(crate) source: Vec<(u32, u8)>,
    /// In a chunk: per triangle, 1 when its anchor's cell is kept (emitted by the chunk).
    pub(crate) kept: Vec<u8>,
    /// When recording ([`crate::Extractor::set_recording`]): per triangle, its anchor cell
    /// (linear index, x fastest).
    pub(crate) cells: Vec<u32>,
    /// Every crossing's triangles (CSR, in triangle order).
    pub(crate) inc: Incidence,
}

impl PlainList {
    /// Empties the list (its memory is kept); the anchor cells are left as they are (read
    /// only when recorded).
    pub(crate) fn clear(&mut self) {
        self.tris.clear();
        self.source.clear();
        self.kept.clear();
        self.inc.start.clear();
        self.inc.inc.clear();
    }

    /// Bytes held.
    pub(crate) fn bytes(&self) -> usize {
        self.tris.len() * 4
            + self.source.len() * 8
            + self.kept.len()
            + self.cells.len() * 4
            + self.inc.bytes()
    }
}

/// Plain MT's triangles over the whole box, in the order of the geometry pass (layer by
/// layer), into `list.tris` (three crossing ids each), with each triangle's source tetrahedron
/// in `list.source` (whose gradient test (c) computes when it reads the triangle); then every crossing's triangles as a CSR table (`list.inc`, in triangle order,
/// built in parallel by [`incidence_parallel`]). The quotient test reads a group's star from
/// these instead of from the lattice. In a chunk (`surface.keep`; every anchor is walked all
/// the same) also, per triangle, whether its anchor's cell is kept (`list.kept`), so that the
/// emission maps the chunk's own triangles from the list too; with `record`, each triangle's
/// anchor cell (`list.cells`). `cpos`: the crossings' positions. Returns the tetrahedra with a
/// triangle (of the kept cells, in a chunk).
pub(crate) fn plain_triangles(
    surface: &Surface,
    cpos: &[[f32; 3]],
    record: bool,
    list: &mut PlainList,
    pool: &rayon::ThreadPool,
) -> usize {
    let keep = surface.keep;
    // Every anchor is walked; the kept cells are marked.
    let walk = Surface {
        keep: None,
        ..*surface
    };
    let PlainList {
        tris,
        source,
        kept,
        cells,
        inc,
    } = list;
    let cells = record.then_some(cells);
    let counts = layer_counts(walk.l, None, walk.crossed, pool);
    let layers = counts.len();
    let total: usize = counts.iter().sum();
    overwritten(tris, 3 * total, 0, pool);
    overwritten(source, total, (0, 0), pool);
    overwritten(kept, if keep.is_some() { total } else { 0 }, 0, pool);
    let record = cells.is_some();
    let mut no_cells = Vec::new();
    let cells = cells.unwrap_or(&mut no_cells);
    overwritten(cells, if record { total } else { 0 }, 0, pool);
    let mut parts = Vec::with_capacity(layers);
    let (mut rest, mut rest_src, mut rest_kept) = (&mut tris[..], &mut source[..], &mut kept[..]);
    let mut rest_cells = &mut cells[..];
    for &n in &counts {
        let (head, tail) = rest.split_at_mut(3 * n);
        let (head_src, tail_src) = rest_src.split_at_mut(n);
        let (head_kept, tail_kept) = rest_kept.split_at_mut(if keep.is_some() { n } else { 0 });
        let (head_cells, tail_cells) = rest_cells.split_at_mut(if record { n } else { 0 });
        parts.push((head, head_src, head_kept, head_cells));
        rest = tail;
        rest_src = tail_src;
        rest_kept = tail_kept;
        rest_cells = tail_cells;
    }
    let processed: usize = pool.install(|| {
        parts
            .into_par_iter()
            .enumerate()
            .map(|(k, (out, source, kept, cells))| {
                let list = ListOut {
                    source,
                    kept: keep.map(|range| (range, kept)),
                };
                let cells = record.then_some(cells);
                let vertices = Vertices {
                    positions: cpos,
                    map: None,
                };
                let out = LayerOut {
                    out,
                    list: Some(list),
                    cells,
                    flip: false,
                };
                geometry_layer(&walk, k, vertices, out).0
            })
            .sum()
    });
    // Incidence in triangle order, so the table is deterministic.
    incidence_parallel(cpos.len(), tris, inc, pool);
    processed
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mt::layout::Layout;
    use crate::mt::testing::{extracted, settings_on, test_pool, wavy};
    use crate::{Clustering, Lattice};

    #[test]
    fn the_list_is_plain_mts_mesh_in_its_order_with_every_crossings_triangles() {
        // Plain MT (no clustering) writes exactly the triangles the listing lists, in the same
        // order; the incidence table names each triangle under each of its corners, once.
        let field = wavy();
        let mut listed = 0;
        for threads in [1, 2] {
            let pool = test_pool(threads);
            for lattice in [Lattice::BodyCentred, Lattice::Simple] {
                for cells in [[5, 4, 6], [14, 12, 13]] {
                    let settings = settings_on(cells, lattice, Clustering::None);
                    let (samples, buf, mesh, stats) = extracted(&field, &settings, &pool);
                    let l = Layout::new(&samples, lattice);
                    let surface = Surface {
                        l: &l,
                        iso: settings.iso,
                        keep: None,
                        crossed: &buf.vertices.crossed,
                    };
                    let what = format!("{lattice:?} {cells:?} threads={threads}");
                    for record in [false, true] {
                        let mut list = PlainList::default();
                        let processed =
                            plain_triangles(&surface, &mesh.positions, record, &mut list, &pool);
                        assert_eq!(list.tris, mesh.indices, "{what}");
                        assert_eq!(processed, stats.tetrahedra_processed, "{what}");
                        let n = list.tris.len() / 3;
                        assert_eq!(list.source.len(), n, "{what}");
                        assert!(list.kept.is_empty(), "{what}: no chunk, no flags");
                        assert_eq!(list.cells.len(), if record { n } else { 0 }, "{what}");
                        let (start, inc) = (&list.inc.start, &list.inc.inc);
                        assert_eq!(start.len(), mesh.positions.len() + 1, "{what}");
                        assert_eq!(inc.len(), list.tris.len(), "{what}");
                        for (t, tri) in list.tris.chunks_exact(3).enumerate() {
                            for &v in tri {
                                let v = v as usize;
                                let star = &inc[start[v] as usize..start[v + 1] as usize];
                                let times = star.iter().filter(|&&s| s == t as u32).count();
                                assert_eq!(times, 1, "{what}: triangle {t} at {v}");
                            }
                        }
                        listed += n;
                    }
                }
            }
        }
        assert!(listed > 2000, "only {listed} triangles listed");
    }
}
