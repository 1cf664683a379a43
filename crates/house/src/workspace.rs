//! The workspace's packages and their crate targets, each read and checked; and the report.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::graph::Graph;
use crate::parse::read_crate;

/// The check of one crate target.
#[derive(Debug)]
pub struct TargetCheck {
    /// `lib`, `bin main`, `test sphere`, `example passes`, `bench extract`.
    pub target: String,
    /// Its import graph, files relative to the package's folder.
    pub graph: Graph,
    /// Module files that could not be read.
    pub problems: Vec<String>,
}

/// The check of one package.
#[derive(Debug)]
pub struct PackageCheck {
    /// The package's name.
    pub name: String,
    /// Its folder, relative to the workspace.
    pub dir: PathBuf,
    /// Its crate targets.
    pub targets: Vec<TargetCheck>,
}

impl PackageCheck {
    /// The number of cycles over all targets.
    pub fn cycle_count(&self) -> usize {
        self.targets.iter().map(|t| t.graph.cycles().len()).sum()
    }
}

/// The folder of the workspace that contains `start` (the first ancestor whose `Cargo.toml` has
/// a `[workspace]` table).
pub fn workspace_root(start: &Path) -> Option<PathBuf> {
    start.ancestors().find_map(|dir| {
        let manifest = std::fs::read_to_string(dir.join("Cargo.toml")).ok()?;
        manifest
            .lines()
            .any(|l| l.trim() == "[workspace]")
            .then(|| dir.to_path_buf())
    })
}

/// The member folders listed in the workspace manifest (`members = [..]`, `dir/*` expanded),
/// sorted.
pub fn members(root: &Path) -> std::io::Result<Vec<PathBuf>> {
    let manifest = std::fs::read_to_string(root.join("Cargo.toml"))?;
    let start = manifest
        .find("members")
        .and_then(|i| manifest[i..].find('[').map(|j| i + j + 1));
    let list = start
        .and_then(|s| manifest[s..].find(']').map(|e| &manifest[s..s + e]))
        .unwrap_or("");
    let mut dirs = Vec::new();
    for entry in list
        .split(',')
        .map(|s| s.trim().trim_matches('"'))
        .filter(|s| !s.is_empty())
    {
        if let Some(parent) = entry.strip_suffix("/*") {
            for sub in std::fs::read_dir(root.join(parent))? {
                let sub = sub?.path();
                if sub.join("Cargo.toml").is_file() {
                    dirs.push(sub.strip_prefix(root).unwrap_or(&sub).to_path_buf());
                }
            }
        } else {
            dirs.push(PathBuf::from(entry));
        }
    }
    dirs.sort();
    Ok(dirs)
}

/// Checks every crate target of every workspace member.
pub fn check_workspace(root: &Path) -> std::io::Result<Vec<PackageCheck>> {
    members(root)?
        .into_iter()
        .map(|dir| check_package(root, &dir))
        .collect()
}

