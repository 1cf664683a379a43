//! A survey's study: the questions of a rendered run folder, the configurations behind their
//! anonymous names, and each participant's plan (question order and left/right swaps).
//!
//! The questions come from `<run>/questionnaire_key.csv` when `experiments questionnaire` has
//! been run (so the survey asks exactly the questions of `questions.csv`, with their canonical
//! left and right), and are otherwise planned from `configurations.csv` the same way
//! (`rmt_render::questionnaire::plan_questions`, same seed), without composing any GIF: the
//! page shows the single turntables of `render/` side by side. Optional control questions show
//! one animation on both sides.
//!
//! A participant's plan:
//! - **order**: all questions (controls included) shuffled by a generator seeded with the
//!   participant's token;
//! - **swaps**: participants are taken in pairs by arrival (1 and 2, 3 and 4, ...); the first
//!   of a pair gets a seeded pattern that swaps half of the real questions, the second the
//!   complement. Every question is therefore shown swapped to half the participants (up to one),
//!   and every participant sees half of the questions swapped (up to one). Controls are never
//!   swapped (both sides are the same animation).
//!
//! **Balanced subsets** ([`Study::with_subsets`]): with many questions, each participant answers
//! `q` of the `R` real questions (controls stay in every session). The real questions are put
//! in one seeded random cycle; the `s`-th participant to arrive takes the `q` that start at
//! position `(s - 1) q` of the cycle (wrapping), so consecutive participants take consecutive
//! windows and every question is answered by the same number of participants, up to one. The
//! `k`-th showing of a question (`k` the laps of the cycle before it) is swapped when
//! `k + flip(question)` is odd (`flip` a seeded coin per question): each question is shown each
//! way equally often, up to one. The order is still shuffled by the token. This is the rule of
//! `rmt_analysis::study::design::assign`, which plans simulated participants.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use rmt_render::names::SplitMix64;
use rmt_render::questionnaire::{plan_questions, Manifest, QuestionKind, QuestionnaireOptions};
use rmt_render::run_folder::{
    read_key, CONFIGURATIONS_FILE, KEY_FILE, QUESTIONNAIRE_KEY_FILE, RENDER_DIR,
};
use serde::{Deserialize, Serialize};

/// Errors while reading a study from a run folder.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// A file of the run folder could not be read or is malformed.
    #[error(transparent)]
    Render(#[from] rmt_render::RenderError),
    /// A file exists but does not fit the rest of the run.
    #[error("{path}: {message}")]
    BadFile {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// Something needed is missing.
    #[error("{0}")]
    Missing(String),
}

/// One configuration of the study.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct StudyConfiguration {
    /// Configuration id (`ss_bi`); never sent to participants.
    pub id: String,
    /// Anonymous animation name (`bcdf`), the only name participants see.
    pub name: String,
    /// Values of [`Study::variables`], in order; never sent to participants.
    pub values: Vec<String>,
}

/// One question of the study.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct StudyQuestion {
    /// `Q1`.. for real questions (as in `questions.csv`), `C1`.. for controls added by the server.
    pub id: String,
    /// `pair`, `reversed` or `control`.
    pub kind: String,
    /// Canonical left configuration (index into [`Study::configurations`]).
    pub left: usize,
    /// Canonical right configuration.
    pub right: usize,
    /// The variable in which the sides differ (empty for controls).
    pub variable: String,
}

impl StudyQuestion {
    /// Whether this is a control question (the same animation on both sides).
    pub fn is_control(&self) -> bool {
        self.kind == QuestionKind::Control.as_str()
    }
}

/// Options of [`Study::from_run`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StudyOptions {
    /// Seed of question planning (without a questionnaire key), controls and swap patterns.
    pub seed: u64,
    /// Control questions to add (an animation against itself).
    pub controls: usize,
}

impl Default for StudyOptions {
    fn default() -> Self {
        Self {
            seed: 1,
            controls: 0,
        }
    }
}

