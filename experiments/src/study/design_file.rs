//! The study design file (`experiments/studies/*.toml`): what a perception study of methods
//! under shadings asks, before anything is rendered. Unknown keys are rejected.
//!
//! ```toml
//! name = "peers"
//! manifest = "../manifests/peers-study.toml"  # the run manifest `study run` renders
//! objects = ["asteroid", "bunny", "chunk"]      # object names of that manifest
//! shadings = ["smooth", "flat"]
//! questions = 24                 # pair questions per participant (at most all pairs)
//! controls = 2                   # control questions per participant
//! seconds_per_question = 12.0    # expected answer time
//! seed = 1                       # balanced subsets, sides and orders
//!
//! [power]                        # the power table (every key optional)
//! reference = "rmt-bcdl"         # default: the first method
//! effect = 0.6                   # decided share to detect
//! tie_rate = 0.2                 # assumed share of "no preference"
//! alpha = 0.05
//!
//! [[methods]]                    # at an equal triangle budget
//! name = "rmt-bcdl"              # the study's label (letters, digits, '-', '.')
//! method = "mt"                  # mt | mc | surface-nets
//! lattice = "bcdl"               # mt only (default bcdl)
//! clustering = "integrated"      # mt only (default integrated)
//! simplify = { method = "meshopt", target = "rmt" }   # optional: target "rmt", a ratio
//!                                # in (0, 1] or a triangle count; lock_border = true
//!
//! [pairs]                        # optional: which pairs to ask
//! methods = "all"                # or [["rmt-bcdl", "mc-meshopt"], ...]
//! shading = true                 # also shading pairs within a method (default true)
//! ```
//!
//! A question compares two configurations of one object that differ in one variable: two
//! methods in one shading, or (with `pairs.shading`) two shadings of one method.

use std::path::{Path, PathBuf};

use rmt_analysis::study::{study_pairs, StudyItems, StudyPair};
use rmt_extract::{Clustering, Lattice, Method};
use serde::Deserialize;

use crate::manifest::Shading;

/// Why a design file cannot be used; every message names the file.
#[derive(Debug, thiserror::Error)]
pub enum DesignError {
    /// The file could not be read.
    #[error("cannot read study {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// Malformed TOML, an unknown key or a wrong type (with line and column).
    #[error("study {}: {message}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// The parser's message.
        message: String,
    },
    /// A value that parses but does not make a study.
    #[error("study {}: {key}: {message}", path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// Where.
        key: String,
        /// What is wrong.
        message: String,
    },
}

/// `simplify = { method = "meshopt", target = ... }`: a simplifier run after the method, down
/// to a triangle count (the runner's key of the same name; the study only names it).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Simplify {
    /// The simplifier: `meshopt`.
    pub method: String,
    /// `"rmt"` (RMT's count on the same object and resolution), a ratio or a count.
    pub target: SimplifyTarget,
    /// meshopt's border-locked variant.
    #[serde(default)]
    pub lock_border: bool,
}

/// The triangle count a simplifier aims at.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum SimplifyTarget {
    /// A triangle count.
    Count(u64),
    /// A share of the method's own triangles, in (0, 1].
    Ratio(f64),
    /// A named target: `rmt`.
    Named(String),
}

/// One `[[methods]]` entry.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MethodEntry {
    /// The study's label.
    pub name: String,
    /// The extraction method.
    pub method: Method,
    /// Marching tetrahedra's lattice (default bcdl).
    #[serde(default)]
    pub lattice: Option<Lattice>,
    /// Marching tetrahedra's clustering (default integrated).
    #[serde(default)]
    pub clustering: Option<Clustering>,
    /// A simplifier after the method.
    #[serde(default)]
    pub simplify: Option<Simplify>,
}

/// `[pairs]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PairsEntry {
    /// `"all"` or a list of method-label pairs.
    #[serde(default)]
    pub methods: Option<MethodPairs>,
    /// Also ask shading pairs (default true).
    #[serde(default)]
    pub shading: Option<bool>,
}

/// `"all"` or `[["a", "b"], ...]`.
#[derive(Clone, Debug, Deserialize)]
#[serde(untagged)]
pub enum MethodPairs {
    /// A keyword: `all`.
    Keyword(String),
    /// Explicit pairs of labels.
    List(Vec<[String; 2]>),
}

