//! `experiments bench`: the extraction benchmark of [`crate::bench`] without criterion, printed as
//! a table or as one JSON object `{"results": [...]}`.
//!
//! ```text
//! experiments bench --fields sphere,asteroid --sizes 32,64,128 --reps 20 --threads 1,2 [--pin] --json
//! experiments bench --sizes 64,128 --threads 1 --python .venv/bin/python [--dump DIR]
//! ```

use anyhow::{Context, Result};

use crate::bench::{format_table, run_bench, BenchConfig, BenchField};
use rmt_extract::ThreadPlacement;

/// Arguments of `bench`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Fields, comma-separated: sphere, asteroid.
    #[arg(long, value_delimiter = ',', default_value = "sphere,asteroid")]
    pub fields: Vec<String>,
    /// Cells per axis, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "32,64,128")]
    pub sizes: Vec<usize>,
    /// Timed repetitions of every method (interleaved; the median is reported).
    #[arg(long, default_value_t = 20)]
    pub reps: usize,
    /// Thread counts of our methods, comma-separated (the peers are single-threaded).
    #[arg(long, value_delimiter = ',', default_value = "1,2")]
    pub threads: Vec<usize>,
    /// Bind worker i of each of our pools to the i-th CPU (Linux): an idle pool's woken workers
    /// then cannot end up sharing one CPU (see `rmt_extract::threads`). Default: the OS places
    /// them.
    #[arg(long)]
    pub pin: bool,
    /// Also time VTK's Flying Edges and scikit-image's marching_cubes on the same values, with
    /// this Python 3 (it needs numpy, vtk and scikit-image), and give every row its ratio over
    /// Flying Edges.
    #[arg(long, value_name = "PY")]
    pub python: Option<String>,
    /// Keep the sampled corner grids (FIELD_N.f32 and FIELD_N.json, format rmt-values-1) and the
    /// peer script in this folder.
    #[arg(long, value_name = "DIR")]
    pub dump: Option<std::path::PathBuf>,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Runs `bench`.
pub fn run(args: Args) -> Result<()> {
    let fields = args
        .fields
        .iter()
        .map(|f| BenchField::parse(f))
        .collect::<Result<Vec<_>, _>>()
        .context("reading --fields")?;
    let config = BenchConfig {
        fields,
        sizes: args.sizes,
        reps: args.reps,
        threads: args.threads,
        placement: if args.pin {
            ThreadPlacement::Pinned
        } else {
            ThreadPlacement::Os
        },
        dump: args.dump,
        python: args.python,
    };
    let report = run_bench(&config, |line| eprintln!("bench: {line}"))?;
    if args.json {
        let text = serde_json::to_string_pretty(&report).context("serialising the results")?;
        println!("{text}");
    } else {
        print!("{}", format_table(&report));
    }
    Ok(())
}