/// Everything the server needs to know about the questionnaire; stored in the database so
/// exports need nothing else.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Study {
    /// Variable names (the columns of `configurations.csv` besides the id).
    pub variables: Vec<String>,
    /// Configurations in manifest order.
    pub configurations: Vec<StudyConfiguration>,
    /// Real questions in `questions.csv` order, then controls.
    pub questions: Vec<StudyQuestion>,
    /// Seed of controls and swap patterns.
    pub seed: u64,
    /// Where the questions came from (`questionnaire_key.csv` or `planned`).
    pub source: String,
    /// Real questions per participant when each answers a balanced subset (`None`: all).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub per_participant: Option<usize>,
}

/// A participant's plan: question indices in the order shown, and whether each (indexed by
/// question) is shown with its sides swapped.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Plan {
    /// `order[k]`: the question shown at position `k` (0-based).
    pub order: Vec<usize>,
    /// `swapped[q]`: question `q` shows its canonical left on the right.
    pub swapped: Vec<bool>,
}

impl Study {
    /// Reads the study of a rendered run folder (`configurations.csv`, `key.csv`, `render/*.gif`
    /// and, if present, `questionnaire_key.csv`).
    pub fn from_run(run: &Path, options: &StudyOptions) -> Result<Study, StudyError> {
        let manifest = Manifest::read(&run.join(CONFIGURATIONS_FILE))?;
        let key_path = run.join(KEY_FILE);
        if !key_path.exists() {
            return Err(StudyError::Missing(format!(
                "{} is missing: run `experiments render {}` first",
                key_path.display(),
                run.display()
            )));
        }
        let key = read_key(&key_path)?;
        let mut configurations = Vec::with_capacity(manifest.configurations.len());
        for c in &manifest.configurations {
            let name = key.get(&c.id).ok_or_else(|| StudyError::BadFile {
                path: key_path.clone(),
                message: format!("configuration `{}` has no name: render the run again", c.id),
            })?;
            configurations.push(StudyConfiguration {
                id: c.id.clone(),
                name: name.clone(),
                values: c.values.clone(),
            });
        }
        let qkey = run.join(QUESTIONNAIRE_KEY_FILE);
        let (mut questions, source) = if qkey.exists() {
            (
                read_questionnaire_key(&qkey, &manifest, &configurations)?,
                QUESTIONNAIRE_KEY_FILE.to_string(),
            )
        } else {
            let planned = plan_questions(
                &manifest,
                &QuestionnaireOptions {
                    seed: options.seed,
                    ..QuestionnaireOptions::default()
                },
            )?;
            let questions = planned
                .into_iter()
                .enumerate()
                .map(|(k, q)| StudyQuestion {
                    id: format!("Q{}", k + 1),
                    kind: q.kind.as_str().to_string(),
                    left: q.left,
                    right: q.right,
                    variable: q.variable.unwrap_or_default(),
                })
                .collect();
            (questions, "planned".to_string())
        };
        if questions.iter().all(StudyQuestion::is_control) {
            return Err(StudyError::Missing(format!(
                "{}: no real question (two configurations of the same object that differ in \
                 exactly one variable)",
                run.display()
            )));
        }
        let mut rng = SplitMix64::for_stream(options.seed, "survey controls");
        let mut pool: Vec<usize> = Vec::new();
        for k in 0..options.controls {
            if pool.is_empty() {
                pool = (0..configurations.len()).collect();
                rng.shuffle(&mut pool);
            }
            if let Some(c) = pool.pop() {
                questions.push(StudyQuestion {
                    id: format!("C{}", k + 1),
                    kind: QuestionKind::Control.as_str().to_string(),
                    left: c,
                    right: c,
                    variable: String::new(),
                });
            }
        }
        let study = Study {
            variables: manifest.variables.clone(),
            configurations,
            questions,
            seed: options.seed,
            source,
            per_participant: None,
        };
        for name in study.shown_names() {
            let gif = run.join(RENDER_DIR).join(format!("{name}.gif"));
            if !gif.is_file() {
                return Err(StudyError::Missing(format!(
                    "{} is missing: run `experiments render {}` again",
                    gif.display(),
                    run.display()
                )));
            }
        }
        Ok(study)
    }

