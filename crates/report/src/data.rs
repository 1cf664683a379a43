//! The run folder as the report sees it: provenance from `run.json`, one [`Configuration`] per
//! row of `summary.csv`, the comparison with the dissertation from `paper_comparison.csv` and a
//! seed study's distributions from `seeds.csv` (drawn by [`crate::seeds`]).
//!
//! Column names are those the runner writes (`experiments::runner`): the configuration columns,
//! `repetitions`, each time's `t_<stage>_s_{mean,sd,min,median,max}`, the counts, validation and
//! quality columns of `experiments extract --json`, then `triangle_reduction`, `discard_share`,
//! `tetrahedra_share` and `share_<stage>`.

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::csv_file::CsvFile;
use crate::error::{io_error, ReportError, Result};

/// `run.json`.
pub const RUN_JSON: &str = rmt_runfolder::layout::RUN_JSON;
/// `summary.csv`.
pub const SUMMARY_CSV: &str = rmt_runfolder::layout::SUMMARY_CSV;
/// `paper_comparison.csv`.
pub const PAPER_CSV: &str = rmt_runfolder::layout::PAPER_CSV;
/// `configurations.csv`.
pub const CONFIGURATIONS_CSV: &str = rmt_runfolder::layout::CONFIGURATIONS_CSV;
/// `raw.csv`.
pub const RAW_CSV: &str = rmt_runfolder::layout::RAW_CSV;
/// `manifest.toml`.
pub const MANIFEST_TOML: &str = rmt_runfolder::layout::MANIFEST_COPY;
/// `seeds.csv`.
pub const SEEDS_CSV: &str = "seeds.csv";

/// Where and how a run was made, from `run.json`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunInfo {
    /// The run's id (its folder name).
    pub run_id: String,
    /// The manifest's run name (`paper`, `ci`, `scaling`).
    pub name: String,
    /// `finished`, `running` or `stopped`.
    pub status: String,
    /// Package version of the tool.
    pub version: String,
    /// Git commit of the source tree, if known.
    pub git_commit: Option<String>,
    /// Whether that tree had uncommitted changes.
    pub git_dirty: Option<bool>,
    /// `release` or `debug`.
    pub build_profile: String,
    /// CPU model, if known.
    pub cpu_model: Option<String>,
    /// Logical CPUs.
    pub cores: Option<u64>,
    /// `linux x86_64`.
    pub os: String,
    /// Distribution, if known.
    pub os_release: Option<String>,
    /// Kernel, if known.
    pub kernel: Option<String>,
    /// Start of the first session (UTC, ISO 8601).
    pub date: String,
    /// End of the last session, when recorded.
    pub ended: Option<String>,
    /// Timed repetitions per configuration.
    pub repetitions: Option<u64>,
    /// Warm-up extractions per configuration.
    pub warmup: Option<u64>,
    /// Worker threads.
    pub threads: Option<u64>,
    /// How times were taken.
    pub timing_protocol: Option<String>,
    /// Sessions (start plus resumes).
    pub sessions: usize,
    /// CPU models of later sessions that differ from the first's.
    pub other_cpus: Vec<String>,
}

impl RunInfo {
    /// Reads `run.json`.
    pub fn read(path: &Path) -> Result<RunInfo> {
        let bytes = std::fs::read(path).map_err(io_error(path))?;
        let value: Value = serde_json::from_slice(&bytes).map_err(|e| ReportError::Json {
            path: path.to_path_buf(),
            message: format!("not valid JSON: {e}"),
        })?;
        Self::from_json(path, &value)
    }

