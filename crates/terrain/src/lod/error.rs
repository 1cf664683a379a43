//! Why a multiresolution mesh could not be built. The lowest module of `lod`: it imports none of
//! the others (a chunk is named by its level and index, not by [`super::ChunkKey`], so the
//! level map can return this error without an import cycle).

/// Why a multiresolution mesh could not be built.
#[derive(Debug, thiserror::Error)]
pub enum LodError {
    /// Bad geometry or settings.
    #[error("invalid level-of-detail settings: {0}")]
    Invalid(String),
    /// A chunk that is not a leaf of the level map.
    #[error("chunk at level {level}, index {at:?} is not in the level map")]
    NoSuchChunk {
        /// The chunk's level.
        level: u8,
        /// Its index among the chunks of that level.
        at: [i32; 3],
    },
    /// The closure left a pattern no green template handles (a bug, never expected).
    #[error("closure incomplete: {0}")]
    Closure(String),
}
