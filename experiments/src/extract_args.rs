//! The options of one extraction (`experiments extract`) as a library: the argument parser
//! ([`Args`]) and its check ([`extraction`]). The command line (`cmd_extract`) and the studio's
//! backend ([`crate::studio`]) both parse with it, so both accept and refuse the same things with
//! the same messages. The help texts that list choices are built from the lists the parsers
//! accept ([`ObjectKind::names`], [`config::LATTICES`], ...).

use std::path::PathBuf;

use anyhow::Result;
use rmt_extract::{Clustering, Lattice, Method};

use crate::config::{self, Extraction, Normals};
use crate::objects::{Bounds, ObjectKind, ObjectParams, ObjectSpec, Resolution};

/// Arguments of `extract`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Object: one of [`ObjectKind::names`].
    #[arg(long, default_value = "sphere", help = object_help())]
    pub object: String,
    /// Object parameters (each object takes only its own).
    #[command(flatten)]
    pub params: ObjectParams,
    /// Cells per axis: N or NX,NY,NZ.
    #[arg(long, default_value = "50")]
    pub resolution: Resolution,
    /// Sampled box xmin,ymin,zmin,xmax,ymax,zmax (default -1,-1,-1,1,1,1).
    #[arg(long, allow_hyphen_values = true)]
    pub bounds: Option<Bounds>,
    /// Lattice: one of [`config::LATTICES`] (ignored by marching cubes).
    #[arg(long, default_value = "bcdl", value_parser = config::parse_lattice, help = lattice_help())]
    pub lattice: Lattice,
    /// Clustering: one of [`config::CLUSTERINGS`] (default: integrated for marching tetrahedra,
    /// none for marching cubes).
    #[arg(long, value_parser = config::parse_clustering, help = clustering_help())]
    pub clustering: Option<Clustering>,
    /// Method: one of [`config::METHODS`].
    #[arg(long, default_value = "mt", value_parser = config::parse_method, help = method_help())]
    pub method: Method,
    /// Edge-collapse threshold (post-processed) or error bound (meshopt), in grid spacings.
    #[arg(long)]
    pub collapse_threshold: Option<f32>,
    /// Isovalue.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub iso: f32,
    /// Normals: one of [`config::NORMALS`].
    #[arg(long, default_value = "area", value_parser = config::parse_normals, help = normals_help())]
    pub normals: Normals,
    /// Simplify after extraction with meshoptimizer: none, meshopt:<target> or
    /// meshopt-locked:<target> (borders locked); the target is rmt (RMT's triangle count on the
    /// same object and resolution), a ratio in (0, 1) or a triangle count.
    #[arg(long, default_value = "none", value_parser = crate::simplify::SimplifyChoice::parse)]
    pub simplify: crate::simplify::SimplifyChoice,
    /// Reorder the triangles for the vertex cache (meshoptimizer), as an engine does before
    /// upload.
    #[arg(long)]
    pub vertex_cache: bool,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Write the mesh to this file, in the format its extension names: .ply (binary unless
    /// --ascii), .obj or .glb (binary glTF).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Write ASCII PLY instead of binary (with a .ply --out).
    #[arg(long)]
    pub ascii: bool,
    /// Render a turntable GIF of the mesh (default turntable settings) to this file.
    #[arg(long)]
    pub gif: Option<PathBuf>,
    /// Print one JSON object instead of a summary.
    #[arg(long)]
    pub json: bool,
    /// Extract in chunks of C^3 cells, weld the chunks and compare with the whole volume
    /// extracted at once. Integrated clustering of marching tetrahedra, checked or not, has
    /// exact seams (the chunks are the whole volume's own mesh, cut by anchor cell); the other
    /// modes mesh each chunk on its own, in parallel, under the tile rule (collapses never cross
    /// a chunk face).
    /// Needs cubic cells; adds the keys `chunk_size`, `chunks`, `t_chunked_s`, `t_whole_s`,
    /// `whole_triangles`, `chunked_equals_whole`.
    #[arg(long, value_name = "C")]
    pub chunks: Option<usize>,
}

