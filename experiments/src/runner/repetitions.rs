//! The timed extractions of one configuration: warm-up, then timed repetitions with one reused
//! extractor, each followed by the configuration's finish steps ([`crate::finish`]), every
//! repetition's finished mesh checked identical to the first by its fingerprint; then the mesh
//! measured once ([`crate::measured`]), its rendering cost included.

use anyhow::{bail, Result};
use indicatif::ProgressBar;
use rmt_extract::{Extractor, Stats};
use rmt_fields::ScalarField;
use rmt_mesh::Mesh;
use rmt_render::cost::RenderCostMeter;

use crate::finish::{FinishRecord, Finisher};
use crate::manifest::{Configuration, Plan};
use crate::measured::{self, Measured};

/// What one configuration produced.
pub struct ConfigResult {
    /// Stats of every timed repetition (vertex and triangle counts of the finished mesh).
    pub stats: Vec<Stats>,
    /// The finish steps of every timed repetition.
    pub finish: Vec<FinishRecord>,
    /// Measurement of the last repetition's mesh.
    pub measured: Measured,
    /// The last repetition's mesh.
    pub mesh: Mesh,
}

/// Runs one configuration: warm-up, then timed repetitions with one reused extractor; checks
/// that every repetition's mesh is identical.
pub fn run_configuration(
    c: &Configuration,
    field: &dyn ScalarField,
    plan: &Plan,
    meter: Option<&mut RenderCostMeter>,
    bar: &ProgressBar,
) -> Result<ConfigResult> {
    run_repetitions(c, field, plan, 1, plan.repetitions, meter, bar)
}

/// Runs timed repetitions `first..=last` of one configuration (a work unit of a shard), after
/// the plan's warm-up, with one reused extractor; checks that every repetition's mesh is
/// identical.
pub fn run_repetitions(
    c: &Configuration,
    field: &dyn ScalarField,
    plan: &Plan,
    first: usize,
    last: usize,
    meter: Option<&mut RenderCostMeter>,
    bar: &ProgressBar,
) -> Result<ConfigResult> {
    let settings = c.extraction.settings(plan.threads);
    let mut extractor = Extractor::new();
    let mut finisher = Finisher::new(&c.extraction, field, plan.threads);
    let mut mesh = Mesh::default();
    for _ in 0..plan.warmup {
        let mut s = extractor.extract(field, &settings, &mut mesh)?;
        finisher.run(&mut mesh, &mut s)?;
        bar.inc(1);
    }
    let n = last + 1 - first.min(last + 1);
    let mut stats = Vec::with_capacity(n);
    let mut finish = Vec::with_capacity(n);
    let mut first_print = None;
    for rep in first..=last {
        let mut s = extractor.extract(field, &settings, &mut mesh)?;
        finish.push(finisher.run(&mut mesh, &mut s)?);
        stats.push(s);
        let print = mesh_fingerprint(&mesh);
        match first_print {
            None => first_print = Some(print),
            Some(f) if f != print => bail!(
                "repetition {rep} produced a different mesh than repetition {first}: the \
                 extraction is not deterministic, so metrics measured on one mesh would not hold \
                 for all"
            ),
            Some(_) => {}
        }
        bar.inc(1);
    }
    let last = stats.last().cloned().unwrap_or_default();
    let last_finish = finish.last().cloned().unwrap_or_default();
    let measured = measured::measure(&mesh, &last, &last_finish, Some(field), &settings, meter)
        .map_err(|e| e.context(format!("measuring configuration {}", c.id)))?;
    Ok(ConfigResult {
        stats,
        finish,
        measured,
        mesh,
    })
}

/// A 64-bit FNV-1a fingerprint of a mesh's positions, normals and indices (bit patterns).
pub fn mesh_fingerprint(mesh: &Mesh) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |w: u32| {
        for b in w.to_le_bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    };
    eat(mesh.positions.len() as u32);
    for p in mesh.positions.iter().chain(&mesh.normals) {
        p.iter().for_each(|c| eat(c.to_bits()));
    }
    eat(mesh.indices.len() as u32);
    mesh.indices.iter().for_each(|&i| eat(i));
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fingerprint_sees_any_change() {
        let mut m = Mesh::from_triangles(
            vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![0, 1, 2],
        );
        let a = mesh_fingerprint(&m);
        assert_eq!(a, mesh_fingerprint(&m.clone()));
        m.indices = vec![0, 2, 1];
        assert_ne!(a, mesh_fingerprint(&m));
        m.indices = vec![0, 1, 2];
        m.positions[2][1] = 1.0000001;
        assert_ne!(a, mesh_fingerprint(&m));
    }
}
