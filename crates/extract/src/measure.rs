//! One flat record per extraction: counters and timings ([`Stats`]), topology checks
//! ([`ValidationReport`]), triangle quality ([`QualityReport`]) and fidelity. Serialised with serde
//! it gives the JSON keys of `experiments extract --json` and the runner's CSV columns.

use glam::Vec3;
use rmt_fields::ScalarField;
use rmt_mesh::{quality, validate, Mesh, QualityReport, ValidationReport};
use serde::Serialize;

use crate::{ExtractSettings, Grid, Stats};

/// Everything measured about one extraction.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Measurement {
    /// Counters and stage times.
    #[serde(flatten)]
    pub stats: Stats,
    /// Closed, manifold, oriented? Euler characteristic and components.
    #[serde(flatten)]
    pub validation: ValidationReport,
    /// Triangle quality.
    #[serde(flatten)]
    pub quality: QualityReport,
    /// Mean distance of the vertices to the true surface, in grid spacings (fields that know it).
    pub fidelity_mean_h: Option<f64>,
    /// Largest distance of a vertex to the true surface, in grid spacings.
    pub fidelity_max_h: Option<f64>,
}

/// Whether `p` lies on the outer boundary of `grid`'s box (within a millionth of a cell).
pub fn on_box_boundary(grid: &Grid, p: [f32; 3]) -> bool {
    let eps = grid.h() * 1e-5;
    let p = Vec3::from(p);
    let inside = p.cmpge(grid.min - eps).all() && p.cmple(grid.max + eps).all();
    let on_face =
        (p - grid.min).abs().min_element() <= eps || (grid.max - p).abs().min_element() <= eps;
    inside && on_face
}

/// Validates and measures `mesh`, extracted with `settings`; `field` gives fidelity when it knows
/// its surface distance.
pub fn measure(
    mesh: &Mesh,
    stats: &Stats,
    field: Option<&dyn ScalarField>,
    settings: &ExtractSettings,
) -> Measurement {
    let grid = settings.grid;
    let validation = validate(mesh, &|p| on_box_boundary(&grid, p));
    let quality = quality(mesh);
    let (fidelity_mean_h, fidelity_max_h) = match fidelity(mesh, field, grid.h()) {
        Some((mean, max)) => (Some(mean), Some(max)),
        None => (None, None),
    };
    Measurement {
        stats: stats.clone(),
        validation,
        quality,
        fidelity_mean_h,
        fidelity_max_h,
    }
}

/// Mean and max vertex distance to the field's surface in units of `h`.
fn fidelity(mesh: &Mesh, field: Option<&dyn ScalarField>, h: f32) -> Option<(f64, f64)> {
    let field = field?;
    if mesh.positions.is_empty() {
        return None;
    }
    let mut sum = 0.0f64;
    let mut max = 0.0f64;
    for p in &mesh.positions {
        let d = f64::from(field.surface_distance(Vec3::from(*p))?) / f64::from(h);
        sum += d;
        max = max.max(d);
    }
    Some((sum / mesh.positions.len() as f64, max))
}