    /// The anonymous names of the animations some question shows.
    pub fn shown_names(&self) -> BTreeSet<String> {
        self.questions
            .iter()
            .flat_map(|q| [q.left, q.right])
            .map(|c| self.configurations[c].name.clone())
            .collect()
    }

    /// Number of real (non-control) questions.
    pub fn real_questions(&self) -> usize {
        self.questions.iter().filter(|q| !q.is_control()).count()
    }

    /// Index of the question with this id.
    pub fn question_index(&self, id: &str) -> Option<usize> {
        self.questions.iter().position(|q| q.id == id)
    }

    /// The same study where every participant answers a balanced subset of `per_participant`
    /// real questions (see the module documentation); all of them is the same as no subsets.
    pub fn with_subsets(mut self, per_participant: usize) -> Result<Study, StudyError> {
        let real = self.real_questions();
        if !(1..=real).contains(&per_participant) {
            return Err(StudyError::Missing(format!(
                "questions per participant must be 1 to the study's {real} questions, got \
                 {per_participant}"
            )));
        }
        self.per_participant = (per_participant < real).then_some(per_participant);
        Ok(self)
    }

    /// Real questions each participant answers.
    pub fn real_questions_per_participant(&self) -> usize {
        self.per_participant
            .unwrap_or_else(|| self.real_questions())
    }

    /// The plan of the participant with this token who arrived `seq`-th (1-based).
    pub fn plan_for(&self, token: &str, seq: u64) -> Plan {
        if let Some(q) = self.per_participant {
            return self.subset_plan_for(token, seq, q);
        }
        let n = self.questions.len();
        let mut order: Vec<usize> = (0..n).collect();
        SplitMix64::for_stream(token_seed(token) ^ self.seed, "survey order").shuffle(&mut order);
        let real: Vec<usize> = (0..n)
            .filter(|&q| !self.questions[q].is_control())
            .collect();
        let pair = seq.saturating_sub(1) / 2;
        let mut pattern: Vec<bool> = (0..real.len()).map(|k| k < real.len() / 2).collect();
        SplitMix64::for_stream(
            self.seed ^ pair.wrapping_mul(0x9e37_79b9_7f4a_7c15),
            "survey swaps",
        )
        .shuffle(&mut pattern);
        let second_of_pair = seq.is_multiple_of(2);
        let mut swapped = vec![false; n];
        for (&q, &s) in real.iter().zip(&pattern) {
            swapped[q] = s != second_of_pair;
        }
        Plan { order, swapped }
    }
}

impl Study {
    /// [`Study::plan_for`] with balanced subsets of `q` real questions.
    fn subset_plan_for(&self, token: &str, seq: u64, q: usize) -> Plan {
        let n = self.questions.len();
        let mut cycle: Vec<usize> = (0..n)
            .filter(|&k| !self.questions[k].is_control())
            .collect();
        let r = cycle.len();
        let q = q.min(r);
        let mut rng = SplitMix64::for_stream(self.seed, "survey subsets");
        rng.shuffle(&mut cycle);
        let flips: Vec<bool> = (0..r).map(|_| rng.coin()).collect();
        let mut order = Vec::with_capacity(q);
        let mut swapped = vec![false; n];
        // Laps before this participant's window: positions of the unrolled cycle.
        let start = (seq.saturating_sub(1) as u128) * q as u128;
        for j in 0..q {
            let u = start + j as u128;
            let c = (u % r as u128) as usize;
            let laps = (u / r as u128) as u64;
            order.push(cycle[c]);
            swapped[cycle[c]] = (laps + u64::from(flips[c])) % 2 == 1;
        }
        order.extend((0..n).filter(|&k| self.questions[k].is_control()));
        SplitMix64::for_stream(token_seed(token) ^ self.seed, "survey order").shuffle(&mut order);
        Plan { order, swapped }
    }
}

