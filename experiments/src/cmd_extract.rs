//! `experiments extract` (in progress: owned by the runner work).
/// Arguments of `extract`.
#[derive(clap::Args, Debug)]
pub struct Args {}
/// Runs `extract`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("extract is being written")
}
