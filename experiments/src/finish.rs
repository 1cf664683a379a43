//! The finish steps a configuration may add after extraction, as an engine does before upload:
//! meshoptimizer's simplifier down to a triangle budget ([`Simplify`]) and its vertex-cache order
//! (`vertex_cache`), on any method. The library does the work ([`rmt_extract::finish`]); this
//! module names the settings, resolves the budget and times the steps.
//!
//! The names of the settings are [`crate::simplify`]'s.

use std::time::Instant;

use anyhow::{Context, Result};
use rmt_extract::{Clustering, Extractor, Lattice, Method, Stats};
use rmt_fields::ScalarField;
use rmt_mesh::Mesh;
use serde::Serialize;

use crate::config::Extraction;
use crate::simplify::{Simplify, SimplifyTarget};

/// The finish steps' columns of one configuration (after the extraction's measurement in
/// `raw.csv` and `extract --json`).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct FinishRecord {
    /// Triangles asked of the simplifier (empty without simplification).
    pub simplify_target: Option<usize>,
    /// The method's triangles before simplification.
    pub simplify_triangles_before: Option<usize>,
    /// The error meshoptimizer reports for the result, in grid spacings.
    pub simplify_error_h: Option<f64>,
    /// Seconds simplifying.
    pub t_simplify_s: f64,
    /// Seconds reordering for the vertex cache.
    pub t_vertex_cache_s: f64,
    /// Seconds from field to finished mesh: `t_total_s` plus the two above.
    pub t_pipeline_s: f64,
}

/// RMT's triangle count for `e`'s object, box, resolution and isovalue: integrated clustering
/// on the body-centred lattice, no finish steps.
pub fn rmt_budget(e: &Extraction, field: &dyn ScalarField, threads: usize) -> Result<usize> {
    let mut rmt = e.clone();
    rmt.method = Method::Mt;
    rmt.lattice = Lattice::BodyCentred;
    rmt.clustering = Clustering::Integrated;
    rmt.simplify = None;
    rmt.vertex_cache = false;
    let mut mesh = Mesh::default();
    let stats = Extractor::new()
        .extract(field, &rmt.settings(threads), &mut mesh)
        .context("extracting RMT for the simplifier's budget")?;
    Ok(stats.triangles)
}

/// The triangle budget of `s` for a mesh of `triangles` triangles; `rmt` is RMT's count, asked
/// for only when the target needs it.
pub fn budget(
    s: &Simplify,
    triangles: usize,
    rmt: impl FnOnce() -> Result<usize>,
) -> Result<usize> {
    Ok(match s.target {
        SimplifyTarget::Rmt => rmt()?,
        SimplifyTarget::Ratio(r) => ((triangles as f64) * r).round().max(1.0) as usize,
        SimplifyTarget::Count(n) => n,
    })
}

/// Runs a configuration's finish steps after each extraction, resolving the simplifier's budget
/// once (RMT's count is extracted on the first call that needs it).
pub struct Finisher<'a> {
    e: &'a Extraction,
    field: &'a dyn ScalarField,
    threads: usize,
    rmt: Option<usize>,
}

impl<'a> Finisher<'a> {
    /// The finisher of `e`, whose field is `field`, extracting RMT's budget on `threads`.
    pub fn new(e: &'a Extraction, field: &'a dyn ScalarField, threads: usize) -> Self {
        Self {
            e,
            field,
            threads,
            rmt: None,
        }
    }

    /// Finishes `mesh`, just extracted with `stats` (see [`apply`]).
    pub fn run(&mut self, mesh: &mut Mesh, stats: &mut Stats) -> Result<FinishRecord> {
        let target = match &self.e.simplify {
            None => None,
            Some(s) => {
                let cached = &mut self.rmt;
                let (e, field, threads) = (self.e, self.field, self.threads);
                Some(budget(s, stats.triangles, || match *cached {
                    Some(n) => Ok(n),
                    None => {
                        let n = rmt_budget(e, field, threads)?;
                        *cached = Some(n);
                        Ok(n)
                    }
                })?)
            }
        };
        Ok(apply(self.e, target, mesh, stats))
    }
}

/// Runs `e`'s finish steps on `mesh` (just extracted, with `stats`), `target` being the
/// simplifier's budget when `e` simplifies. Updates the vertex and triangle counts of `stats` to
/// the finished mesh's and returns the finish columns.
pub fn apply(
    e: &Extraction,
    target: Option<usize>,
    mesh: &mut Mesh,
    stats: &mut Stats,
) -> FinishRecord {
    let mut r = FinishRecord::default();
    if let (Some(s), Some(target)) = (&e.simplify, target) {
        let t = Instant::now();
        let out = rmt_extract::finish::simplify_to(mesh, target, s.lock_border);
        r.t_simplify_s = t.elapsed().as_secs_f64();
        let h = f64::from(e.settings(1).grid.h());
        r.simplify_target = Some(target);
        r.simplify_triangles_before = Some(out.triangles_before);
        r.simplify_error_h = Some(f64::from(out.error) / h);
    }
    if e.vertex_cache {
        let t = Instant::now();
        rmt_extract::finish::optimize_vertex_cache(mesh);
        r.t_vertex_cache_s = t.elapsed().as_secs_f64();
    }
    stats.vertices = mesh.positions.len();
    stats.triangles = mesh.triangle_count();
    r.t_pipeline_s = stats.t_total_s + r.t_simplify_s + r.t_vertex_cache_s;
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn budgets_follow_the_target() {
        let s = |t| Simplify {
            target: t,
            lock_border: false,
        };
        let never = || -> Result<usize> { anyhow::bail!("not asked") };
        assert_eq!(
            budget(&s(SimplifyTarget::Ratio(0.25)), 1000, never).unwrap(),
            250
        );
        assert_eq!(
            budget(&s(SimplifyTarget::Ratio(0.001)), 10, never).unwrap(),
            1
        );
        assert_eq!(
            budget(&s(SimplifyTarget::Count(77)), 1000, never).unwrap(),
            77
        );
        assert_eq!(
            budget(&s(SimplifyTarget::Rmt), 1000, || Ok(321)).unwrap(),
            321
        );
    }
}
