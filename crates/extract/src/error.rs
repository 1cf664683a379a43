//! The error of an extraction that cannot run.

/// Why an extraction could not run.
#[derive(Debug, thiserror::Error)]
pub enum ExtractError {
    /// Bad grid dimensions or bounds.
    #[error("invalid grid: {0}")]
    InvalidGrid(String),
    /// Bad settings other than the grid.
    #[error("invalid settings: {0}")]
    InvalidSettings(String),
    /// The lattice would not fit in memory.
    #[error(
        "grid of {cells:?} cells is too large: its lattice would exceed {limit} sample points"
    )]
    TooLarge {
        /// The requested cells per axis.
        cells: [usize; 3],
        /// The sample point limit.
        limit: usize,
    },
    /// The field returned NaN or infinity.
    #[error("the field is not finite at ({x}, {y}, {z}): got {value}")]
    NonFiniteSample {
        /// Position of the first bad sample (x).
        x: f32,
        /// Position of the first bad sample (y).
        y: f32,
        /// Position of the first bad sample (z).
        z: f32,
        /// The value returned.
        value: f32,
    },
    /// The requested combination is not available (e.g. a clustering mode for marching cubes).
    #[error("unsupported: {0}")]
    Unsupported(String),
    /// The worker thread pool could not be created.
    #[error("could not start {threads} worker threads: {message}")]
    ThreadPool {
        /// Requested threads.
        threads: usize,
        /// The error from rayon.
        message: String,
    },
}