    /// Reads the record from parsed JSON, naming `path` in errors.
    pub fn from_json(path: &Path, value: &Value) -> Result<RunInfo> {
        let missing = |key: &str| ReportError::Json {
            path: path.to_path_buf(),
            message: format!("missing key `{key}` (not a run.json of `experiments run`?)"),
        };
        let provenance = value
            .get("provenance")
            .filter(|p| p.is_object())
            .ok_or_else(|| missing("provenance"))?;
        let text = |v: &Value, key: &str| v.get(key).and_then(Value::as_str).map(str::to_string);
        let number = |v: &Value, key: &str| v.get(key).and_then(Value::as_u64);
        let settings = value.get("settings").cloned().unwrap_or(Value::Null);
        let sessions: Vec<Value> = value
            .get("sessions")
            .and_then(Value::as_array)
            .cloned()
            .unwrap_or_default();
        let first_cpu = text(provenance, "cpu_model");
        let mut other_cpus: Vec<String> = Vec::new();
        for session in &sessions {
            if let Some(cpu) = session.get("provenance").and_then(|p| text(p, "cpu_model")) {
                if Some(&cpu) != first_cpu.as_ref() && !other_cpus.contains(&cpu) {
                    other_cpus.push(cpu);
                }
            }
        }
        Ok(RunInfo {
            run_id: text(value, "run_id").ok_or_else(|| missing("run_id"))?,
            name: text(value, "name").ok_or_else(|| missing("name"))?,
            status: text(value, "status").unwrap_or_else(|| "unknown".into()),
            version: text(provenance, "version").unwrap_or_else(|| "unknown".into()),
            git_commit: text(provenance, "git_commit"),
            git_dirty: provenance.get("git_dirty").and_then(Value::as_bool),
            build_profile: text(provenance, "build_profile").unwrap_or_else(|| "unknown".into()),
            cpu_model: first_cpu,
            cores: number(provenance, "cores"),
            os: text(provenance, "os").unwrap_or_else(|| "unknown".into()),
            os_release: text(provenance, "os_release"),
            kernel: text(provenance, "kernel"),
            date: text(provenance, "date").ok_or_else(|| missing("provenance.date"))?,
            ended: sessions.last().and_then(|s| text(s, "ended")),
            repetitions: number(&settings, "repetitions"),
            warmup: number(&settings, "warmup"),
            threads: number(&settings, "threads"),
            timing_protocol: text(value, "timing_protocol"),
            sessions: sessions.len(),
            other_cpus,
        })
    }

    /// One line describing the machine: CPU, cores, OS, kernel.
    pub fn machine(&self) -> String {
        let mut parts = vec![self
            .cpu_model
            .clone()
            .unwrap_or_else(|| "unknown CPU".into())];
        if let Some(cores) = self.cores {
            parts.push(format!("{cores} logical cores"));
        }
        parts.push(
            self.os_release
                .clone()
                .map(|r| format!("{r} ({})", self.os))
                .unwrap_or_else(|| self.os.clone()),
        );
        if let Some(kernel) = &self.kernel {
            parts.push(format!("kernel {kernel}"));
        }
        parts.join(", ")
    }

    /// The commit, shortened, with `(uncommitted changes)` when the tree was dirty.
    pub fn commit(&self) -> String {
        match &self.git_commit {
            None => "unknown (git unavailable)".into(),
            Some(c) => {
                let short: String = c.chars().take(12).collect();
                match self.git_dirty {
                    Some(true) => format!("{short} (with uncommitted changes)"),
                    _ => short,
                }
            }
        }
    }
}

/// Mean, standard deviation, minimum, median and maximum of one time over the repetitions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeStats {
    /// Mean, seconds.
    pub mean: f64,
    /// Sample standard deviation (none below two repetitions), seconds.
    pub sd: Option<f64>,
    /// Minimum, seconds.
    pub min: f64,
    /// Median, seconds.
    pub median: f64,
    /// Maximum, seconds.
    pub max: f64,
}

