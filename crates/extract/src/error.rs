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
    /// A value given to extract from (not sampled from a field) is NaN or infinite: the first
    /// such slot of the sample array. Found by the first pass over the values of marching
    /// cubes, surface nets and marching tetrahedra on the simple lattice, where the slot is
    /// lattice point `(x, y, z)` at `x + (nx + 1) * (y + (ny + 1) * z)`: the C order of a
    /// `(z, y, x)` volume.
    #[error(
        "the sample array is not finite at lattice point (x, y, z) = ({}, {}, {}), slot {slot}: \
         got {value}",
        point[0],
        point[1],
        point[2]
    )]
    NonFiniteValue {
        /// The slot of the sample array (the first non-finite one in storage order).
        slot: usize,
        /// Its lattice point `(x, y, z)`.
        point: [usize; 3],
        /// The value.
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
