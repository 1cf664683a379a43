//! The question set of a perception study: which configurations to compare, in which order, on
//! which side, and the HTML page that collects the answers.
//!
//! - A **manifest** lists configurations: an id column (`id`, or `name` as in
//!   `data/questionnaire/configurations.csv`) and one column per variable, one of them `object`.
//! - A **pair** is two configurations of the same object that differ in exactly one other
//!   variable. With the paper's 18 configurations (3 objects x 2 lattices x 3 clusterings) that is,
//!   per object, the 3 clustering pairs within each lattice and the lattice pair within each
//!   clustering: 9 per object, 27 in all.
//! - **Counterbalancing**: each pair is shown once in one orientation, and the orientations are
//!   chosen so that every configuration appears on the left and on the right equally often, up to
//!   one. This is the classic balanced orientation of a graph: give every odd-degree vertex an
//!   edge to a dummy vertex, so every degree is even; walk closed trails along unused edges (in an
//!   even graph a trail can only get stuck where it started) and orient each edge the way it was
//!   walked; every vertex is entered as often as it is left, and dropping the dummy edges changes
//!   that by at most one. The trails are randomised by the seed.
//! - **Reversed pairs** (optional) show each pair a second time with the sides swapped;
//!   **controls** (optional) show an animation against itself.
//! - **Order**: all questions are shuffled (seeded), then a question that repeats the pair of the
//!   question before it is swapped with a later one when possible.
//!
//! Answers are exported in the analysis crate's long format: `participant,question,response`,
//! questions `Q1..Qn` in the order shown, responses `L`, `N` or `R`.

use crate::names::SplitMix64;
use crate::{RenderError, Result};
use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::path::Path;

/// One configuration: its id and its value of each variable.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Configuration {
    /// The id (`ss_bi`).
    pub id: String,
    /// Values, in the order of [`Manifest::variables`].
    pub values: Vec<String>,
}

/// The configurations of a run.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Manifest {
    /// Column names other than the id, in file order.
    pub variables: Vec<String>,
    /// Rows in file order.
    pub configurations: Vec<Configuration>,
}

impl Manifest {
    /// Reads a configurations CSV file.
    pub fn read(path: &Path) -> Result<Self> {
        let file = std::fs::File::open(path).map_err(crate::io_error(path))?;
        Self::from_reader(file, path)
    }

    /// Reads configurations CSV from `reader`; `path` only names the source in errors.
    pub fn from_reader(reader: impl std::io::Read, path: &Path) -> Result<Self> {
        let csv_error = |source| RenderError::Csv {
            path: path.to_path_buf(),
            source,
        };
        let bad = |message: String| RenderError::BadFile {
            path: path.to_path_buf(),
            message,
        };
        let mut reader = csv::ReaderBuilder::new()
            .trim(csv::Trim::All)
            .from_reader(reader);
        let headers = reader.headers().map_err(csv_error)?.clone();
        let id_column = ["id", "name"]
            .iter()
            .find_map(|want| headers.iter().position(|h| h == *want))
            .ok_or_else(|| bad("no `id` (or `name`) column in the header".into()))?;
        let variables: Vec<String> = headers
            .iter()
            .enumerate()
            .filter(|&(i, _)| i != id_column)
            .map(|(_, h)| h.to_string())
            .collect();
        let mut configurations = Vec::new();
        let mut seen = BTreeSet::new();
        for (row, record) in reader.records().enumerate() {
            let record = record.map_err(csv_error)?;
            let line = row + 2;
            let id = record.get(id_column).unwrap_or("").to_string();
            if id.is_empty() {
                return Err(bad(format!("line {line}: empty id")));
            }
            if !id
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-' || c == '.')
            {
                return Err(bad(format!(
                    "line {line}: id `{id}` may only use letters, digits, `_`, `-` and `.`"
                )));
            }
            if !seen.insert(id.clone()) {
                return Err(bad(format!("line {line}: duplicate id `{id}`")));
            }
            let values = record
                .iter()
                .enumerate()
                .filter(|&(i, _)| i != id_column)
                .map(|(_, v)| v.to_string())
                .collect();
            configurations.push(Configuration { id, values });
        }
        if configurations.is_empty() {
            return Err(bad("no configurations".into()));
        }
        Ok(Self {
            variables,
            configurations,
        })
    }

