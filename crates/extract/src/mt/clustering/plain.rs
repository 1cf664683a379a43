//! The listing of plain MT's triangles that integrated clustering reads: every triangle of
//! the box once, in the order of the geometry pass, with its tetrahedron's gradient (and, in a
//! chunk, whether its cell is kept), then every crossing's triangles (the incidence table): the
//! stars of the quotient test. The emission later maps the same list through the output
//! vertices ([`crate::mt::emission::emit`]).

use super::*;

/// Plain MT's triangles over the whole box, in the order of the geometry pass (layer by
/// layer), into `tris` (three crossing ids each), with each triangle's source tetrahedron
/// gradient (of the linear interpolant on its source tetrahedron, up to a positive factor) in
/// `grad`; then every crossing's triangles as a CSR
/// table (`inc[inc_start[x]..inc_start[x + 1]]`, in triangle order, built in parallel by
/// [`crate::incidence::incidence_parallel`]; `inc_cursor` and `inc_parts` are its working memory). The quotient test reads a group's star from these instead of from the lattice.
/// With `keep` (a chunk) also, per triangle, whether its anchor's cell is kept (`kept`), so
/// that the emission maps the chunk's own triangles from the list too; returns the tetrahedra
/// with a triangle (of the kept cells, with `keep`).
#[allow(clippy::too_many_arguments)]
pub(crate) fn plain_triangles(
    layout: &Layout,
    iso: f32,
    crossed: &CrossedIndex,
    cpos: &[[f32; 3]],
    pool: &rayon::ThreadPool,
    keep: Option<CellRange>,
    tris: &mut Vec<u32>,
    grad: &mut Vec<[f32; 3]>,
    kept: &mut Vec<u8>,
    cells: Option<&mut Vec<u32>>,
    inc_start: &mut Vec<u32>,
    inc: &mut Vec<u32>,
    inc_cursor: &mut Vec<u32>,
    inc_parts: &mut Vec<Vec<u32>>,
) -> usize {
    let counts = layer_counts(layout, None, crossed, pool);
    let layers = counts.len();
    let total: usize = counts.iter().sum();
    overwritten(tris, 3 * total, 0, pool);
    overwritten(grad, total, [0.0; 3], pool);
    overwritten(kept, if keep.is_some() { total } else { 0 }, 0, pool);
    let record = cells.is_some();
    let mut no_cells = Vec::new();
    let cells = cells.unwrap_or(&mut no_cells);
    overwritten(cells, if record { total } else { 0 }, 0, pool);
    let mut parts = Vec::with_capacity(layers);
    let (mut rest, mut rest_src, mut rest_kept) = (&mut tris[..], &mut grad[..], &mut kept[..]);
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
            .map(|(k, (out, grad, kept, cells))| {
                let list = ListOut {
                    grad,
                    kept: keep.map(|range| (range, kept)),
                };
                let cells = record.then_some(cells);
                geometry_layer(
                    layout,
                    k,
                    iso,
                    None,
                    crossed,
                    cpos,
                    None,
                    out,
                    Some(list),
                    cells,
                )
                .0
            })
            .sum()
    });
    // Incidence in triangle order, so the table is deterministic.
    crate::incidence::incidence_parallel(
        cpos.len(),
        tris,
        inc_start,
        inc,
        inc_cursor,
        inc_parts,
        pool,
    );
    processed
}
