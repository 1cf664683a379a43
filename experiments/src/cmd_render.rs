//! `experiments render <run>`: a turntable GIF of every configuration of a run folder, under
//! anonymous names, with `render/settings.json` and `key.csv` (see `rmt_render::run_folder`).

use anyhow::Context;
use rmt_render::shade::Shading;
use rmt_render::wireframe::Wireframe;
use rmt_render::TurntableSettings;
use std::path::PathBuf;

/// Arguments of `render`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The run folder (holds `configurations.csv` and `meshes/<id>.ply`).
    pub run: PathBuf,
    /// Seed of the anonymous animation names (keep it as secret as key.csv).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Render settings as JSON (the format of render/settings.json); flags below override it.
    #[arg(long)]
    pub settings: Option<PathBuf>,
    /// Frame width in pixels.
    #[arg(long)]
    pub width: Option<u32>,
    /// Frame height in pixels.
    #[arg(long)]
    pub height: Option<u32>,
    /// Frames per turn.
    #[arg(long)]
    pub frames: Option<u32>,
    /// Frames per second.
    #[arg(long)]
    pub fps: Option<u32>,
    /// Camera elevation in degrees.
    #[arg(long)]
    pub elevation: Option<f32>,
    /// Camera distance in bounding-sphere radii.
    #[arg(long)]
    pub distance: Option<f32>,
    /// Share of the frame's shorter side that the bounding sphere's image spans, (0, 1].
    #[arg(long)]
    pub fill: Option<f32>,
    /// Supersampling factor per axis.
    #[arg(long)]
    pub supersampling: Option<u32>,
    /// Flat shading (face normals) instead of smooth.
    #[arg(long)]
    pub flat: bool,
    /// Draw the wireframe over the surface.
    #[arg(long)]
    pub wireframe: bool,
}

impl Args {
    /// The settings file (or the defaults) with the flags applied.
    pub fn settings(&self) -> anyhow::Result<TurntableSettings> {
        let mut s = match &self.settings {
            Some(path) => TurntableSettings::read_json(path)?,
            None => TurntableSettings::default(),
        };
        s.width = self.width.unwrap_or(s.width);
        s.height = self.height.unwrap_or(s.height);
        s.frames = self.frames.unwrap_or(s.frames);
        s.fps = self.fps.unwrap_or(s.fps);
        s.elevation_degrees = self.elevation.unwrap_or(s.elevation_degrees);
        s.distance_radii = self.distance.unwrap_or(s.distance_radii);
        s.fill = self.fill.unwrap_or(s.fill);
        s.supersampling = self.supersampling.unwrap_or(s.supersampling);
        if self.flat {
            s.shading = Shading::Flat;
        }
        if self.wireframe && s.wireframe.is_none() {
            s.wireframe = Some(Wireframe::default());
        }
        s.validate()?;
        Ok(s)
    }
}

/// Runs `render`.
pub fn run(args: Args) -> anyhow::Result<()> {
    let settings = args.settings()?;
    let rendered =
        rmt_render::run_folder::render_run(&args.run, &settings, args.seed, |k, n, a| {
            eprintln!("[{k}/{n}] {} ({} kB)", a.path.display(), a.bytes / 1000);
        })
        .with_context(|| format!("rendering run folder {}", args.run.display()))?;
    let total: u64 = rendered.iter().map(|a| a.bytes).sum();
    println!(
        "{} turntables ({} frames, {}x{}, {} kB in all) in {}; key in {}",
        rendered.len(),
        settings.frames,
        settings.width,
        settings.height,
        total / 1000,
        args.run.join(rmt_render::run_folder::RENDER_DIR).display(),
        args.run.join(rmt_render::run_folder::KEY_FILE).display()
    );
    Ok(())
}