    /// Column index (into `values`) of a variable.
    pub fn variable_index(&self, name: &str) -> Option<usize> {
        self.variables.iter().position(|v| v == name)
    }

    /// Index of the configuration with this id.
    pub fn position(&self, id: &str) -> Option<usize> {
        self.configurations.iter().position(|c| c.id == id)
    }
}

/// Two configurations (indices into the manifest, manifest order) that differ in one variable.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Pair {
    /// The earlier configuration.
    pub first: usize,
    /// The later configuration.
    pub second: usize,
    /// The variable in which they differ.
    pub variable: String,
}

/// Every pair of configurations with the same `object` that differ in exactly one other variable.
pub fn single_variable_pairs(manifest: &Manifest) -> Result<Vec<Pair>> {
    let object = manifest.variable_index("object").ok_or_else(|| {
        RenderError::Questionnaire("the configurations have no `object` column".into())
    })?;
    let configs = &manifest.configurations;
    let mut pairs = Vec::new();
    for i in 0..configs.len() {
        for j in i + 1..configs.len() {
            let (a, b) = (&configs[i].values, &configs[j].values);
            if a[object] != b[object] {
                continue;
            }
            let differing: Vec<usize> = (0..a.len()).filter(|&k| a[k] != b[k]).collect();
            if let [k] = differing[..] {
                pairs.push(Pair {
                    first: i,
                    second: j,
                    variable: manifest.variables[k].clone(),
                });
            }
        }
    }
    Ok(pairs)
}

/// For each edge `(a, b)` of a graph on `vertices` vertices, whether to keep it as `a -> b`
/// (`true`) or turn it into `b -> a`, such that every vertex's out-degree and in-degree differ by
/// at most one (see the module documentation).
pub fn balanced_orientation(
    vertices: usize,
    edges: &[(usize, usize)],
    rng: &mut SplitMix64,
) -> Vec<bool> {
    let dummy = vertices;
    let mut all: Vec<(usize, usize)> = edges.to_vec();
    let mut degree = vec![0usize; vertices + 1];
    for &(a, b) in edges {
        degree[a] += 1;
        degree[b] += 1;
    }
    for (v, &d) in degree.iter().enumerate().take(vertices) {
        if d % 2 == 1 {
            all.push((v, dummy));
        }
    }
    let mut incident: Vec<Vec<usize>> = vec![Vec::new(); vertices + 1];
    for (e, &(a, b)) in all.iter().enumerate() {
        incident[a].push(e);
        if b != a {
            incident[b].push(e);
        }
    }
    for list in &mut incident {
        rng.shuffle(list);
    }
    let mut starts: Vec<usize> = (0..=vertices).collect();
    rng.shuffle(&mut starts);
    let mut used = vec![false; all.len()];
    let mut forward = vec![true; all.len()];
    let mut next = vec![0usize; vertices + 1];
    let mut unused_edge = |v: usize, used: &[bool]| -> Option<usize> {
        while next[v] < incident[v].len() {
            let e = incident[v][next[v]];
            if !used[e] {
                return Some(e);
            }
            next[v] += 1;
        }
        None
    };
    for start in starts {
        // Walk closed trails from `start` until its edges are used up.
        while unused_edge(start, &used).is_some() {
            let mut at = start;
            while let Some(e) = unused_edge(at, &used) {
                used[e] = true;
                let (a, b) = all[e];
                forward[e] = a == at;
                at = if a == at { b } else { a };
            }
        }
    }
    let flip_all = rng.coin();
    forward.truncate(edges.len());
    forward.iter().map(|&f| f != flip_all).collect()
}

/// Why a question is there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum QuestionKind {
    /// A pair, in its counterbalanced orientation.
    Pair,
    /// The same pair with the sides swapped (`--reverse-pairs`).
    Reversed,
    /// An animation against itself (`--controls`).
    Control,
}

impl QuestionKind {
    /// The lowercase name used in key files.
    pub fn as_str(self) -> &'static str {
        match self {
            QuestionKind::Pair => "pair",
            QuestionKind::Reversed => "reversed",
            QuestionKind::Control => "control",
        }
    }
}

/// A question before it is given a number: two configurations (manifest indices).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Question {
    /// Shown on the left.
    pub left: usize,
    /// Shown on the right.
    pub right: usize,
    /// Pair, reversed pair or control.
    pub kind: QuestionKind,
    /// The variable that differs (`None` for controls).
    pub variable: Option<String>,
}

