//! One extraction's full description ([`Extraction`]): object, box, resolution and extractor
//! settings, shared by `extract` and the runner; the names these take on the command line, in
//! manifests and in CSV files (every choice listed once: [`LATTICES`], [`CLUSTERINGS`],
//! [`METHODS`], [`NORMALS`]); and one extraction's record as JSON ([`config_json`],
//! [`measurement_json`]), which `extract --json`, the studio and `raw.csv` share.

use rmt_extract::{Clustering, ExtractSettings, Grid, Lattice, Measurement, Method, NormalMode};
use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};

use crate::objects::{Bounds, ObjectSpec, Resolution};
use crate::simplify::{simplify_name, Simplify};

/// How normals are computed, with the names used on the command line and in manifests
/// (`area`, `gradient`, `none`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Normals {
    /// Area-weighted mean of the face normals (the dissertation's choice).
    #[default]
    Area,
    /// Central differences of the field.
    Gradient,
    /// No normals.
    None,
}

impl Normals {
    /// The extractor's setting.
    pub fn mode(self) -> NormalMode {
        match self {
            Normals::Area => NormalMode::AreaWeighted,
            Normals::Gradient => NormalMode::Gradient,
            Normals::None => NormalMode::Skip,
        }
    }

    /// The name (`area`, `gradient`, `none`).
    pub fn name(self) -> &'static str {
        match self {
            Normals::Area => "area",
            Normals::Gradient => "gradient",
            Normals::None => "none",
        }
    }
}

/// Every lattice, in the order help texts and errors list them.
pub const LATTICES: [Lattice; 2] = [Lattice::BodyCentred, Lattice::Simple];

/// Every clustering mode, in the order help texts and errors list them.
pub const CLUSTERINGS: [Clustering; 5] = [
    Clustering::None,
    Clustering::Integrated,
    Clustering::IntegratedUnchecked,
    Clustering::Postprocessed,
    Clustering::Meshopt,
];

/// Every method, in the order help texts and errors list them.
pub const METHODS: [Method; 3] = [Method::Mt, Method::Mc, Method::SurfaceNets];

/// Every normals mode, in the order help texts and errors list them.
pub const NORMALS: [Normals; 3] = [Normals::Area, Normals::Gradient, Normals::None];

/// The names of `all`, by `name`.
pub fn names<T: Copy>(all: &[T], name: fn(T) -> &'static str) -> Vec<&'static str> {
    all.iter().map(|&x| name(x)).collect()
}

/// Choices as help texts and errors list them: `a, b or c`.
pub fn one_of<S: AsRef<str>>(names: &[S]) -> String {
    match names.split_last() {
        None => String::new(),
        Some((last, [])) => last.as_ref().to_string(),
        Some((last, rest)) => {
            let rest: Vec<&str> = rest.iter().map(AsRef::as_ref).collect();
            format!("{} or {}", rest.join(", "), last.as_ref())
        }
    }
}

/// Parses a name of [`LATTICES`] (`bcdl`, `simple`).
pub fn parse_lattice(s: &str) -> Result<Lattice, String> {
    LATTICES.into_iter().find(|l| l.name() == s).ok_or_else(|| {
        format!(
            "unknown lattice `{s}` (expected {})",
            one_of(&names(&LATTICES, Lattice::name))
        )
    })
}

/// Parses a name of [`CLUSTERINGS`] (`none`, `integrated`, `integrated-unchecked`,
/// `postprocessed`, `meshopt`).
pub fn parse_clustering(s: &str) -> Result<Clustering, String> {
    CLUSTERINGS
        .into_iter()
        .find(|c| c.name() == s)
        .ok_or_else(|| {
            format!(
                "unknown clustering `{s}` (expected {})",
                one_of(&names(&CLUSTERINGS, Clustering::name))
            )
        })
}

/// Parses a name of [`METHODS`] (`mt`, `mc`).
pub fn parse_method(s: &str) -> Result<Method, String> {
    METHODS
        .into_iter()
        .find(|&m| method_name(m) == s)
        .ok_or_else(|| {
            format!(
                "unknown method `{s}` (expected {})",
                one_of(&names(&METHODS, method_name))
            )
        })
}

/// Parses a name of [`NORMALS`] (`area`, `gradient`, `none`).
pub fn parse_normals(s: &str) -> Result<Normals, String> {
    NORMALS.into_iter().find(|n| n.name() == s).ok_or_else(|| {
        format!(
            "unknown normals `{s}` (expected {})",
            one_of(&names(&NORMALS, Normals::name))
        )
    })
}

/// The method's name (`mt`, `mc`, `surface-nets`).
pub fn method_name(m: Method) -> &'static str {
    match m {
        Method::Mt => "mt",
        Method::Mc => "mc",
        Method::SurfaceNets => "surface-nets",
    }
}