/// One configuration: one row of `summary.csv`.
#[derive(Clone, Debug, PartialEq)]
pub struct Configuration {
    /// Configuration id (`ss_bi`, `as_bu_r64`).
    pub id: String,
    /// Object name from the manifest (`sphere`).
    pub object: String,
    /// `mt` or `mc`.
    pub method: String,
    /// `bcdl` or `simple`.
    pub lattice: String,
    /// `none`, `integrated`, `integrated-unchecked`, `postprocessed` or `meshopt`.
    pub clustering: String,
    /// Cells per axis.
    pub resolution: [u64; 3],
    /// Collapse threshold, as written.
    pub collapse_threshold: String,
    /// Timed repetitions.
    pub repetitions: u64,
    /// Output vertices.
    pub vertices: f64,
    /// Output triangles.
    pub triangles: f64,
    /// Triangles dropped by clustering or collapse.
    pub discarded: f64,
    /// Tetrahedra (cubes for marching cubes) with a crossing.
    pub tetrahedra_processed: f64,
    /// Tetrahedra of the lattice.
    pub tetrahedra_total: f64,
    /// Stage times in column order, keyed by stage (`total`, `sampling`, `vertex`, ...).
    pub times: Vec<(String, TimeStats)>,
    /// Mean radius ratio (1 = equilateral).
    pub ar_mean: f64,
    /// Standard deviation of the radius ratio over the triangles.
    pub ar_sd: f64,
    /// Median radius ratio.
    pub ar_median: f64,
    /// 95th percentile of the radius ratio.
    pub ar_p95: f64,
    /// Mean vertex distance to the true surface, grid spacings (fields that know it).
    pub fidelity_mean_h: Option<f64>,
    /// Largest vertex distance to the true surface, grid spacings.
    pub fidelity_max_h: Option<f64>,
    /// No interior boundary edge, non-manifold edge or vertex, or orientation error.
    pub closed_manifold: bool,
    /// Mesh defects: interior boundary edges, non-manifold edges, non-manifold vertices,
    /// orientation errors and duplicate triangles (the last none in runs made before it was
    /// counted).
    pub defects: Defects,
    /// Euler characteristic.
    pub euler: f64,
    /// Connected components.
    pub components: f64,
    /// 1 - triangles / triangles without clustering, when that configuration was run.
    pub triangle_reduction: Option<f64>,
    /// Discarded / (triangles + discarded).
    pub discard_share: Option<f64>,
    /// Processed / total tetrahedra.
    pub tetrahedra_share: Option<f64>,
    /// Bytes of the lattice, edge data, vertex buffer and index buffer.
    pub bytes: [f64; 4],
    /// Share of the lattice points at which the field was evaluated (`points_sampled /
    /// sample_points`; runs made before sparse sampling lack the column).
    pub points_sampled_share: Option<f64>,
    /// Share of the sampling blocks skipped (`blocks_skipped / blocks`; none with dense
    /// sampling or in older runs).
    pub blocks_skipped_share: Option<f64>,
}

impl Configuration {
    /// The statistics of stage `stage` (`total`, `vertex`, ...), if the summary has it.
    pub fn time(&self, stage: &str) -> Option<&TimeStats> {
        self.times.iter().find(|(s, _)| s == stage).map(|(_, t)| t)
    }

    /// Mean of stage `stage`, 0 when absent.
    pub fn mean_time(&self, stage: &str) -> f64 {
        self.time(stage).map_or(0.0, |t| t.mean)
    }

    /// Whether it is marching cubes.
    pub fn is_marching_cubes(&self) -> bool {
        self.method == "mc"
    }

    /// The method variant that colours it in every figure: the clustering mode for marching
    /// tetrahedra, `marching cubes` otherwise.
    pub fn variant(&self) -> String {
        if self.is_marching_cubes() {
            "marching cubes".into()
        } else {
            self.clustering.clone()
        }
    }

    /// `BCDL, integrated`, `simple cubic, none`, `marching cubes`.
    pub fn description(&self) -> String {
        if self.is_marching_cubes() {
            "marching cubes".into()
        } else {
            format!("{}, {}", lattice_name(&self.lattice), self.clustering)
        }
    }

    /// Cells per axis as one number: the geometric mean of the three.
    pub fn cells_per_axis(&self) -> f64 {
        let [x, y, z] = self.resolution;
        ((x * y * z) as f64).cbrt()
    }
}

/// Defect counts of one configuration's mesh (see `rmt_mesh::validate`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Defects {
    /// Boundary edges not on the sampled box (holes).
    pub boundary_edges_interior: f64,
    /// Edges with more than two triangles.
    pub non_manifold_edges: f64,
    /// Vertices whose triangles do not form one fan.
    pub non_manifold_vertices: f64,
    /// Edges whose two triangles disagree on orientation.
    pub orientation_errors: f64,
    /// Triangles with the same three vertices as another.
    pub duplicate_triangles: Option<f64>,
}

/// Display name of a lattice: `BCDL`, `simple cubic`.
pub fn lattice_name(lattice: &str) -> String {
    match lattice {
        "bcdl" => "BCDL".into(),
        "simple" => "simple cubic".into(),
        other => other.to_string(),
    }
}

/// `part / whole` when both are known and `whole > 0`.
fn share(part: Option<f64>, whole: Option<f64>) -> Option<f64> {
    match (part, whole) {
        (Some(p), Some(w)) if w > 0.0 => Some(p / w),
        _ => None,
    }
}