impl Question {
    fn same_pair(&self, other: &Question) -> bool {
        (self.left.min(self.right), self.left.max(self.right))
            == (other.left.min(other.right), other.left.max(other.right))
    }
}

/// Options of the question set.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct QuestionnaireOptions {
    /// Seed of orientation, order and control choice.
    pub seed: u64,
    /// Also show every pair with the sides swapped.
    pub reverse_pairs: bool,
    /// Number of control questions (an animation against itself).
    pub controls: usize,
    /// Pixels between the two animations, before scaling.
    pub gap: u16,
    /// Nearest-neighbour scale factor of the question animations.
    pub scale: u16,
}

impl Default for QuestionnaireOptions {
    fn default() -> Self {
        Self {
            seed: 1,
            reverse_pairs: false,
            controls: 0,
            gap: 8,
            scale: 2,
        }
    }
}

/// The questions in the order they are shown (question `k` is `Q{k+1}`).
pub fn plan_questions(
    manifest: &Manifest,
    options: &QuestionnaireOptions,
) -> Result<Vec<Question>> {
    let pairs = single_variable_pairs(manifest)?;
    if pairs.is_empty() && options.controls == 0 {
        return Err(RenderError::Questionnaire(
            "no two configurations of the same object differ in exactly one variable".into(),
        ));
    }
    let n = manifest.configurations.len();
    let mut rng = SplitMix64::for_stream(options.seed, "left/right orientation");
    let edges: Vec<(usize, usize)> = pairs.iter().map(|p| (p.first, p.second)).collect();
    let keep = balanced_orientation(n, &edges, &mut rng);
    let mut questions = Vec::new();
    for (pair, keep) in pairs.iter().zip(keep) {
        let (left, right) = if keep {
            (pair.first, pair.second)
        } else {
            (pair.second, pair.first)
        };
        let variable = Some(pair.variable.clone());
        questions.push(Question {
            left,
            right,
            kind: QuestionKind::Pair,
            variable: variable.clone(),
        });
        if options.reverse_pairs {
            questions.push(Question {
                left: right,
                right: left,
                kind: QuestionKind::Reversed,
                variable,
            });
        }
    }
    let mut rng = SplitMix64::for_stream(options.seed, "controls");
    let mut pool: Vec<usize> = Vec::new();
    for _ in 0..options.controls {
        if pool.is_empty() {
            pool = (0..n).collect();
            rng.shuffle(&mut pool);
        }
        if let Some(c) = pool.pop() {
            questions.push(Question {
                left: c,
                right: c,
                kind: QuestionKind::Control,
                variable: None,
            });
        }
    }
    let mut rng = SplitMix64::for_stream(options.seed, "question order");
    rng.shuffle(&mut questions);
    // Move a question that repeats its predecessor's pair to the first later place where
    // neither it nor the question it trades places with repeats a neighbour.
    let clashes = |q: &[Question], at: usize| {
        (at > 0 && q[at].same_pair(&q[at - 1])) || q.get(at + 1).is_some_and(|n| q[at].same_pair(n))
    };
    for i in 1..questions.len() {
        if !questions[i].same_pair(&questions[i - 1]) {
            continue;
        }
        for j in i + 1..questions.len() {
            questions.swap(i, j);
            if !clashes(&questions, i) && !clashes(&questions, j) {
                break;
            }
            questions.swap(i, j);
        }
    }
    Ok(questions)
}

/// Zero-padded question file name: `q07_abcd_efgh.gif` (at least two digits).
pub fn question_file_name(number: usize, total: usize, left: &str, right: &str) -> String {
    let width = total.to_string().len().max(2);
    format!("q{number:0width$}_{left}_{right}.gif")
}

fn escape_html(s: &str) -> String {
    s.chars()
        .map(|c| match c {
            '&' => "&amp;".to_string(),
            '<' => "&lt;".to_string(),
            '>' => "&gt;".to_string(),
            '"' => "&quot;".to_string(),
            '\'' => "&#39;".to_string(),
            c => c.to_string(),
        })
        .collect()
}

/// One question as the page shows it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PageQuestion {
    /// `Q1`, `Q2`, ...
    pub id: String,
    /// The side-by-side GIF, relative to the page.
    pub file: String,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