/// The method's full name (`marching tetrahedra`, `marching cubes`, `surface nets`).
pub fn method_title(m: Method) -> &'static str {
    match m {
        Method::Mt => "marching tetrahedra",
        Method::Mc => "marching cubes",
        Method::SurfaceNets => "surface nets",
    }
}

/// The lattice a configuration samples, by name: marching cubes and surface nets sample the
/// simple cubic lattice whatever the setting says.
pub fn lattice_name(method: Method, lattice: Lattice) -> &'static str {
    match method {
        Method::Mc | Method::SurfaceNets => Lattice::Simple.name(),
        Method::Mt => lattice.name(),
    }
}

/// Everything that decides one extraction.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Extraction {
    /// The object and its parameters.
    pub object: ObjectSpec,
    /// The sampled box.
    pub bounds: Bounds,
    /// Cells per axis.
    pub resolution: Resolution,
    /// Marching tetrahedra or marching cubes.
    pub method: Method,
    /// The tetrahedral lattice (marching cubes: always simple).
    pub lattice: Lattice,
    /// Vertex merging.
    pub clustering: Clustering,
    /// Edge-collapse threshold (post-processed) or error bound (meshopt), in grid spacings.
    pub collapse_threshold: f32,
    /// The isovalue.
    pub iso: f32,
    /// Normals.
    pub normals: Normals,
    /// meshoptimizer's simplifier down to a budget after extraction ([`crate::finish`]).
    pub simplify: Option<Simplify>,
    /// meshoptimizer's vertex-cache order after extraction (and simplification).
    pub vertex_cache: bool,
}

/// Threads to use when not told: every core the process may use.
pub fn default_threads() -> usize {
    std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1)
}

/// The configuration keys of an extraction on `threads` threads, as `extract --json` prints
/// them before the measurement.
pub fn config_json(e: &Extraction, threads: usize) -> Map<String, Value> {
    let mut m = Map::new();
    m.insert("object".into(), e.object.kind.name().into());
    m.insert("lattice".into(), lattice_name(e.method, e.lattice).into());
    m.insert("clustering".into(), e.clustering.name().into());
    m.insert("method".into(), method_name(e.method).into());
    m.insert("resolution".into(), serde_json::json!(e.resolution.cells()));
    m.insert(
        "bounds".into(),
        serde_json::json!(<[f32; 6]>::from(e.bounds)),
    );
    m.insert(
        "collapse_threshold".into(),
        serde_json::json!(e.collapse_threshold),
    );
    m.insert("iso".into(), serde_json::json!(e.iso));
    m.insert("normals".into(), e.normals.name().into());
    m.insert("simplify".into(), simplify_name(e.simplify.as_ref()).into());
    m.insert("vertex_cache".into(), e.vertex_cache.into());
    m.insert("threads".into(), threads.into());
    m
}

/// The measurement as an ordered JSON map (its serde keys, flattened): the keys of
/// `extract --json` after the configuration and the measurement columns of `raw.csv`.
pub fn measurement_json(m: &Measurement) -> anyhow::Result<Map<String, Value>> {
    use anyhow::Context;
    match serde_json::to_value(m).context("serialising the measurement")? {
        Value::Object(map) => Ok(map),
        other => anyhow::bail!("the measurement serialised to {other}, not an object"),
    }
}

