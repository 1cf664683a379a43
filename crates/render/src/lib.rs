//! Software rendering of meshes into turntable GIFs, and the questionnaire built from them.
//!
//! One job: turn [`rmt_mesh::Mesh`]es into the animations a perception study shows, with every
//! rendering parameter identical across configurations by construction.
//!
//! The pipeline, one module per step:
//!
//! 1. [`camera`]: a perspective camera that looks at the mesh's bounding sphere from a fixed
//!    elevation and distance (in sphere radii) and picks the field of view so that the sphere fills
//!    a fixed share of the frame.
//! 2. [`raster`]: a watertight rasteriser: vertices are snapped to 1/256 of a sample,
//!    edge functions are exact 64-bit integers with a top-left rule, back faces are culled and a
//!    `1/w` depth buffer keeps the nearest surface. It fills a G-buffer (triangle id, perspective-
//!    correct barycentrics), so shading runs once per visible sample.
//! 3. [`shade`]: Blinn-Phong with a fixed light rig in camera space (key light from the upper left,
//!    a weaker fill from the right, ambient), smooth (per-pixel interpolated vertex normals) or flat
//!    (face normals), lit in linear light, supersampled `s x s` and box-filtered, then encoded to
//!    sRGB; an optional anti-aliased wireframe ([`wireframe`], drawn with `tiny-skia`) goes on top.
//! 4. [`palette`]: one 255-colour palette per settings, never per mesh: median cut over a
//!    reference sphere rendered with the same settings (a sphere shows every normal, so every shade
//!    the light rig can produce), plus the exact background (and wire) colour.
//! 5. [`animation`]: frames of palette indices, GIF encoding (global palette, frames cropped to the
//!    rectangle that changed, loop forever), decoding with compositing, and side-by-side composition.
//! 6. [`turntable`]: the settings struct ([`TurntableSettings`]) and one full turn about the
//!    vertical (+y) axis: [`render_turntable_gif`].
//! 7. [`names`], [`questionnaire`], [`run_folder`]: seeded anonymous names, the question set (pairs
//!    of configurations that differ in exactly one variable, counterbalanced left/right, random
//!    order, reversed pairs, controls), the HTML answer sheet, and the run-folder layout used by
//!    `experiments render` and `experiments questionnaire`.
//!
//! Beside the pictures, [`cost`] measures what drawing a mesh costs a GPU ([`cost::RenderCost`]):
//! quad occupancy after a depth pre-pass at four screen sizes over eight views, on the same
//! rasteriser ([`raster`]'s edge functions, top-left rule and depth test, shared, not copied),
//! meshoptimizer's vertex-cache, overdraw and vertex-fetch analyzers, and buffer sizes.
//!
//! Determinism: no threads share mutable state, no hash-map iteration order reaches the output,
//! random choices come from a seeded SplitMix64, and floating-point work is the same sequence of
//! IEEE operations on every run; the same mesh and settings give the same bytes.
//!
//! Cost: a default turntable (72 frames of 256 x 256, 3 x 3 supersampling, smooth shading) of a
//! 59k-triangle bunny takes about 1 s of CPU time (0.95 s measured, 13 ms a frame; frames are
//! spread over the cores) plus 0.2 s of GIF encoding, and makes a GIF of about 1 MB
//! (`cargo run --release -p rmt-render --example turntable_bunny` reproduces the figures).
//!
//! ```
//! use rmt_render::{render_frame, TurntableSettings};
//! let mesh = rmt_render::shapes::uv_sphere(1.0, 24, 12);
//! let settings = TurntableSettings { width: 64, height: 64, ..TurntableSettings::default() };
//! let frame = render_frame(&mesh, &settings, 0.0).unwrap();
//! // The sphere is centred: the middle pixel is covered, the corner is background.
//! assert_eq!(frame.coverage_at(32, 32), 1.0);
//! assert_eq!(frame.pixel(0, 0), settings.background);
//! ```

pub mod animation;
pub mod camera;
pub mod color;
pub mod cost;
pub mod names;
pub mod palette;
pub mod questionnaire;
pub mod raster;
pub mod run_folder;
pub mod shade;
pub mod shapes;
pub mod turntable;
pub mod wireframe;

pub use animation::{decode_gif, DecodedGif, IndexedAnimation};
pub use turntable::{
    render_frame, render_turntable, render_turntable_gif, Frame, Renderer, TurntableSettings,
};

use std::path::PathBuf;

/// Everything that can go wrong while rendering or building a questionnaire.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A CSV file could not be read or written.
    #[error("{}: {source}", path.display())]
    Csv {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: csv::Error,
    },
    /// A CSV or JSON file is well formed but its content is wrong.
    #[error("{}: {message}", path.display())]
    BadFile {
        /// The file.
        path: PathBuf,
        /// What is wrong, naming the row, column or key.
        message: String,
    },
    /// A JSON file could not be read or written.
    #[error("{}: {source}", path.display())]
    Json {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: serde_json::Error,
    },
    /// A GIF could not be encoded.
    #[error("{}: GIF encoding: {source}", path.display())]
    GifEncode {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: gif::EncodingError,
    },
    /// A GIF could not be decoded.
    #[error("{}: GIF decoding: {source}", path.display())]
    GifDecode {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: gif::DecodingError,
    },
    /// Two animations cannot be put side by side.
    #[error("cannot put {left} and {right} side by side: {message}")]
    Mismatch {
        /// The left animation.
        left: String,
        /// The right animation.
        right: String,
        /// What differs.
        message: String,
    },
    /// A settings value is out of range.
    #[error("invalid render settings: {0}")]
    InvalidSettings(String),
    /// The mesh cannot be rendered.
    #[error("invalid mesh: {0}")]
    InvalidMesh(String),
    /// A mesh file could not be read (the error names the file).
    #[error(transparent)]
    MeshIo(#[from] rmt_mesh::io::MeshIoError),
    /// A mesh from a file cannot be rendered.
    #[error("{}: {message}", path.display())]
    MeshFile {
        /// The file.
        path: PathBuf,
        /// What is wrong with the mesh.
        message: String,
    },
    /// Questionnaire options that cannot be satisfied.
    #[error("questionnaire: {0}")]
    Questionnaire(String),
}

/// Result type of this crate.
pub type Result<T, E = RenderError> = std::result::Result<T, E>;

pub(crate) fn io_error(path: impl Into<PathBuf>) -> impl FnOnce(std::io::Error) -> RenderError {
    let path = path.into();
    move |source| RenderError::Io { path, source }
}
