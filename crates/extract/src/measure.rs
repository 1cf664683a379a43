//! Validation, quality and fidelity of an extracted mesh, in one flat record (in progress).
/// Placeholder while the mesh crate's reports are written.
#[derive(Debug, Default, serde::Serialize)]
pub struct Measurement {}
/// Placeholder.
pub fn measure() -> Measurement { Measurement {} }