/// The extractor's default collapse threshold, in grid spacings.
pub fn default_collapse_threshold() -> f32 {
    ExtractSettings::new(Grid::cube(1, 1.0), Lattice::Simple, Clustering::None).collapse_threshold
}

impl Extraction {
    /// The extractor settings for `threads` worker threads.
    pub fn settings(&self, threads: usize) -> ExtractSettings {
        let grid = Grid::new(self.resolution.cells(), self.bounds.min, self.bounds.max);
        let lattice = match self.method {
            Method::Mc | Method::SurfaceNets => Lattice::Simple,
            Method::Mt => self.lattice,
        };
        let mut s = ExtractSettings::new(grid, lattice, self.clustering);
        s.method = self.method;
        s.collapse_threshold = self.collapse_threshold;
        s.iso = self.iso;
        s.threads = threads;
        s.normals = self.normals.mode();
        s
    }

    /// Checks what can be checked without building the field: grid, settings, the memory the
    /// sample array and per-point tables would need, and method/clustering combinations.
    pub fn check(&self, threads: usize) -> Result<(), String> {
        let settings = self.settings(threads);
        settings.check().map_err(|e| e.to_string())?;
        if self.method != Method::Mt && self.clustering != Clustering::None {
            return Err(format!(
                "{} takes clustering none, got {}",
                method_title(self.method),
                self.clustering.name()
            ));
        }
        check_memory(&settings)
    }
}

/// The clustering a method takes when none is named: integrated (RMT) for marching tetrahedra,
/// none for marching cubes and surface nets (which take no other).
pub fn default_clustering(method: Method) -> Clustering {
    match method {
        Method::Mt => Clustering::Integrated,
        Method::Mc | Method::SurfaceNets => Clustering::None,
    }
}

/// Checks that `path` names a mesh format the writers know (`.ply`, `.obj`, `.glb`, any case).
pub fn check_mesh_path(path: &std::path::Path) -> anyhow::Result<()> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    match ext.as_deref() {
        Some("ply" | "obj" | "glb") => Ok(()),
        _ => anyhow::bail!(
            "{}: unknown mesh format (the extension must be .ply, .obj or .glb)",
            path.display()
        ),
    }
}

/// Estimated bytes of working memory per sample slot: the extractor keeps 10 per slot (a 4-byte
/// value, 2 bytes of crossing flags, a 4-byte first-crossing id); the rest is headroom for the
/// buffers that grow with the surface (crossings, clusters, triangles, the output mesh), which for
/// a dense surface such as a fine gyroid approach the volume's size.
pub const BYTES_PER_SAMPLE_ESTIMATE: u64 = 24;

/// The estimated bytes an extraction with `settings` holds: sample slots times
/// [`BYTES_PER_SAMPLE_ESTIMATE`] (saturating).
pub fn estimated_bytes(settings: &ExtractSettings) -> u64 {
    let [nx, ny, nz] = settings.grid.cells.map(|c| c as u64);
    let slots = match rmt_extract::samples::sampled_lattice(settings) {
        Lattice::Simple => (nx + 1).saturating_mul(ny + 1).saturating_mul(nz + 1),
        Lattice::BodyCentred => (nx + 2)
            .saturating_mul(ny + 2)
            .saturating_mul(nz.saturating_mul(2) + 3),
    };
    slots.saturating_mul(BYTES_PER_SAMPLE_ESTIMATE)
}

/// Memory the system reports as available (Linux `MemAvailable`), if known.
pub fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Refuses settings whose estimated memory exceeds what is available, before allocating.
pub fn check_memory(settings: &ExtractSettings) -> Result<(), String> {
    let need = estimated_bytes(settings);
    match available_memory() {
        Some(have) if need > have => Err(format!(
            "resolution {:?} needs an estimated {} (sample array and per-point tables), more than \
             the {} of memory available",
            settings.grid.cells,
            human_bytes(need),
            human_bytes(have)
        )),
        _ => Ok(()),
    }
}

