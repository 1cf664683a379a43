//! The rows the runner writes: `raw.csv` (one row per timed repetition: the columns of
//! [`RAW_PREFIX`], then every key of `extract --json`'s measurement, [`Measured::keys`]) and `configurations.csv`
//! (the columns of [`schema::CONFIGURATIONS`]). The column lists live in
//! [`rmt_runfolder::schema`].

use std::collections::HashMap;

use anyhow::Result;
use rmt_extract::Stats;
use rmt_runfolder::csv_bytes;
use rmt_runfolder::schema::{self, RAW_PREFIX};
use serde_json::Value;

use crate::config;
use crate::finish::FinishRecord;
use crate::manifest::{Configuration, Plan};
use crate::measured::Measured;

/// The header of `raw.csv`: [`RAW_PREFIX`] then the measurement keys.
pub fn raw_header() -> Vec<String> {
    let keys = Measured::keys();
    RAW_PREFIX
        .iter()
        .map(|s| s.to_string())
        .chain(keys)
        .collect()
}

/// The configuration columns of a configuration (shared by raw rows and `configurations.csv`).
fn config_values(c: &Configuration) -> HashMap<&'static str, String> {
    let e = &c.extraction;
    let [rx, ry, rz] = e.resolution.cells();
    HashMap::from([
        ("id", c.id.clone()),
        ("object", c.object.clone()),
        ("kind", e.object.kind.name().to_string()),
        ("method", config::method_name(e.method).to_string()),
        (
            "lattice",
            config::lattice_name(e.method, e.lattice).to_string(),
        ),
        ("clustering", e.clustering.name().to_string()),
        (
            "simplify",
            crate::simplify::simplify_name(e.simplify.as_ref()),
        ),
        ("vertex_cache", e.vertex_cache.to_string()),
        ("rx", rx.to_string()),
        ("ry", ry.to_string()),
        ("rz", rz.to_string()),
        ("collapse_threshold", e.collapse_threshold.to_string()),
        ("iso", e.iso.to_string()),
        ("normals", e.normals.name().to_string()),
    ])
}