/// Reads `summary.csv`: one configuration per row, in file order.
pub fn read_summary(path: &Path) -> Result<Vec<Configuration>> {
    let file = CsvFile::read(path)?;
    let stages: Vec<String> = file
        .header
        .iter()
        .filter_map(|h| h.strip_prefix("t_")?.strip_suffix("_s_mean"))
        .map(str::to_string)
        .collect();
    if !stages.iter().any(|s| s == "total") {
        return Err(ReportError::MissingColumn {
            path: path.to_path_buf(),
            column: "t_total_s_mean".into(),
        });
    }
    let mut configurations: Vec<Configuration> = Vec::with_capacity(file.rows.len());
    for r in 0..file.rows.len() {
        let text = |name: &str| file.text(r, name).map(str::to_string);
        let count = |name: &str| file.required(r, name);
        let mut times = Vec::with_capacity(stages.len());
        for stage in &stages {
            let column = |stat: &str| format!("t_{stage}_s_{stat}");
            let mean = file.required(r, &column("mean"))?;
            times.push((
                stage.clone(),
                TimeStats {
                    mean,
                    sd: file.optional(r, &column("sd"))?,
                    min: file.optional(r, &column("min"))?.unwrap_or(mean),
                    median: file.optional(r, &column("median"))?.unwrap_or(mean),
                    max: file.optional(r, &column("max"))?.unwrap_or(mean),
                },
            ));
        }
        let defects = [
            "boundary_edges_interior",
            "non_manifold_edges",
            "non_manifold_vertices",
            "orientation_errors",
        ];
        let mut closed_manifold = true;
        for d in defects {
            closed_manifold &= count(d)? == 0.0;
        }
        let defects = Defects {
            boundary_edges_interior: count(defects[0])?,
            non_manifold_edges: count(defects[1])?,
            non_manifold_vertices: count(defects[2])?,
            orientation_errors: count(defects[3])?,
            duplicate_triangles: file.optional(r, "duplicate_triangles")?,
        };
        let resolution = |name: &str| -> Result<u64> {
            let v = count(name)?;
            if v >= 1.0 && v.fract() == 0.0 {
                Ok(v as u64)
            } else {
                Err(ReportError::Input {
                    path: path.to_path_buf(),
                    message: format!("line {}, column `{name}`: `{v}` is not a cell count", r + 2),
                })
            }
        };
        let c = Configuration {
            id: text("id")?,
            object: text("object")?,
            method: text("method")?,
            lattice: text("lattice")?,
            clustering: text("clustering")?,
            resolution: [resolution("rx")?, resolution("ry")?, resolution("rz")?],
            collapse_threshold: text("collapse_threshold")?,
            repetitions: count("repetitions")? as u64,
            vertices: count("vertices")?,
            triangles: count("triangles")?,
            discarded: count("discarded")?,
            tetrahedra_processed: count("tetrahedra_processed")?,
            tetrahedra_total: count("tetrahedra_total")?,
            times,
            ar_mean: count("ar_mean")?,
            ar_sd: count("ar_sd")?,
            ar_median: count("ar_median")?,
            ar_p95: count("ar_p95")?,
            fidelity_mean_h: file.optional(r, "fidelity_mean_h")?,
            fidelity_max_h: file.optional(r, "fidelity_max_h")?,
            closed_manifold,
            defects,
            euler: count("euler")?,
            components: count("components")?,
            triangle_reduction: file.optional(r, "triangle_reduction")?,
            discard_share: file.optional(r, "discard_share")?,
            tetrahedra_share: file.optional(r, "tetrahedra_share")?,
            bytes: [
                count("bytes_lattice")?,
                count("bytes_edges")?,
                count("bytes_vertices")?,
                count("bytes_indices")?,
            ],
            points_sampled_share: share(
                file.optional(r, "points_sampled")?,
                file.optional(r, "sample_points")?,
            ),
            blocks_skipped_share: share(
                file.optional(r, "blocks_skipped")?,
                file.optional(r, "blocks")?,
            ),
        };
        if c.id.is_empty() {
            return Err(ReportError::EmptyCell {
                path: path.to_path_buf(),
                line: r + 2,
                column: "id".into(),
            });
        }
        if configurations.iter().any(|o| o.id == c.id) {
            return Err(ReportError::Input {
                path: path.to_path_buf(),
                message: format!("line {}: configuration `{}` appears twice", r + 2, c.id),
            });
        }
        configurations.push(c);
    }
    if configurations.is_empty() {
        return Err(ReportError::Input {
            path: path.to_path_buf(),
            message: "no configurations".into(),
        });
    }
    Ok(configurations)
}

