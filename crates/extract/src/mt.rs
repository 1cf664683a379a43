//! Marching tetrahedra: vertex pass and geometry pass (in progress).
use crate::{merge::MergeBuffers, ExtractError, ExtractSettings, Samples, Stats};
use rmt_mesh::Mesh;

/// Per-point working arrays kept between extractions.
#[derive(Default)]
pub struct MtBuffers {}

/// Extracts the surface of `samples` (in progress).
pub fn extract(_s: &Samples, _settings: &ExtractSettings, _pool: &rayon::ThreadPool, _b: &mut MtBuffers, _m: &mut MergeBuffers, _mesh: &mut Mesh, _stats: &mut Stats) -> Result<(), ExtractError> {
    Err(ExtractError::Unsupported("marching tetrahedra is being written".into()))
}