/// A JSON value as a CSV cell: null empty, strings unquoted, the rest as JSON.
fn json_cell(v: &Value) -> String {
    match v {
        Value::Null => String::new(),
        Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// The raw rows of one configuration: one per repetition, each with that repetition's stats and
/// finish steps and the shared mesh metrics.
pub fn raw_rows(
    run_id: &str,
    c: &Configuration,
    threads: usize,
    stats: &[Stats],
    finish: &[FinishRecord],
    measured: &Measured,
) -> Result<Vec<Vec<String>>> {
    raw_rows_from(run_id, c, threads, 1, stats, finish, measured)
}

/// Like [`raw_rows`], numbering the repetitions from `first` (a block of a sharded run).
pub fn raw_rows_from(
    run_id: &str,
    c: &Configuration,
    threads: usize,
    first: usize,
    stats: &[Stats],
    finish: &[FinishRecord],
    measured: &Measured,
) -> Result<Vec<Vec<String>>> {
    anyhow::ensure!(
        finish.len() == stats.len(),
        "{} repetitions with {} finish records",
        stats.len(),
        finish.len()
    );
    let mut values = config_values(c);
    values.insert("run_id", run_id.to_string());
    values.insert("threads", threads.to_string());
    let mut rows = Vec::with_capacity(stats.len());
    for (i, (s, f)) in stats.iter().zip(finish).enumerate() {
        values.insert("repetition", (first + i).to_string());
        let m = measured.repetition(s, f);
        let mut row: Vec<String> = RAW_PREFIX
            .iter()
            .map(|k| values.get(k).cloned().unwrap_or_default())
            .collect();
        row.extend(m.json()?.values().map(json_cell));
        rows.push(row);
    }
    Ok(rows)
}

/// `configurations.csv` of a plan: the columns of [`schema::CONFIGURATIONS`], then
/// [`schema::SHADING`] when some configuration is not smooth (so that the study commands pair
/// configurations within a shading, and plans that never name shading keep their bytes), then
/// [`schema::ELEVATION`] when some object sets its camera elevation (empty for the others).
pub fn configurations_csv(plan: &Plan) -> Result<Vec<u8>> {
    let shaded = plan
        .configurations
        .iter()
        .any(|c| c.shading != crate::manifest::Shading::Smooth);
    let mut header: Vec<String> = schema::CONFIGURATIONS
        .iter()
        .map(|s| s.to_string())
        .collect();
    if shaded {
        header.push(schema::SHADING.to_string());
    }
    let elevated = plan
        .configurations
        .iter()
        .any(|c| c.elevation_deg.is_some());
    if elevated {
        header.push(schema::ELEVATION.to_string());
    }
    let mut rows = vec![header];
    for c in &plan.configurations {
        let v = config_values(c);
        let mut row: Vec<String> = schema::CONFIGURATIONS
            .iter()
            .map(|k| v.get(k).cloned().unwrap_or_default())
            .collect();
        if shaded {
            row.push(crate::manifest::shading_name(c.shading).to_string());
        }
        if elevated {
            row.push(c.elevation_deg.map(|e| e.to_string()).unwrap_or_default());
        }
        rows.push(row);
    }
    Ok(csv_bytes(&rows)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn raw_header_starts_with_the_prefix_and_has_every_measurement_key() {
        let h = raw_header();
        assert_eq!(
            &h[..RAW_PREFIX.len()],
            RAW_PREFIX.map(String::from).as_slice()
        );
        for k in [
            "vertices",
            "triangles",
            "t_total_s",
            "ar_mean",
            "euler",
            "fidelity_max_h",
        ] {
            assert!(h.iter().any(|c| c == k), "missing {k}");
        }
    }

    #[test]
    fn every_configuration_column_has_a_value() {
        let plan = crate::manifest::parse(
            "name = \"t\"\n[[objects]]\nname = \"sphere\"\nresolution = 4\n\
             [[configurations]]\nobject = \"sphere\"\n",
            std::path::Path::new("t.toml"),
        )
        .unwrap()
        .plan(
            std::path::Path::new("t.toml"),
            std::path::Path::new("."),
            &Default::default(),
        )
        .unwrap();
        let values = config_values(&plan.configurations[0]);
        for column in schema::CONFIGURATION {
            assert!(values.contains_key(column), "no value for {column}");
        }
        let csv = String::from_utf8(configurations_csv(&plan).unwrap()).unwrap();
        assert_eq!(
            csv,
            "id,object,lattice,clustering,method,kind,rx,ry,rz,collapse_threshold,iso,normals,\
             simplify,vertex_cache\n\
             ss_bu,sphere,bcdl,none,mt,sphere,4,4,4,0.5,0,area,none,false\n"
        );
    }

    #[test]
    fn a_shading_column_appears_only_when_some_configuration_is_flat() {
        let plan = crate::manifest::parse(
            "name = \"t\"\n[[objects]]\nname = \"sphere\"\nresolution = 4\n\
             [matrix]\nlattices = [\"bcdl\"]\nclustering = [\"integrated\"]\n\
             shading = [\"smooth\", \"flat\"]\n",
            std::path::Path::new("t.toml"),
        )
        .unwrap()
        .plan(
            std::path::Path::new("t.toml"),
            std::path::Path::new("."),
            &Default::default(),
        )
        .unwrap();
        let csv = String::from_utf8(configurations_csv(&plan).unwrap()).unwrap();
        assert_eq!(
            csv,
            "id,object,lattice,clustering,method,kind,rx,ry,rz,collapse_threshold,iso,normals,\
             simplify,vertex_cache,shading\n\
             ss_bi,sphere,bcdl,integrated,mt,sphere,4,4,4,0.5,0,area,none,false,smooth\n\
             ss_bi_flat,sphere,bcdl,integrated,mt,sphere,4,4,4,0.5,0,area,none,false,flat\n"
        );
    }

    #[test]
    fn an_elevation_column_appears_only_when_some_object_sets_one() {
        let plan = |elevation: &str| {
            crate::manifest::parse(
                &format!(
                    "name = \"t\"\n[[objects]]\nname = \"sphere\"\nresolution = 4\n\
                     [[objects]]\nname = \"torus\"\nresolution = 4\n{elevation}\
                     [matrix]\nlattices = [\"bcdl\"]\nclustering = [\"integrated\"]\n"
                ),
                std::path::Path::new("t.toml"),
            )
            .unwrap()
            .plan(
                std::path::Path::new("t.toml"),
                std::path::Path::new("."),
                &Default::default(),
            )
        };
        let csv = |p: &Plan| String::from_utf8(configurations_csv(p).unwrap()).unwrap();
        let plain = csv(&plan("").unwrap());
        assert!(!plain.contains("elevation_deg"), "{plain}");
        let set = csv(&plan("elevation_deg = 55\n").unwrap());
        assert_eq!(
            set,
            "id,object,lattice,clustering,method,kind,rx,ry,rz,collapse_threshold,iso,normals,\
             simplify,vertex_cache,elevation_deg\n\
             ss_bi,sphere,bcdl,integrated,mt,sphere,4,4,4,0.5,0,area,none,false,\n\
             os_bi,torus,bcdl,integrated,mt,torus,4,4,4,0.5,0,area,none,false,55\n"
        );
        let err = plan("elevation_deg = 90\n").unwrap_err().to_string();
        assert!(err.contains("elevation_deg must be -89 to 89"), "{err}");
    }
}
