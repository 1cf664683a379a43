//! Marching cubes (in progress).
use crate::{ExtractSettings, Samples, Stats};
use rmt_mesh::Mesh;

/// Marching cubes over the simple-lattice samples (in progress).
pub fn extract(_s: &Samples, _settings: &ExtractSettings, _pool: &rayon::ThreadPool, _mesh: &mut Mesh, _stats: &mut Stats) {}