/// `[power]`.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PowerEntry {
    /// The reference method's label.
    #[serde(default)]
    pub reference: Option<String>,
    /// Decided share to detect (default 0.6).
    #[serde(default)]
    pub effect: Option<f64>,
    /// Assumed tie rate (default 0.2).
    #[serde(default)]
    pub tie_rate: Option<f64>,
    /// Test level (default 0.05).
    #[serde(default)]
    pub alpha: Option<f64>,
}

/// A design file as written.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DesignFile {
    /// Study name.
    pub name: String,
    /// Free text.
    #[serde(default)]
    pub description: Option<String>,
    /// The run manifest, relative to the design file.
    pub manifest: PathBuf,
    /// Object names of the manifest.
    pub objects: Vec<String>,
    /// Shadings (default smooth and flat).
    #[serde(default)]
    pub shadings: Option<Vec<Shading>>,
    /// The methods.
    pub methods: Vec<MethodEntry>,
    /// Pair questions per participant (default: all pairs).
    #[serde(default)]
    pub questions: Option<usize>,
    /// Control questions per participant (default 2).
    #[serde(default)]
    pub controls: Option<usize>,
    /// Expected seconds per answer (default 12).
    #[serde(default)]
    pub seconds_per_question: Option<f64>,
    /// Seed of the plan (default 1).
    #[serde(default)]
    pub seed: Option<u64>,
    /// Which pairs.
    #[serde(default)]
    pub pairs: Option<PairsEntry>,
    /// The power table's assumptions.
    #[serde(default)]
    pub power: Option<PowerEntry>,
}

/// A checked design.
#[derive(Clone, Debug)]
pub struct Design {
    /// Study name.
    pub name: String,
    /// The run manifest, resolved against the design file's folder.
    pub manifest: PathBuf,
    /// The methods as written.
    pub methods: Vec<MethodEntry>,
    /// Shadings, in order.
    pub shadings: Vec<Shading>,
    /// Configurations.
    pub items: StudyItems,
    /// Pairs asked.
    pub pairs: Vec<StudyPair>,
    /// Pair questions per participant.
    pub questions: usize,
    /// Controls per participant.
    pub controls: usize,
    /// Expected seconds per answer.
    pub seconds_per_question: f64,
    /// Seed of the plan.
    pub seed: u64,
    /// Reference method index.
    pub reference: usize,
    /// Effect to detect.
    pub effect: f64,
    /// Assumed tie rate.
    pub tie_rate: f64,
    /// Test level.
    pub alpha: f64,
}

impl Design {
    /// Questions each participant answers, controls included.
    pub fn questions_per_participant(&self) -> usize {
        self.questions + self.controls
    }

    /// Expected minutes per participant.
    pub fn expected_minutes(&self) -> f64 {
        self.questions_per_participant() as f64 * self.seconds_per_question / 60.0
    }
}

fn label_ok(s: &str) -> bool {
    !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '.')
}