/// One row of `paper_comparison.csv`.
#[derive(Clone, Debug, PartialEq)]
pub struct PaperRow {
    /// Configuration id.
    pub id: String,
    /// Our summary column (`triangles`, `t_total_s_mean`).
    pub metric: String,
    /// Our value.
    pub ours: Option<f64>,
    /// The dissertation's value.
    pub theirs: Option<f64>,
    /// Ours / theirs.
    pub ratio: Option<f64>,
}

/// Reads `paper_comparison.csv` (`id,metric,ours,theirs,ratio`).
pub fn read_paper_comparison(path: &Path) -> Result<Vec<PaperRow>> {
    let file = CsvFile::read(path)?;
    let mut rows = Vec::with_capacity(file.rows.len());
    for r in 0..file.rows.len() {
        rows.push(PaperRow {
            id: file.text(r, "id")?.to_string(),
            metric: file.text(r, "metric")?.to_string(),
            ours: file.number(r, "ours")?,
            theirs: file.number(r, "theirs")?,
            ratio: file.number(r, "ratio")?,
        });
    }
    Ok(rows)
}

/// The seed the single-seed tables show: 7 (the dissertation's asteroid, the asteroid's default
/// seed) when the study has it, else the study's first seed.
pub fn representative_seed(from: u64, to: u64) -> u64 {
    if (from..=to).contains(&7) {
        7
    } else {
        from
    }
}

/// A metric's distribution over the seeds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spread {
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation.
    pub sd: Option<f64>,
    /// 95% confidence interval of the mean.
    pub ci: Option<(f64, f64)>,
    /// Smallest and largest value.
    pub range: (f64, f64),
}

/// One row of `seeds.csv`.
#[derive(Clone, Debug, PartialEq)]
pub struct SeedRow {
    /// Configuration id without seed.
    pub id: String,
    /// Object name.
    pub object: String,
    /// `mt` or `mc`.
    pub method: String,
    /// Lattice.
    pub lattice: String,
    /// Clustering.
    pub clustering: String,
    /// Number of seeds, first and last.
    pub seeds: (u64, u64, u64),
    /// Output triangles.
    pub triangles: Option<Spread>,
    /// Triangle reduction against no clustering.
    pub reduction: Option<Spread>,
    /// Mean radius ratio.
    pub radius_ratio: Option<Spread>,
    /// Mean distance to the surface, grid spacings.
    pub fidelity: Option<Spread>,
    /// The dissertation's triangles, reduction and radius ratio (single asteroid).
    pub paper: [Option<f64>; 3],
}

impl SeedRow {
    /// `BCDL, integrated` or `marching cubes`.
    pub fn description(&self) -> String {
        if self.method == "mc" {
            "marching cubes".into()
        } else {
            format!("{}, {}", lattice_name(&self.lattice), self.clustering)
        }
    }

    /// `marching cubes` or the clustering: the variant a seed figure colours.
    pub(crate) fn variant(&self) -> String {
        if self.method == "mc" {
            "marching cubes".into()
        } else {
            self.clustering.clone()
        }
    }
}