/// `1.5 GiB`-style sizes.
pub fn human_bytes(b: u64) -> String {
    let units = ["B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"];
    let mut v = b as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < units.len() {
        v /= 1024.0;
        u += 1;
    }
    format!("{v:.1} {}", units[u])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn measurement_keys_follow_the_stats_fields_in_order() {
        let keys: Vec<String> = measurement_json(&Measurement::default())
            .unwrap()
            .keys()
            .cloned()
            .collect();
        assert_eq!(keys[0], "vertices");
        assert!(keys.iter().any(|k| k == "t_total_s"));
        assert!(keys.iter().any(|k| k == "fidelity_mean_h"));
    }

    #[test]
    fn parsers_accept_their_lists_and_name_them_when_refusing() {
        assert_eq!(one_of(&["a"]), "a");
        assert_eq!(one_of(&["a", "b", "c"]), "a, b or c");
        for l in LATTICES {
            assert_eq!(parse_lattice(l.name()), Ok(l));
        }
        for c in CLUSTERINGS {
            assert_eq!(parse_clustering(c.name()), Ok(c));
        }
        for m in METHODS {
            assert_eq!(parse_method(method_name(m)), Ok(m));
        }
        for n in NORMALS {
            assert_eq!(parse_normals(n.name()), Ok(n));
        }
        assert_eq!(
            parse_lattice("hex").unwrap_err(),
            "unknown lattice `hex` (expected bcdl or simple)"
        );
        assert_eq!(
            parse_clustering("x").unwrap_err(),
            "unknown clustering `x` (expected none, integrated, integrated-unchecked, \
             postprocessed or meshopt)"
        );
        assert_eq!(
            parse_method("x").unwrap_err(),
            "unknown method `x` (expected mt, mc or surface-nets)"
        );
        assert_eq!(
            parse_normals("x").unwrap_err(),
            "unknown normals `x` (expected area, gradient or none)"
        );
    }

    #[test]
    fn names_round_trip() {
        for s in ["bcdl", "simple"] {
            assert_eq!(parse_lattice(s).unwrap().name(), s);
        }
        for s in [
            "none",
            "integrated",
            "integrated-unchecked",
            "postprocessed",
            "meshopt",
        ] {
            assert_eq!(parse_clustering(s).unwrap().name(), s);
        }
        for s in ["mt", "mc"] {
            assert_eq!(method_name(parse_method(s).unwrap()), s);
        }
        for s in ["area", "gradient", "none"] {
            assert_eq!(parse_normals(s).unwrap().name(), s);
        }
        assert!(parse_lattice("fcc").unwrap_err().contains("fcc"));
        assert!(parse_clustering("all").is_err());
        assert!(parse_method("dc").is_err());
    }

    #[test]
    fn memory_estimate_grows_with_resolution_and_refuses_huge_grids() {
        let small = Grid::cube(10, 1.0);
        let big = Grid::cube(40, 1.0);
        let s = |g| ExtractSettings::new(g, Lattice::BodyCentred, Clustering::None);
        // Four times the cells per axis: at least 4^3 / 2 times the memory (boundary slots aside).
        assert!(estimated_bytes(&s(big)) > 32 * estimated_bytes(&s(small)));
        assert!(check_memory(&s(small)).is_ok());
        let huge = ExtractSettings::new(
            Grid::new([1 << 20; 3], glam::Vec3::ZERO, glam::Vec3::ONE),
            Lattice::Simple,
            Clustering::None,
        );
        if available_memory().is_some() {
            assert!(check_memory(&huge)
                .unwrap_err()
                .contains("needs an estimated"));
        }
    }

    #[test]
    fn human_bytes_picks_a_unit() {
        assert_eq!(human_bytes(512), "512.0 B");
        assert_eq!(human_bytes(3 << 30), "3.0 GiB");
    }
}