/// Reads and checks a design file.
pub fn read(path: &Path) -> Result<Design, DesignError> {
    let text = std::fs::read_to_string(path).map_err(|source| DesignError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    parse(&text, path)
}

/// Parses and checks design text; `path` names it in errors and anchors `manifest`.
pub fn parse(text: &str, path: &Path) -> Result<Design, DesignError> {
    let file: DesignFile = toml::from_str(text).map_err(|e| DesignError::Parse {
        path: path.to_path_buf(),
        message: e.to_string().trim_end().to_string(),
    })?;
    let invalid = |key: &str, message: String| DesignError::Invalid {
        path: path.to_path_buf(),
        key: key.to_string(),
        message,
    };
    if file.objects.is_empty() {
        return Err(invalid("objects", "the list is empty".into()));
    }
    for (i, o) in file.objects.iter().enumerate() {
        if !label_ok(o) || file.objects[..i].contains(o) {
            return Err(invalid(
                "objects",
                format!("`{o}` must be a unique name of letters, digits, '-' or '.'"),
            ));
        }
    }
    if file.methods.len() < 2 {
        return Err(invalid(
            "methods",
            "a study compares at least two methods".into(),
        ));
    }
    for (i, m) in file.methods.iter().enumerate() {
        let key = format!("methods[{i}] ({})", m.name);
        if !label_ok(&m.name) || file.methods[..i].iter().any(|x| x.name == m.name) {
            return Err(invalid(
                &key,
                "name must be unique letters, digits, '-' or '.'".into(),
            ));
        }
        if m.method != Method::Mt && (m.lattice.is_some() || m.clustering.is_some()) {
            return Err(invalid(
                &key,
                "only marching tetrahedra (method = \"mt\") takes a lattice or clustering".into(),
            ));
        }
        if let Some(s) = &m.simplify {
            if s.method != "meshopt" {
                return Err(invalid(
                    &format!("{key}.simplify.method"),
                    format!("unknown simplifier `{}` (expected meshopt)", s.method),
                ));
            }
            match &s.target {
                SimplifyTarget::Named(n) if n != "rmt" => {
                    return Err(invalid(
                        &format!("{key}.simplify.target"),
                        format!("unknown target `{n}` (expected \"rmt\", a ratio or a count)"),
                    ))
                }
                SimplifyTarget::Ratio(r) if !(*r > 0.0 && *r <= 1.0) => {
                    return Err(invalid(
                        &format!("{key}.simplify.target"),
                        format!("a ratio must be in (0, 1], got {r}"),
                    ))
                }
                SimplifyTarget::Count(0) => {
                    return Err(invalid(
                        &format!("{key}.simplify.target"),
                        "a count must be at least 1".into(),
                    ))
                }
                _ => {}
            }
        }
    }
    let shadings = file
        .shadings
        .clone()
        .unwrap_or_else(|| vec![Shading::Smooth, Shading::Flat]);
    if shadings.is_empty() || (shadings.len() == 2 && shadings[0] == shadings[1]) {
        return Err(invalid("shadings", "must list distinct shadings".into()));
    }
    let items = StudyItems {
        objects: file.objects.clone(),
        methods: file.methods.iter().map(|m| m.name.clone()).collect(),
        shadings: shadings
            .iter()
            .map(|&s| crate::manifest::shading_name(s).to_string())
            .collect(),
    };
    let index_of = |label: &str, key: &str| {
        items
            .methods
            .iter()
            .position(|m| m == label)
            .ok_or_else(|| invalid(key, format!("no method named `{label}`")))
    };
    let pairs_entry = file.pairs.clone();
    let method_pairs: Option<Vec<(usize, usize)>> =
        match pairs_entry.as_ref().and_then(|p| p.methods.clone()) {
            None => None,
            Some(MethodPairs::Keyword(k)) if k == "all" => None,
            Some(MethodPairs::Keyword(k)) => {
                return Err(invalid(
                    "pairs.methods",
                    format!("`{k}`: expected \"all\" or a list of pairs"),
                ))
            }
            Some(MethodPairs::List(list)) => {
                let mut out = Vec::new();
                for [a, b] in &list {
                    let (i, j) = (index_of(a, "pairs.methods")?, index_of(b, "pairs.methods")?);
                    if i == j {
                        return Err(invalid("pairs.methods", format!("`{a}` against itself")));
                    }
                    out.push((i.min(j), i.max(j)));
                }
                out.sort_unstable();
                out.dedup();
                Some(out)
            }
        };
    let shading_pairs = pairs_entry.and_then(|p| p.shading).unwrap_or(true) && shadings.len() > 1;
    let pairs = study_pairs(&items, method_pairs.as_deref(), shading_pairs);
    let questions = file.questions.unwrap_or(pairs.len());
    if questions == 0 || questions > pairs.len() {
        return Err(invalid(
            "questions",
            format!(
                "must be 1 to the {} pairs the study asks, got {questions}",
                pairs.len()
            ),
        ));
    }
    let power = file.power.clone().unwrap_or_default();
    let reference = match &power.reference {
        Some(r) => index_of(r, "power.reference")?,
        None => 0,
    };
    let effect = power.effect.unwrap_or(0.6);
    let tie_rate = power.tie_rate.unwrap_or(0.2);
    let alpha = power.alpha.unwrap_or(0.05);
    if !(effect > 0.5 && effect < 1.0) {
        return Err(invalid(
            "power.effect",
            format!("must be in (0.5, 1), got {effect}"),
        ));
    }
    if !(0.0..1.0).contains(&tie_rate) {
        return Err(invalid(
            "power.tie_rate",
            format!("must be in [0, 1), got {tie_rate}"),
        ));
    }
    if !(alpha > 0.0 && alpha < 0.5) {
        return Err(invalid(
            "power.alpha",
            format!("must be in (0, 0.5), got {alpha}"),
        ));
    }
    let seconds = file.seconds_per_question.unwrap_or(12.0);
    if !(seconds > 0.0 && seconds.is_finite()) {
        return Err(invalid(
            "seconds_per_question",
            format!("must be > 0, got {seconds}"),
        ));
    }
    let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
    Ok(Design {
        name: file.name,
        manifest: base.join(&file.manifest),
        methods: file.methods,
        shadings,
        items,
        pairs,
        questions,
        controls: file.controls.unwrap_or(2),
        seconds_per_question: seconds,
        seed: file.seed.unwrap_or(1),
        reference,
        effect,
        tie_rate,
        alpha,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const PEERS: &str = include_str!("../../studies/peers.toml");

    #[test]
    fn the_peers_study_parses_with_every_method_and_simplify() {
        let d = parse(PEERS, Path::new("experiments/studies/peers.toml")).unwrap();
        assert_eq!(d.items.objects.len(), 3);
        assert_eq!(d.items.methods.len(), 4);
        assert_eq!(d.shadings, [Shading::Smooth, Shading::Flat]);
        assert_eq!(d.pairs.len(), 48);
        let simplified: Vec<&MethodEntry> =
            d.methods.iter().filter(|m| m.simplify.is_some()).collect();
        assert_eq!(simplified.len(), 2);
        assert_eq!(
            simplified[0].simplify.as_ref().unwrap().target,
            SimplifyTarget::Named("rmt".into())
        );
        assert_eq!(d.methods[2].method, Method::SurfaceNets);
        assert!(d.manifest.ends_with("peers-study.toml"));
        assert!(d.expected_minutes() > 1.0);
    }

    #[test]
    fn bad_designs_name_the_key() {
        let base = "name = \"t\"\nmanifest = \"m.toml\"\nobjects = [\"a\"]\n\
                    [[methods]]\nname = \"x\"\nmethod = \"mt\"\n";
        let with = |extra: &str| {
            parse(&format!("{base}{extra}"), Path::new("s.toml"))
                .unwrap_err()
                .to_string()
        };
        let err = with("");
        assert!(err.contains("at least two methods"), "{err}");
        let two = "[[methods]]\nname = \"y\"\nmethod = \"mc\"\n";
        let err = with(&format!("{two}questions = 99\n"));
        assert!(err.contains("questions"), "{err}");
        let err = with("[[methods]]\nname = \"y\"\nmethod = \"mc\"\nlattice = \"bcdl\"\n");
        assert!(err.contains("methods[1] (y)"), "{err}");
        let err = with(
            "[[methods]]\nname = \"y\"\nmethod = \"mc\"\n\
             simplify = { method = \"qem\", target = \"rmt\" }\n",
        );
        assert!(err.contains("qem"), "{err}");
        let err = with(
            "[[methods]]\nname = \"y\"\nmethod = \"mc\"\n\
             simplify = { method = \"meshopt\", target = 1.5 }\n",
        );
        assert!(err.contains("ratio"), "{err}");
        let err = with(&format!("{two}[pairs]\nmethods = [[\"x\", \"z\"]]\n"));
        assert!(err.contains("no method named `z`"), "{err}");
        let err = with(&format!("{two}bogus = 1\n"));
        assert!(err.contains("bogus"), "{err}");
        let ok = parse(&format!("{base}{two}"), Path::new("s.toml")).unwrap();
        // One object, two methods, two shadings: 2 method pairs and 2 shading pairs.
        assert_eq!(ok.pairs.len(), 4);
        assert_eq!(ok.questions, 4);
    }
}