/// The help of `--object`: every kind [`ObjectKind`] parses.
fn object_help() -> String {
    format!("Object: {}", config::one_of(&ObjectKind::names()))
}

/// The help of `--lattice`: every lattice [`config::parse_lattice`] accepts.
fn lattice_help() -> String {
    let names: Vec<&str> = config::LATTICES.iter().map(|l| l.name()).collect();
    format!(
        "Lattice: {} (ignored by marching cubes)",
        config::one_of(&names)
    )
}

/// The help of `--clustering`: every mode [`config::parse_clustering`] accepts.
fn clustering_help() -> String {
    let names: Vec<&str> = config::CLUSTERINGS.iter().map(|c| c.name()).collect();
    format!(
        "Clustering: {} (default: integrated for marching tetrahedra, none for marching cubes)",
        config::one_of(&names)
    )
}

/// The help of `--method`: every method [`config::parse_method`] accepts, with its long name.
fn method_help() -> String {
    let names: Vec<String> = config::METHODS
        .iter()
        .map(|&m| format!("{} ({})", config::method_name(m), config::method_title(m)))
        .collect();
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    format!("Method: {}", config::one_of(&names))
}

/// The help of `--normals`: every mode [`config::parse_normals`] accepts.
fn normals_help() -> String {
    let names: Vec<&str> = config::NORMALS.iter().map(|n| n.name()).collect();
    format!("Normals: {}", config::one_of(&names))
}

