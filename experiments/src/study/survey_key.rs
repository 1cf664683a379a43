//! From a study's design to the files the survey server reads: each configuration of the
//! study matched to one configuration of the run manifest, `questionnaire_key.csv` (the study's
//! pairs as questions, canonical sides) and `study_key.csv` (`id,object,method,shading`, the key
//! `study analyse --key` reads an export with).
//!
//! A study method matches a configuration of the run manifest's plan when the object, the
//! method, for marching tetrahedra the lattice and clustering, the shading and the
//! simplification (`none`, `meshopt:rmt`, `meshopt-locked:0.25`, ...) are equal; the
//! vertex-cache order changes nothing participants see and is not compared. Exactly one
//! configuration must match.

use std::path::Path;

use anyhow::{bail, Context, Result};
use rmt_extract::{Clustering, Lattice, Method};
use rmt_runfolder::{csv_bytes, write_atomic};

use super::design_file::{Design, MethodEntry, SimplifyTarget};
use crate::config::method_name;

/// The run's name for a simplification (`meshopt:rmt`, `meshopt-locked:5000`).
pub fn simplify_name(m: &MethodEntry) -> Option<String> {
    let s = m.simplify.as_ref()?;
    let target = match &s.target {
        SimplifyTarget::Named(n) => n.clone(),
        SimplifyTarget::Ratio(r) => r.to_string(),
        SimplifyTarget::Count(c) => c.to_string(),
    };
    let method = if s.lock_border {
        "meshopt-locked"
    } else {
        "meshopt"
    };
    Some(format!("{method}:{target}"))
}

/// What matching reads of one run configuration.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Candidate {
    /// Configuration id.
    pub id: String,
    /// Object name.
    pub object: String,
    /// Method name (`mt`, `mc`, `surface-nets`).
    pub method: String,
    /// Lattice name.
    pub lattice: String,
    /// Clustering name.
    pub clustering: String,
    /// Shading name.
    pub shading: String,
    /// Simplification name (`none`, `meshopt:rmt`, ...).
    pub simplify: String,
}

/// The candidates of a run plan, in plan order.
pub fn candidates(plan: &crate::manifest::Plan) -> Vec<Candidate> {
    plan.configurations
        .iter()
        .map(|c| {
            let e = &c.extraction;
            Candidate {
                id: c.id.clone(),
                object: c.object.clone(),
                method: method_name(e.method).to_string(),
                lattice: crate::config::lattice_name(e.method, e.lattice).to_string(),
                clustering: e.clustering.name().to_string(),
                shading: crate::manifest::shading_name(c.shading).to_string(),
                simplify: crate::simplify::simplify_name(e.simplify.as_ref()),
            }
        })
        .collect()
}

