//! One mesh's full record, the columns of `raw.csv` after the configuration and the keys of
//! `extract --json` after it: the extraction's [`Measurement`] (counters, stage times, topology,
//! quality, fidelity), the finish steps' [`FinishRecord`], the rendering cost
//! ([`rmt_render::cost::RenderCost`]: quad occupancy, meshoptimizer's analyzers, buffer sizes)
//! and `t_cost_s`, the seconds that measuring the cost took.
//!
//! Counters and times change from repetition to repetition ([`Measured::repetition`]); the mesh
//! measures are taken once, on the last repetition's mesh (every repetition's mesh is checked
//! identical). A mesh with no triangle has no rendering cost: its cost cells are empty.

use std::time::Instant;

use anyhow::{Context, Result};
use rmt_extract::{ExtractSettings, Measurement, Stats};
use rmt_fields::ScalarField;
use rmt_mesh::Mesh;
use rmt_render::cost::{RenderCost, RenderCostMeter};
use serde_json::{Map, Value};

use crate::config::measurement_json;
use crate::finish::FinishRecord;

/// Everything measured about one configuration's mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Measured {
    /// The extraction's measurement (its stats those of the finished mesh: see
    /// [`crate::finish::apply`]).
    pub measurement: Measurement,
    /// The finish steps.
    pub finish: FinishRecord,
    /// The rendering cost (None for a mesh without triangles).
    pub cost: Option<RenderCost>,
    /// Seconds measuring the rendering cost.
    pub t_cost_s: f64,
}

impl Measured {
    /// The record of one repetition: its stats and finish times, the shared mesh measures.
    pub fn repetition(&self, stats: &Stats, finish: &FinishRecord) -> Measured {
        Measured {
            measurement: Measurement {
                stats: stats.clone(),
                ..self.measurement.clone()
            },
            finish: finish.clone(),
            ..self.clone()
        }
    }

    /// The record as an ordered JSON map: the measurement's keys, the finish keys, the cost keys
    /// (null without a cost), `t_cost_s`.
    pub fn json(&self) -> Result<Map<String, Value>> {
        let mut map = measurement_json(&self.measurement)?;
        for (part, value) in [
            ("finish", serde_json::to_value(&self.finish)),
            (
                "rendering cost",
                serde_json::to_value(self.cost.unwrap_or_default()),
            ),
        ] {
            let value = value.with_context(|| format!("serialising the {part}"))?;
            let Value::Object(fields) = value else {
                anyhow::bail!("the {part} serialised to {value}, not an object");
            };
            let measured = part == "finish" || self.cost.is_some();
            map.extend(
                fields
                    .into_iter()
                    .map(|(k, v)| (k, if measured { v } else { Value::Null })),
            );
        }
        map.insert("t_cost_s".into(), serde_json::json!(self.t_cost_s));
        Ok(map)
    }

    /// The keys of [`Measured::json`], in order.
    pub fn keys() -> Vec<String> {
        Measured::default()
            .json()
            .map(|m| m.keys().cloned().collect())
            .unwrap_or_default()
    }
}

/// Measures a finished `mesh`: validation, quality and fidelity (`field`, when it knows its
/// distance) by [`rmt_extract::measure`], then the rendering cost with `meter` (none without a
/// meter).
pub fn measure(
    mesh: &Mesh,
    stats: &Stats,
    finish: &FinishRecord,
    field: Option<&dyn ScalarField>,
    settings: &ExtractSettings,
    meter: Option<&mut RenderCostMeter>,
) -> Result<Measured> {
    let measurement = rmt_extract::measure(mesh, stats, field, settings);
    let t = Instant::now();
    let cost = match meter {
        Some(meter) if mesh.triangle_count() > 0 => Some(
            meter
                .measure(mesh)
                .context("measuring the rendering cost")?,
        ),
        _ => None,
    };
    Ok(Measured {
        measurement,
        finish: finish.clone(),
        cost,
        t_cost_s: t.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_run_measurement_finish_cost_then_cost_time() {
        let keys = Measured::keys();
        let at = |k: &str| keys.iter().position(|x| x == k).unwrap();
        assert_eq!(keys[0], "vertices");
        assert!(at("fidelity_max_h") < at("simplify_target"));
        assert!(at("t_pipeline_s") < at("quad_occupancy_1080"));
        assert!(at("glb_bytes") < at("t_cost_s"));
        assert_eq!(keys.last().map(String::as_str), Some("t_cost_s"));
        let unique: std::collections::HashSet<&String> = keys.iter().collect();
        assert_eq!(unique.len(), keys.len(), "a key appears twice");
    }

    #[test]
    fn an_empty_mesh_has_empty_cost_cells_and_a_measured_one_has_numbers() {
        let empty = Measured::default().json().unwrap();
        assert_eq!(empty["quad_occupancy_1080"], Value::Null);
        assert_eq!(empty["glb_bytes"], Value::Null);
        assert_eq!(empty["t_pipeline_s"], serde_json::json!(0.0));
        let mesh = rmt_render::shapes::uv_sphere(1.0, 16, 8);
        let settings = ExtractSettings::new(
            rmt_extract::Grid::cube(4, 1.0),
            rmt_extract::Lattice::Simple,
            rmt_extract::Clustering::None,
        );
        let m = measure(
            &mesh,
            &Stats::default(),
            &FinishRecord::default(),
            None,
            &settings,
            Some(&mut RenderCostMeter::new()),
        )
        .unwrap();
        let json = m.json().unwrap();
        assert_eq!(
            json["index_bytes"],
            serde_json::json!(12 * mesh.triangle_count())
        );
        assert!(json["quad_occupancy_1080"]
            .as_f64()
            .is_some_and(|o| o > 0.0 && o <= 1.0));
    }
}