/// The extraction that `args` describe (checked, field not built yet), and its thread count.
pub fn extraction(args: &Args) -> Result<(Extraction, usize)> {
    let kind: ObjectKind = args.object.parse()?;
    let object = ObjectSpec::new(kind, args.params.clone())?;
    let threads = args.threads.unwrap_or_else(config::default_threads);
    let e = Extraction {
        object,
        bounds: args.bounds.unwrap_or_default(),
        resolution: args.resolution,
        method: args.method,
        lattice: args.lattice,
        clustering: args
            .clustering
            .unwrap_or_else(|| config::default_clustering(args.method)),
        collapse_threshold: args
            .collapse_threshold
            .unwrap_or_else(config::default_collapse_threshold),
        iso: args.iso,
        normals: args.normals,
        simplify: args.simplify.0,
        vertex_cache: args.vertex_cache,
    };
    e.check(threads).map_err(anyhow::Error::msg)?;
    Ok((e, threads))
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::{Args as _, Parser};

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: Args,
    }

    fn parse(line: &[&str]) -> Result<Args, clap::Error> {
        Cli::try_parse_from(std::iter::once("extract").chain(line.iter().copied())).map(|c| c.args)
    }

    /// The help text of option `id` (e.g. `object`).
    fn help_of(id: &str) -> String {
        let command = Args::augment_args(clap::Command::new("extract"));
        let arg = command.get_arguments().find(|a| a.get_id() == id);
        arg.and_then(|a| a.get_help())
            .map(|h| h.to_string())
            .unwrap_or_default()
    }

    /// The choices a help text lists after `Label: ` (`a, b or c`), parenthesised remarks left
    /// out.
    fn listed(help: &str) -> Vec<String> {
        let list = help.split_once(": ").map_or("", |(_, rest)| rest);
        let mut bare = String::new();
        let mut depth = 0;
        for ch in list.chars() {
            match ch {
                '(' => depth += 1,
                ')' => depth -= 1,
                _ if depth == 0 => bare.push(ch),
                _ => {}
            }
        }
        bare.replace(" or ", ", ")
            .split(',')
            .map(|s| s.trim().to_string())
            .collect()
    }

    #[test]
    fn object_help_lists_exactly_the_objects_the_parser_accepts() {
        let help = help_of("object");
        assert_eq!(listed(&help), ObjectKind::names(), "{help}");
        for name in ObjectKind::names() {
            let args = parse(&["--object", name]).unwrap();
            assert_eq!(args.object.parse::<ObjectKind>().unwrap().name(), name);
        }
        let mut command = Args::augment_args(clap::Command::new("extract"));
        let shown = command.render_help().to_string();
        for name in ["terrain", "caves", "random"] {
            assert!(
                shown.contains(name),
                "`extract --help` omits {name}:\n{shown}"
            );
        }
    }

    #[test]
    fn choice_helps_list_exactly_what_the_parsers_accept() {
        let cases = [
            ("lattice", config::names(&config::LATTICES, Lattice::name)),
            (
                "clustering",
                config::names(&config::CLUSTERINGS, Clustering::name),
            ),
            ("normals", config::names(&config::NORMALS, Normals::name)),
            (
                "method",
                config::names(&config::METHODS, config::method_name),
            ),
        ];
        for (option, want) in cases {
            let help = help_of(option);
            let got = listed(&help);
            assert_eq!(got, want, "--{option}: {help}");
            for name in got {
                let flag = format!("--{option}");
                assert!(
                    parse(&[&flag, &name]).is_ok(),
                    "--{option} {name} is listed but refused"
                );
            }
        }
        assert_eq!(
            help_of("method"),
            "Method: mt (marching tetrahedra), mc (marching cubes) or surface-nets (surface nets)"
        );
    }

    #[test]
    fn command_line_builds_the_described_extraction() {
        let args = parse(&[
            "--object",
            "sphere",
            "--radius",
            "0.5",
            "--resolution",
            "8,9,10",
            "--bounds",
            "-1,-2,-3,1,2,3",
            "--lattice",
            "simple",
            "--clustering",
            "postprocessed",
            "--collapse-threshold",
            "0.3",
            "--iso",
            "-0.1",
            "--threads",
            "2",
        ])
        .unwrap();
        let (e, threads) = extraction(&args).unwrap();
        let s = e.settings(threads);
        assert_eq!(s.grid.cells, [8, 9, 10]);
        assert_eq!(s.grid.min, glam::Vec3::new(-1.0, -2.0, -3.0));
        assert_eq!(s.lattice, Lattice::Simple);
        assert_eq!(s.clustering, Clustering::Postprocessed);
        assert_eq!(s.collapse_threshold, 0.3);
        assert_eq!(s.iso, -0.1);
        assert_eq!(s.threads, 2);
        let keys: Vec<String> = config::config_json(&e, threads).keys().cloned().collect();
        assert_eq!(
            &keys[..5],
            ["object", "lattice", "clustering", "method", "resolution"]
        );
    }

    #[test]
    fn bad_command_lines_give_errors_not_panics() {
        assert!(parse(&["--resolution", "0"]).is_err());
        assert!(parse(&["--bounds", "NaN,0,0,1,1,1"]).is_err());
        assert!(parse(&["--lattice", "hex"]).is_err());
        let unknown = parse(&["--object", "teapot"]).unwrap();
        assert!(extraction(&unknown)
            .unwrap_err()
            .to_string()
            .contains("teapot"));
        let wrong_param = parse(&["--object", "gyroid", "--radius", "2"]).unwrap();
        assert!(extraction(&wrong_param)
            .unwrap_err()
            .to_string()
            .contains("radius"));
        let mc = parse(&["--method", "mc", "--clustering", "integrated"]).unwrap();
        assert!(extraction(&mc)
            .unwrap_err()
            .to_string()
            .contains("marching cubes"));
        let mc_unchecked = parse(&["--method", "mc", "--clustering", "none"]).unwrap();
        assert!(extraction(&mc_unchecked).is_ok());
        let threads = parse(&["--threads", "0"]).unwrap();
        assert!(extraction(&threads)
            .unwrap_err()
            .to_string()
            .contains("threads"));
    }

    #[test]
    fn the_default_clustering_follows_the_method() {
        let (mc, _) = extraction(&parse(&["--method", "mc"]).unwrap()).unwrap();
        assert_eq!(mc.clustering, Clustering::None);
        let (mt, _) = extraction(&parse(&[]).unwrap()).unwrap();
        assert_eq!(mt.clustering, Clustering::Integrated);
    }
}