/// Reads `seeds.csv`.
pub fn read_seeds(path: &Path) -> Result<Vec<SeedRow>> {
    let file = CsvFile::read(path)?;
    let mut rows = Vec::with_capacity(file.rows.len());
    for r in 0..file.rows.len() {
        let spread = |m: &str| -> Result<Option<Spread>> {
            let Some(mean) = file.number(r, &format!("{m}_mean"))? else {
                return Ok(None);
            };
            let lo = file.number(r, &format!("{m}_ci_low"))?;
            let hi = file.number(r, &format!("{m}_ci_high"))?;
            Ok(Some(Spread {
                mean,
                sd: file.number(r, &format!("{m}_sd"))?,
                ci: lo.zip(hi),
                range: (
                    file.number(r, &format!("{m}_min"))?.unwrap_or(mean),
                    file.number(r, &format!("{m}_max"))?.unwrap_or(mean),
                ),
            }))
        };
        let int = |name: &str| -> Result<u64> { Ok(file.required(r, name)? as u64) };
        let paper = |m: &str| -> Result<Option<f64>> {
            if file.has(&format!("paper_{m}")) {
                file.number(r, &format!("paper_{m}"))
            } else {
                Ok(None)
            }
        };
        rows.push(SeedRow {
            id: file.text(r, "id")?.to_string(),
            object: file.text(r, "object")?.to_string(),
            method: file.text(r, "method")?.to_string(),
            lattice: file.text(r, "lattice")?.to_string(),
            clustering: file.text(r, "clustering")?.to_string(),
            seeds: (int("seeds")?, int("seed_from")?, int("seed_to")?),
            triangles: spread("triangles")?,
            reduction: spread("triangle_reduction")?,
            radius_ratio: spread("ar_mean")?,
            fidelity: spread("fidelity_mean_h")?,
            paper: [
                paper("triangles")?,
                paper("triangle_reduction")?,
                paper("ar_mean")?,
            ],
        });
    }
    Ok(rows)
}

/// A run folder read for the report.
#[derive(Clone, Debug, PartialEq)]
pub struct Run {
    /// The folder.
    pub folder: PathBuf,
    /// Its provenance.
    pub info: RunInfo,
    /// Its configurations.
    pub configurations: Vec<Configuration>,
    /// The comparison with the dissertation, when the run has one.
    pub paper: Option<Vec<PaperRow>>,
    /// A seed study's distributions (`seeds.csv`); its per-seed configurations are then left out
    /// of [`Run::configurations`] except one seed each ([`representative_seed`]).
    pub seeds: Option<Vec<SeedRow>>,
}

impl Run {
    /// Reads `run.json`, `summary.csv` and (if present) `paper_comparison.csv` from `folder`.
    pub fn read(folder: &Path) -> Result<Run> {
        let need = |name: &str, hint: &str| -> Result<PathBuf> {
            let path = folder.join(name);
            if path.is_file() {
                Ok(path)
            } else {
                Err(ReportError::MissingFile {
                    path,
                    hint: hint.to_string(),
                })
            }
        };
        let info = RunInfo::read(&need(
            RUN_JSON,
            "the run folder's provenance, written by `experiments run`",
        )?)?;
        let mut configurations = read_summary(&need(
            SUMMARY_CSV,
            "written when a run finishes; continue an unfinished run with `experiments run \
             --resume <folder>`",
        )?)?;
        let paper_path = folder.join(PAPER_CSV);
        let paper = if paper_path.is_file() {
            Some(read_paper_comparison(&paper_path)?)
        } else {
            None
        };
        let seeds_path = folder.join(SEEDS_CSV);
        let seeds = if seeds_path.is_file() {
            Some(read_seeds(&seeds_path)?)
        } else {
            None
        };
        if let Some(rows) = &seeds {
            // Keep one seed of each seeded configuration: `<id>_s<seed>`.
            configurations.retain(|c| {
                !rows.iter().any(|r| {
                    c.id.strip_prefix(r.id.as_str())
                        .and_then(|rest| rest.strip_prefix("_s"))
                        .and_then(|s| s.parse::<u64>().ok())
                        .is_some_and(|seed| seed != representative_seed(r.seeds.1, r.seeds.2))
                })
            });
        }
        Ok(Run {
            folder: folder.to_path_buf(),
            info,
            configurations,
            paper,
            seeds,
        })
    }

    /// Object names in order of first appearance.
    pub fn objects(&self) -> Vec<String> {
        let mut objects: Vec<String> = Vec::new();
        for c in &self.configurations {
            if !objects.contains(&c.object) {
                objects.push(c.object.clone());
            }
        }
        objects
    }

    /// Configurations grouped by object (objects in order of first appearance, configurations in
    /// file order within each).
    pub fn by_object(&self) -> Vec<(String, Vec<&Configuration>)> {
        self.objects()
            .into_iter()
            .map(|o| {
                let members = self
                    .configurations
                    .iter()
                    .filter(|c| c.object == o)
                    .collect();
                (o, members)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_dissertation_seed_is_shown_when_the_study_has_it() {
        assert_eq!(representative_seed(1, 200), 7);
        assert_eq!(representative_seed(8, 20), 8);
        assert_eq!(representative_seed(7, 7), 7);
    }
}