/// The configuration id of every study item (in item order) among `candidates` (`source`
/// names the manifest in errors).
pub fn match_items(design: &Design, candidates: &[Candidate], source: &str) -> Result<Vec<String>> {
    let it = &design.items;
    let mut ids = Vec::with_capacity(it.len());
    for item in 0..it.len() {
        let (o, m, s) = it.parts(item);
        let entry = &design.methods[m];
        let want_simplify = simplify_name(entry).unwrap_or_else(|| "none".into());
        let (want_lattice, want_clustering) = match entry.method {
            Method::Mt => (
                entry.lattice.unwrap_or(Lattice::BodyCentred).name(),
                entry.clustering.unwrap_or(Clustering::Integrated).name(),
            ),
            Method::Mc | Method::SurfaceNets => (Lattice::Simple.name(), Clustering::None.name()),
        };
        let matches: Vec<&Candidate> = candidates
            .iter()
            .filter(|c| {
                c.object == it.objects[o]
                    && c.method == method_name(entry.method)
                    && c.lattice == want_lattice
                    && c.clustering == want_clustering
                    && c.shading == it.shadings[s]
                    && c.simplify == want_simplify
            })
            .collect();
        match matches[..] {
            [one] => ids.push(one.id.clone()),
            [] => bail!(
                "{source}: no configuration is `{}` ({}, simplify {want_simplify}) on `{}` with \
                 {} shading",
                entry.name,
                method_name(entry.method),
                it.objects[o],
                it.shadings[s],
            ),
            _ => bail!(
                "{source}: {} configurations are `{}` on `{}` with {} shading: {}",
                matches.len(),
                entry.name,
                it.objects[o],
                it.shadings[s],
                matches
                    .iter()
                    .map(|c| c.id.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        }
    }
    Ok(ids)
}

/// Writes `questionnaire_key.csv` (the study's pairs, `Q1`.. in pair order) and
/// `study_key.csv` into the run folder `run`, for the configuration ids `ids` of the items.
pub fn write_survey_key(run: &Path, design: &Design, ids: &[String]) -> Result<()> {
    let mut questions = vec![["question", "left", "right", "kind", "variable"]
        .map(String::from)
        .to_vec()];
    for (k, p) in design.pairs.iter().enumerate() {
        questions.push(vec![
            super::export::question_id(k),
            ids[p.first].clone(),
            ids[p.second].clone(),
            "pair".into(),
            p.kind.as_str().into(),
        ]);
    }
    let mut key = vec![["id", "object", "method", "shading"]
        .map(String::from)
        .to_vec()];
    let it = &design.items;
    for (item, id) in ids.iter().enumerate() {
        let (o, m, s) = it.parts(item);
        key.push(vec![
            id.clone(),
            it.objects[o].clone(),
            it.methods[m].clone(),
            it.shadings[s].clone(),
        ]);
    }
    for (name, rows) in [("questionnaire_key.csv", questions), ("study_key.csv", key)] {
        let path = run.join(name);
        write_atomic(&path, &csv_bytes(&rows)?)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn design() -> Design {
        super::super::design_file::parse(
            "name = \"t\"\nmanifest = \"m.toml\"\nobjects = [\"rock\"]\n\
             [[methods]]\nname = \"rmt\"\nmethod = \"mt\"\n\
             [[methods]]\nname = \"mc-q\"\nmethod = \"mc\"\n\
             simplify = { method = \"meshopt\", target = \"rmt\" }\n",
            Path::new("s.toml"),
        )
        .unwrap()
    }

    fn candidate(id: &str, method: &str, shading: &str, simplify: &str) -> Candidate {
        let mt = method == "mt";
        Candidate {
            id: id.into(),
            object: "rock".into(),
            method: method.into(),
            lattice: if mt { "bcdl" } else { "simple" }.into(),
            clustering: if mt { "integrated" } else { "none" }.into(),
            shading: shading.into(),
            simplify: simplify.into(),
        }
    }

    #[test]
    fn items_match_one_configuration_each_with_the_same_simplification() {
        let d = design();
        let all = [
            candidate("a", "mt", "smooth", "none"),
            candidate("b", "mt", "flat", "none"),
            candidate("c", "mc", "smooth", "meshopt:rmt"),
            candidate("d", "mc", "flat", "meshopt:rmt"),
            candidate("e", "mc", "flat", "none"),
            candidate("f", "mc", "flat", "meshopt-locked:rmt"),
        ];
        assert_eq!(
            match_items(&d, &all, "m.toml").unwrap(),
            ["a", "b", "c", "d"]
        );
        // Without a simplified marching cubes there is nothing to show for it.
        let err = match_items(&d, &all[..2], "m.toml")
            .unwrap_err()
            .to_string();
        assert!(err.contains("simplify meshopt:rmt"), "{err}");
        // Two candidates are named.
        let twice = [
            candidate("a", "mt", "smooth", "none"),
            candidate("a2", "mt", "smooth", "none"),
        ];
        let err = match_items(&d, &twice, "m.toml").unwrap_err().to_string();
        assert!(err.contains("a, a2"), "{err}");
    }
}
