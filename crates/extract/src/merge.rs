//! Vertex merging with an exact local check (in progress).
/// Scratch buffers for merging.
#[derive(Default)]
pub struct MergeBuffers {}