/// A self-contained HTML page (no external resources) that shows the questions in order, each
/// titled only by its number, with the choices Prefer left / No preference / Prefer right, and
/// exports the answers as long-format CSV (`participant,question,response`, L/N/R).
pub fn questionnaire_html(questions: &[PageQuestion]) -> String {
    let mut body = String::new();
    for (k, q) in questions.iter().enumerate() {
        let (id, file) = (escape_html(&q.id), escape_html(&q.file));
        let number = k + 1;
        let _ = write!(
            body,
            r#"<section class="question" id="{id}">
<h2>Question {number}</h2>
<img src="{file}" width="{w}" height="{h}" loading="lazy" alt="Question {number}: two animations side by side">
<div class="choices">
<label><input type="radio" name="{id}" value="L"> Prefer left</label>
<label><input type="radio" name="{id}" value="N"> No preference</label>
<label><input type="radio" name="{id}" value="R"> Prefer right</label>
</div>
</section>
"#,
            w = q.width,
            h = q.height,
        );
    }
    let ids: Vec<String> = questions
        .iter()
        .map(|q| format!("\"{}\"", escape_html(&q.id)))
        .collect();
    format!(
        r#"<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>Questionnaire</title>
<style>
body {{ font-family: system-ui, sans-serif; max-width: 1120px; margin: 0 auto; padding: 1em; background: #f7f7f7; color: #222; }}
.question {{ background: #fff; border: 1px solid #ddd; border-radius: 6px; margin: 1.5em 0; padding: 1em; }}
.question h2 {{ margin-top: 0; font-size: 1.2em; }}
.question img {{ display: block; max-width: 100%; height: auto; image-rendering: pixelated; }}
.choices {{ margin-top: 0.8em; display: flex; gap: 2.5em; flex-wrap: wrap; }}
.choices label {{ cursor: pointer; }}
#export-area {{ background: #fff; border: 1px solid #ddd; border-radius: 6px; padding: 1em; }}
textarea {{ width: 100%; height: 8em; font-family: monospace; }}
</style>
</head>
<body>
<h1>Which animation do you prefer?</h1>
<p>Each question shows two turning objects side by side. Look at both for as long as you like,
then choose the one you prefer, or <em>No preference</em>. There are {count} questions.</p>
<p><label>Participant ID: <input id="participant" autocomplete="off"></label></p>
<form id="answers" onsubmit="return false">
{body}</form>
<div id="export-area">
<button type="button" id="export">Download answers (CSV)</button>
<p>If the download does not start, copy the text below and send it instead.</p>
<textarea id="csv" readonly></textarea>
</div>
<script>
const QUESTIONS = [{ids}];
function csvField(s) {{
  return /[",\r\n]/.test(s) ? '"' + s.replace(/"/g, '""') + '"' : s;
}}
function answer(q) {{
  const checked = document.querySelector('input[name="' + q + '"]:checked');
  return checked ? checked.value : null;
}}
document.getElementById("export").addEventListener("click", function () {{
  const participant = document.getElementById("participant").value.trim();
  if (!participant) {{ alert("Please enter your participant ID first."); return; }}
  const missing = QUESTIONS.filter(function (q) {{ return answer(q) === null; }});
  if (missing.length > 0 &&
      !confirm(missing.length + " question(s) have no answer (" + missing.join(", ") + "). Export anyway?")) {{
    return;
  }}
  let csv = "participant,question,response\n";
  for (const q of QUESTIONS) {{
    const a = answer(q);
    if (a !== null) {{ csv += csvField(participant) + "," + q + "," + a + "\n"; }}
  }}
  document.getElementById("csv").value = csv;
  const url = URL.createObjectURL(new Blob([csv], {{ type: "text/csv" }}));
  const link = document.createElement("a");
  link.href = url;
  link.download = "answers_" + participant.replace(/[^A-Za-z0-9_-]/g, "_") + ".csv";
  document.body.appendChild(link);
  link.click();
  link.remove();
  URL.revokeObjectURL(url);
}});
</script>
</body>
</html>
"#,
        count = questions.len(),
        ids = ids.join(", "),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    const PAPER_CONFIGURATIONS: &str = include_str!("../tests/fixtures/configurations.csv");
    const PAPER_QUESTIONS: &str = include_str!("../tests/fixtures/questions.csv");

    fn paper() -> Manifest {
        Manifest::from_reader(
            PAPER_CONFIGURATIONS.as_bytes(),
            Path::new("configurations.csv"),
        )
        .unwrap()
    }

    fn unordered(a: &str, b: &str) -> (String, String) {
        if a < b {
            (a.into(), b.into())
        } else {
            (b.into(), a.into())
        }
    }

    #[test]
    fn paper_manifest_yields_exactly_the_27_published_comparisons() {
        let m = paper();
        assert_eq!(m.variables, ["object", "lattice", "clustering"]);
        let ours: BTreeSet<(String, String)> = single_variable_pairs(&m)
            .unwrap()
            .iter()
            .map(|p| {
                unordered(
                    &m.configurations[p.first].id,
                    &m.configurations[p.second].id,
                )
            })
            .collect();
        let mut published = BTreeSet::new();
        for line in PAPER_QUESTIONS
            .lines()
            .skip(1)
            .filter(|l| !l.trim().is_empty())
        {
            let f: Vec<&str> = line.split(',').map(str::trim).collect();
            published.insert(unordered(f[1], f[2]));
        }
        assert_eq!(published.len(), 27);
        assert_eq!(ours, published);
    }

    #[test]
    fn pairs_per_object_split_into_lattice_and_clustering() {
        let m = paper();
        let pairs = single_variable_pairs(&m).unwrap();
        let mut per: BTreeMap<(String, String), usize> = BTreeMap::new();
        for p in &pairs {
            let object = m.configurations[p.first].values[0].clone();
            *per.entry((object, p.variable.clone())).or_default() += 1;
        }
        for object in ["sphere", "asteroid", "bunny"] {
            assert_eq!(per[&(object.to_string(), "lattice".to_string())], 3);
            assert_eq!(per[&(object.to_string(), "clustering".to_string())], 6);
        }
    }

    #[test]
    fn id_column_may_be_called_id_and_extra_variables_count() {
        let csv = "id,object,lattice,clustering,method\na,s,b,n,rmt\nb,s,b,n,mc\nc,s,s,n,mc\nd,t,s,n,mc\n";
        let m = Manifest::from_reader(csv.as_bytes(), Path::new("c.csv")).unwrap();
        let pairs = single_variable_pairs(&m).unwrap();
        let found: Vec<(usize, usize, &str)> = pairs
            .iter()
            .map(|p| (p.first, p.second, p.variable.as_str()))
            .collect();
        // a-b differ in method only, b-c in lattice only; a-c in two; d is another object.
        assert_eq!(found, vec![(0, 1, "method"), (1, 2, "lattice")]);
    }

    #[test]
    fn bad_manifests_name_line_and_problem() {
        let err = |csv: &str| {
            Manifest::from_reader(csv.as_bytes(), Path::new("m.csv"))
                .unwrap_err()
                .to_string()
        };
        assert!(err("object,lattice\ns,b\n").contains("no `id`"));
        assert!(err("id,object\na,s\na,t\n").contains("line 3: duplicate id `a`"));
        assert!(err("id,object\n,s\n").contains("line 2: empty id"));
        assert!(err("id,object\na/b,s\n").contains("line 2"));
        assert!(err("id,object\na,s,extra\n").contains("m.csv"));
        let m = Manifest::from_reader("id,lattice\na,b\n".as_bytes(), Path::new("m.csv")).unwrap();
        assert!(single_variable_pairs(&m)
            .unwrap_err()
            .to_string()
            .contains("`object`"));
    }

    #[test]
    fn every_configuration_is_left_and_right_equally_often_up_to_one() {
        let m = paper();
        for seed in 0..20 {
            let q = plan_questions(
                &m,
                &QuestionnaireOptions {
                    seed,
                    ..Default::default()
                },
            )
            .unwrap();
            assert_eq!(q.len(), 27);
            let mut balance = vec![0i32; m.configurations.len()];
            for question in &q {
                balance[question.left] += 1;
                balance[question.right] -= 1;
            }
            assert!(
                balance.iter().all(|b| b.abs() <= 1),
                "seed {seed}: {balance:?}"
            );
        }
    }

    #[test]
    fn balanced_orientation_holds_on_random_graphs() {
        let mut rng = SplitMix64::new(11);
        for _ in 0..50 {
            let n = 2 + rng.below(12) as usize;
            let m = rng.below(40) as usize;
            let edges: Vec<(usize, usize)> = (0..m)
                .map(|_| (rng.below(n as u64) as usize, rng.below(n as u64) as usize))
                .filter(|(a, b)| a != b)
                .collect();
            let keep = balanced_orientation(n, &edges, &mut rng);
            let mut balance = vec![0i32; n];
            for (&(a, b), k) in edges.iter().zip(keep) {
                let (l, r) = if k { (a, b) } else { (b, a) };
                balance[l] += 1;
                balance[r] -= 1;
            }
            assert!(
                balance.iter().all(|b| b.abs() <= 1),
                "{edges:?} {balance:?}"
            );
        }
    }

    #[test]
    fn reversed_pairs_and_controls_are_added_and_order_is_seeded() {
        let m = paper();
        let opts = QuestionnaireOptions {
            seed: 5,
            reverse_pairs: true,
            controls: 4,
            ..Default::default()
        };
        let q = plan_questions(&m, &opts).unwrap();
        assert_eq!(q.len(), 27 * 2 + 4);
        let controls: Vec<&Question> = q
            .iter()
            .filter(|q| q.kind == QuestionKind::Control)
            .collect();
        assert_eq!(controls.len(), 4);
        assert!(controls
            .iter()
            .all(|c| c.left == c.right && c.variable.is_none()));
        let distinct: BTreeSet<usize> = controls.iter().map(|c| c.left).collect();
        assert_eq!(
            distinct.len(),
            4,
            "controls use different animations while they last"
        );
        // Every pair appears once each way.
        let shown: BTreeSet<(usize, usize)> = q
            .iter()
            .filter(|q| q.kind != QuestionKind::Control)
            .map(|q| (q.left, q.right))
            .collect();
        assert_eq!(shown.len(), 54);
        assert!(shown.iter().all(|&(l, r)| shown.contains(&(r, l))));
        // No pair right after itself.
        assert!(q.windows(2).all(|w| !w[0].same_pair(&w[1])));
        // Seeded: same seed, same order; another seed, another order.
        assert_eq!(q, plan_questions(&m, &opts).unwrap());
        let other = plan_questions(
            &m,
            &QuestionnaireOptions {
                seed: 6,
                ..opts.clone()
            },
        )
        .unwrap();
        assert_ne!(q, other);
    }

    #[test]
    fn question_order_is_not_the_manifest_order() {
        let m = paper();
        let q = plan_questions(&m, &QuestionnaireOptions::default()).unwrap();
        let firsts: Vec<usize> = q.iter().map(|q| q.left.min(q.right)).collect();
        let mut sorted = firsts.clone();
        sorted.sort_unstable();
        assert_ne!(firsts, sorted);
    }

    #[test]
    fn file_names_are_padded_and_built_from_the_two_names() {
        assert_eq!(
            question_file_name(7, 27, "abcd", "efgh"),
            "q07_abcd_efgh.gif"
        );
        assert_eq!(
            question_file_name(7, 120, "abcd", "efgh"),
            "q007_abcd_efgh.gif"
        );
    }

    #[test]
    fn html_lists_questions_in_order_with_three_choices_and_long_csv_export() {
        let qs: Vec<PageQuestion> = (1..=3)
            .map(|k| PageQuestion {
                id: format!("Q{k}"),
                file: format!("q0{k}_a_b.gif"),
                width: 10,
                height: 5,
            })
            .collect();
        let html = questionnaire_html(&qs);
        let p1 = html.find("Question 1</h2>").unwrap();
        let p2 = html.find("Question 2</h2>").unwrap();
        let p3 = html.find("Question 3</h2>").unwrap();
        assert!(p1 < p2 && p2 < p3);
        assert_eq!(html.matches(r#"value="L""#).count(), 3);
        assert_eq!(html.matches(r#"value="N""#).count(), 3);
        assert_eq!(html.matches(r#"value="R""#).count(), 3);
        assert!(html.contains(r#"const QUESTIONS = ["Q1", "Q2", "Q3"];"#));
        assert!(html.contains("participant,question,response"));
        assert!(html.contains(r#"src="q02_a_b.gif""#));
    }
}