/// Checks the crate targets of the package in `root/dir`: `src/lib.rs`, `src/main.rs`,
/// `src/bin/*`, and the `tests`, `examples` and `benches` files Cargo finds by itself.
pub fn check_package(root: &Path, dir: &Path) -> std::io::Result<PackageCheck> {
    let folder = root.join(dir);
    let manifest = std::fs::read_to_string(folder.join("Cargo.toml"))?;
    let name = manifest
        .lines()
        .skip_while(|l| l.trim() != "[package]")
        .find_map(|l| {
            let (key, value) = l.split_once('=')?;
            (key.trim() == "name").then(|| value.trim().trim_matches('"').to_string())
        })
        .unwrap_or_else(|| dir.display().to_string());
    let mut roots: Vec<(String, PathBuf)> = Vec::new();
    for (kind, file) in [("lib", "src/lib.rs"), ("bin", "src/main.rs")] {
        if folder.join(file).is_file() {
            let label = if kind == "lib" {
                "lib".to_string()
            } else {
                format!("bin {name}")
            };
            roots.push((label, PathBuf::from(file)));
        }
    }
    for (kind, sub) in [
        ("bin", "src/bin"),
        ("test", "tests"),
        ("example", "examples"),
        ("bench", "benches"),
    ] {
        let Ok(entries) = std::fs::read_dir(folder.join(sub)) else {
            continue;
        };
        let mut found = Vec::new();
        for entry in entries {
            let path = entry?.path();
            let stem = path
                .file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or("")
                .to_string();
            if path.extension().is_some_and(|e| e == "rs") {
                found.push((
                    format!("{kind} {stem}"),
                    Path::new(sub).join(format!("{stem}.rs")),
                ));
            } else if path.join("main.rs").is_file() {
                found.push((
                    format!("{kind} {stem}"),
                    Path::new(sub).join(&stem).join("main.rs"),
                ));
            }
        }
        found.sort();
        roots.extend(found);
    }
    let read = |p: &Path| std::fs::read_to_string(folder.join(p)).ok();
    let targets = roots
        .into_iter()
        .map(|(target, file)| {
            let krate = read_crate(&file, &read);
            TargetCheck {
                target,
                graph: Graph::of(&krate),
                problems: krate.problems,
            }
        })
        .collect();
    Ok(PackageCheck {
        name,
        dir: dir.to_path_buf(),
        targets,
    })
}

/// The report: one line per package (targets, modules, imports, cycles), then each cycle with
/// its files and the imports inside it (`a -> b: names (line)`).
pub fn render(packages: &[PackageCheck]) -> String {
    let mut out = String::new();
    let total: usize = packages.iter().map(PackageCheck::cycle_count).sum();
    for p in packages {
        let lib_or_bin: Vec<&TargetCheck> = p
            .targets
            .iter()
            .filter(|t| t.target == "lib" || t.target.starts_with("bin"))
            .collect();
        let sizes: Vec<String> = lib_or_bin
            .iter()
            .map(|t| {
                format!(
                    "{} {} files, {} imports",
                    t.target,
                    t.graph.nodes.len(),
                    t.graph.edge_count()
                )
            })
            .collect();
        let others = p.targets.len() - lib_or_bin.len();
        let cycles = p.cycle_count();
        let verdict = match cycles {
            0 => "no cycles".to_string(),
            1 => "1 CYCLE".to_string(),
            n => format!("{n} CYCLES"),
        };
        let _ = writeln!(
            out,
            "{} ({}): {}; {} test/example/bench targets: {}",
            p.name,
            p.dir.display(),
            sizes.join("; "),
            others,
            verdict
        );
        for t in &p.targets {
            for problem in &t.problems {
                let _ = writeln!(out, "  note ({}): {problem}", t.target);
            }
            for cycle in t.graph.cycles() {
                let name = |n: usize| {
                    let node = &t.graph.nodes[n];
                    let file = p.dir.join(&node.file).display().to_string();
                    if node.test {
                        format!("{file} [tests]")
                    } else {
                        file
                    }
                };
                let files: Vec<String> = cycle.iter().map(|&n| name(n)).collect();
                let _ = writeln!(
                    out,
                    "  cycle in {} ({} files): {}",
                    t.target,
                    files.len(),
                    files.join(", ")
                );
                for (&(a, b), names) in &t.graph.edges {
                    if cycle.contains(&a) && cycle.contains(&b) {
                        let listed: Vec<String> = names
                            .iter()
                            .map(|(n, line)| format!("{n} (line {line})"))
                            .collect();
                        let _ =
                            writeln!(out, "    {} -> {}: {}", name(a), name(b), listed.join(", "));
                    }
                }
            }
        }
    }
    let _ = writeln!(
        out,
        "{} packages, {} crate targets: {}",
        packages.len(),
        packages.iter().map(|p| p.targets.len()).sum::<usize>(),
        match total {
            0 => "no cycles".to_string(),
            1 => "1 cycle".to_string(),
            n => format!("{n} cycles"),
        }
    );
    out
}
