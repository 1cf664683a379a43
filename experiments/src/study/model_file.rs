//! The planted preference model of simulated participants (`--model M.toml`). Unknown keys are
//! rejected.
//!
//! ```toml
//! tie_rate = 0.2      # share of "no preference" between equal configurations, in [0, 1)
//! left_bias = 1.2     # odds multiplier of the left screen (1: none), > 0
//! fatigue = 0.5       # drift of the tie log-propensity from first to last question
//!
//! [strengths.smooth]  # log-strength per method label, per shading (every object)
//! rmt-bcdl = 0.35
//! nets-meshopt = -0.2
//!
//! [[configuration]]   # optional: one configuration's own log-strength
//! object = "bunny"
//! method = "rmt-bcdl"
//! shading = "flat"
//! log_strength = 0.5
//! ```
//!
//! Every method of the study needs a strength in every shading.

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{bail, Context, Result};
use rmt_analysis::study::simulate::PlantedModel;
use rmt_analysis::study::StudyItems;
use serde::Deserialize;

/// One `[[configuration]]` override.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConfigurationStrength {
    /// Object name.
    pub object: String,
    /// Method label.
    pub method: String,
    /// Shading name.
    pub shading: String,
    /// Its log-strength.
    pub log_strength: f64,
}

/// A model file as written.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelFile {
    /// Tie rate between equal configurations.
    pub tie_rate: f64,
    /// Left-screen odds multiplier.
    #[serde(default = "one")]
    pub left_bias: f64,
    /// Fatigue drift of ties.
    #[serde(default)]
    pub fatigue: f64,
    /// Shading -> method -> log-strength.
    pub strengths: BTreeMap<String, BTreeMap<String, f64>>,
    /// Per-configuration overrides.
    #[serde(default)]
    pub configuration: Vec<ConfigurationStrength>,
}

fn one() -> f64 {
    1.0
}

/// Reads a model file for a study's configurations.
pub fn read(path: &Path, items: &StudyItems) -> Result<PlantedModel> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    parse(&text, items).with_context(|| format!("model {}", path.display()))
}

/// Parses model text for a study's configurations.
pub fn parse(text: &str, items: &StudyItems) -> Result<PlantedModel> {
    let file: ModelFile = toml::from_str(text).map_err(|e| anyhow::anyhow!("{e}"))?;
    if !(0.0..1.0).contains(&file.tie_rate) {
        bail!("tie_rate must be in [0, 1), got {}", file.tie_rate);
    }
    if !(file.left_bias > 0.0 && file.left_bias.is_finite()) {
        bail!("left_bias must be finite and > 0, got {}", file.left_bias);
    }
    if !file.fatigue.is_finite() {
        bail!("fatigue must be finite");
    }
    for (shading, methods) in &file.strengths {
        if !items.shadings.contains(shading) {
            bail!("strengths.{shading}: the study has no shading `{shading}`");
        }
        for m in methods.keys() {
            if !items.methods.contains(m) {
                bail!("strengths.{shading}.{m}: the study has no method `{m}`");
            }
        }
    }
    let mut log_strengths = Vec::with_capacity(items.len());
    for i in 0..items.len() {
        let (_, m, s) = items.parts(i);
        let (method, shading) = (&items.methods[m], &items.shadings[s]);
        let v = file
            .strengths
            .get(shading)
            .and_then(|t| t.get(method))
            .with_context(|| format!("strengths.{shading}.{method} is missing"))?;
        if !v.is_finite() {
            bail!("strengths.{shading}.{method} must be finite");
        }
        log_strengths.push(*v);
    }
    for (k, c) in file.configuration.iter().enumerate() {
        let find = |list: &[String], name: &str, what: &str| {
            list.iter()
                .position(|x| x == name)
                .with_context(|| format!("configuration[{k}]: the study has no {what} `{name}`"))
        };
        let o = find(&items.objects, &c.object, "object")?;
        let m = find(&items.methods, &c.method, "method")?;
        let s = find(&items.shadings, &c.shading, "shading")?;
        if !c.log_strength.is_finite() {
            bail!("configuration[{k}]: log_strength must be finite");
        }
        log_strengths[items.item(o, m, s)] = c.log_strength;
    }
    Ok(PlantedModel {
        log_strengths,
        tie_rate: file.tie_rate,
        left_bias: file.left_bias,
        fatigue: file.fatigue,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn items() -> StudyItems {
        StudyItems {
            objects: vec!["a".into(), "b".into()],
            methods: vec!["x".into(), "y".into()],
            shadings: vec!["smooth".into(), "flat".into()],
        }
    }

    #[test]
    fn strengths_fill_every_configuration_and_overrides_win() {
        let m = parse(
            "tie_rate = 0.1\nleft_bias = 1.5\n[strengths.smooth]\nx = 1.0\ny = 0.0\n\
             [strengths.flat]\nx = 0.5\ny = -0.5\n\
             [[configuration]]\nobject = \"b\"\nmethod = \"y\"\nshading = \"flat\"\nlog_strength = 2.0\n",
            &items(),
        )
        .unwrap();
        let it = items();
        assert_eq!(m.log_strengths[it.item(0, 0, 1)], 0.5);
        assert_eq!(m.log_strengths[it.item(1, 1, 1)], 2.0);
        assert_eq!(m.log_strengths[it.item(0, 1, 1)], -0.5);
        assert_eq!((m.left_bias, m.fatigue), (1.5, 0.0));
    }

    #[test]
    fn missing_and_unknown_names_are_errors() {
        let err = parse(
            "tie_rate = 0.1\n[strengths.smooth]\nx = 1.0\n[strengths.flat]\nx = 0.0\ny = 0.0\n",
            &items(),
        )
        .unwrap_err();
        assert!(format!("{err:#}").contains("strengths.smooth.y"), "{err:#}");
        let err = parse("tie_rate = 0.1\n[strengths.toon]\nx = 1.0\n", &items()).unwrap_err();
        assert!(format!("{err:#}").contains("toon"), "{err:#}");
        let err = parse("tie_rate = 1.5\n[strengths.smooth]\n", &items()).unwrap_err();
        assert!(format!("{err:#}").contains("tie_rate"), "{err:#}");
    }

    #[test]
    fn the_bundled_peers_model_fits_the_peers_study() {
        let design = super::super::design_file::parse(
            include_str!("../../studies/peers.toml"),
            Path::new("experiments/studies/peers.toml"),
        )
        .unwrap();
        let m = parse(
            include_str!("../../studies/peers-model.toml"),
            &design.items,
        )
        .unwrap();
        assert_eq!(m.log_strengths.len(), 24);
    }
}