/// A seed from a token: FNV-1a of its bytes.
fn token_seed(token: &str) -> u64 {
    token.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// Reads `questionnaire_key.csv` (`question,left,right,left_name,right_name,kind,...`), checking
/// its ids and names against the manifest and `key.csv`.
fn read_questionnaire_key(
    path: &Path,
    manifest: &Manifest,
    configurations: &[StudyConfiguration],
) -> Result<Vec<StudyQuestion>, StudyError> {
    let bad = |message: String| StudyError::BadFile {
        path: path.to_path_buf(),
        message,
    };
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_path(path)
        .map_err(|e| bad(e.to_string()))?;
    let headers = reader.headers().map_err(|e| bad(e.to_string()))?.clone();
    let column = |name: &str| -> Result<usize, StudyError> {
        headers
            .iter()
            .position(|h| h == name)
            .ok_or_else(|| bad(format!("no `{name}` column")))
    };
    let (qc, lc, rc) = (column("question")?, column("left")?, column("right")?);
    // Optional name columns, checked against key.csv when present.
    let names: BTreeMap<&str, usize> = ["left_name", "right_name"]
        .into_iter()
        .filter_map(|n| headers.iter().position(|h| h == n).map(|c| (n, c)))
        .collect();
    let kind_column = headers.iter().position(|h| h == "kind");
    let variable_column = headers.iter().position(|h| h == "variable");
    let mut questions = Vec::new();
    let mut seen = BTreeSet::new();
    for (row, record) in reader.records().enumerate() {
        let record = record.map_err(|e| bad(e.to_string()))?;
        let line = row + 2;
        let get = |c: usize| record.get(c).unwrap_or("").to_string();
        let id = get(qc);
        if !seen.insert(id.clone()) {
            return Err(bad(format!("line {line}: question `{id}` twice")));
        }
        let side = |c: usize| -> Result<usize, StudyError> {
            let cid = get(c);
            manifest
                .position(&cid)
                .ok_or_else(|| bad(format!("line {line}: unknown configuration `{cid}`")))
        };
        let (left, right) = (side(lc)?, side(rc)?);
        for (column_name, &c) in &names {
            let expected = if *column_name == "left_name" {
                &configurations[left].name
            } else {
                &configurations[right].name
            };
            if &get(c) != expected {
                return Err(bad(format!(
                    "line {line}: `{column_name}` is `{}` but key.csv names it `{expected}`: \
                     build the questionnaire again after rendering",
                    get(c)
                )));
            }
        }
        let kind = kind_column
            .map(&get)
            .filter(|k| !k.is_empty())
            .unwrap_or_else(|| {
                if left == right {
                    QuestionKind::Control.as_str().to_string()
                } else {
                    QuestionKind::Pair.as_str().to_string()
                }
            });
        questions.push(StudyQuestion {
            id,
            kind,
            left,
            right,
            variable: variable_column.map(&get).unwrap_or_default(),
        });
    }
    if questions.is_empty() {
        return Err(bad("no questions".into()));
    }
    Ok(questions)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn study(controls: usize) -> Study {
        let manifest = Manifest::from_reader(
            "id,object,lattice,clustering\n\
             a,s,b,n\nb,s,b,i\nc,s,b,p\nd,s,s,n\ne,s,s,i\nf,s,s,p\n"
                .as_bytes(),
            Path::new("c.csv"),
        )
        .unwrap();
        let planned = plan_questions(&manifest, &QuestionnaireOptions::default()).unwrap();
        let mut questions: Vec<StudyQuestion> = planned
            .into_iter()
            .enumerate()
            .map(|(k, q)| StudyQuestion {
                id: format!("Q{}", k + 1),
                kind: q.kind.as_str().into(),
                left: q.left,
                right: q.right,
                variable: q.variable.unwrap_or_default(),
            })
            .collect();
        for k in 0..controls {
            questions.push(StudyQuestion {
                id: format!("C{}", k + 1),
                kind: "control".into(),
                left: k,
                right: k,
                variable: String::new(),
            });
        }
        Study {
            variables: manifest.variables.clone(),
            configurations: manifest
                .configurations
                .iter()
                .map(|c| StudyConfiguration {
                    id: c.id.clone(),
                    name: format!("n{}", c.id),
                    values: c.values.clone(),
                })
                .collect(),
            questions,
            seed: 3,
            source: "planned".into(),
            per_participant: None,
        }
    }

    #[test]
    fn subsets_are_balanced_per_question_and_sides_per_question() {
        let full = study(2);
        let real = full.real_questions();
        assert!(full.clone().with_subsets(0).is_err());
        assert!(full.clone().with_subsets(real + 1).is_err());
        assert_eq!(full.clone().with_subsets(real).unwrap(), full);
        let s = full.with_subsets(4).unwrap();
        assert_eq!(s.real_questions_per_participant(), 4);
        let mut seen = vec![0usize; s.questions.len()];
        let mut swaps = vec![0usize; s.questions.len()];
        let participants = 23u64;
        for seq in 1..=participants {
            let plan = s.plan_for(&format!("{seq:032x}"), seq);
            assert_eq!(plan.order.len(), 4 + 2);
            let mut distinct = plan.order.clone();
            distinct.sort_unstable();
            distinct.dedup();
            assert_eq!(distinct.len(), plan.order.len(), "a question twice");
            for &q in &plan.order {
                seen[q] += 1;
                swaps[q] += usize::from(plan.swapped[q]);
                if s.questions[q].is_control() {
                    assert!(!plan.swapped[q]);
                }
            }
            // The same participant gets the same plan.
            assert_eq!(plan, s.plan_for(&format!("{seq:032x}"), seq));
        }
        let real_seen: Vec<usize> = (0..s.questions.len())
            .filter(|&q| !s.questions[q].is_control())
            .map(|q| seen[q])
            .collect();
        let (lo, hi) = (
            *real_seen.iter().min().unwrap(),
            *real_seen.iter().max().unwrap(),
        );
        assert!(hi - lo <= 1, "seen {lo}..{hi}");
        assert_eq!(real_seen.iter().sum::<usize>(), 4 * participants as usize);
        for q in 0..s.questions.len() {
            if !s.questions[q].is_control() {
                assert!((2 * swaps[q]).abs_diff(seen[q]) <= 1, "question {q}");
            }
        }
        // Stored as before when there are no subsets; with them the field is kept.
        let json = serde_json::to_string(&study(2)).unwrap();
        assert!(!json.contains("per_participant"));
        let back: Study = serde_json::from_str(&serde_json::to_string(&s).unwrap()).unwrap();
        assert_eq!(back, s);
    }

    #[test]
    fn order_is_a_permutation_seeded_by_the_token() {
        let s = study(2);
        let a = s.plan_for("00112233445566778899aabbccddeeff", 1);
        let b = s.plan_for("00112233445566778899aabbccddeeff", 1);
        let c = s.plan_for("ffeeddccbbaa99887766554433221100", 1);
        assert_eq!(a, b);
        assert_ne!(a.order, c.order);
        let mut sorted = a.order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..s.questions.len()).collect::<Vec<_>>());
    }

    #[test]
    fn swaps_are_balanced_across_pairs_of_participants_and_within_each() {
        let s = study(2);
        let real = s.real_questions();
        let mut per_question = vec![0usize; s.questions.len()];
        for seq in 1..=40u64 {
            let plan = s.plan_for(&format!("{seq:032x}"), seq);
            let swaps = plan.swapped.iter().filter(|&&x| x).count();
            assert!(
                swaps == real / 2 || swaps == real.div_ceil(2),
                "{seq}: {swaps}"
            );
            for (q, &x) in plan.swapped.iter().enumerate() {
                per_question[q] += usize::from(x);
                if s.questions[q].is_control() {
                    assert!(!x, "controls are never swapped");
                }
            }
        }
        for (q, &count) in per_question.iter().enumerate() {
            if !s.questions[q].is_control() {
                assert_eq!(count, 20, "question {q} swapped for exactly half of 40");
            }
        }
        // Patterns differ between pairs.
        assert_ne!(s.plan_for("a", 1).swapped, s.plan_for("a", 3).swapped);
    }
}
