//! Triangle quality (being written: the bodies below are placeholders).
use crate::Mesh;
use serde::{Deserialize, Serialize};

/// Triangle quality statistics. Ratios exclude zero-area triangles (counted apart).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct QualityReport {
    /// Mean radius ratio R / (2r) (1 = equilateral).
    pub ar_mean: f64,
    /// Standard deviation of the radius ratio.
    pub ar_sd: f64,
    /// Median radius ratio.
    pub ar_median: f64,
    /// 95th percentile of the radius ratio.
    pub ar_p95: f64,
    /// 99th percentile of the radius ratio.
    pub ar_p99: f64,
    /// Largest radius ratio.
    pub ar_max: f64,
    /// Share of triangles with radius ratio above 2.
    pub ar_share_above_2: f64,
    /// Mean Verdict aspect ratio l_max / (2 sqrt(3) r).
    pub verdict_ar_mean: f64,
    /// Mean of each triangle's smallest angle, degrees.
    pub min_angle_deg_mean: f64,
    /// Smallest angle in the mesh, degrees.
    pub min_angle_deg_min: f64,
    /// Mean triangle area.
    pub area_mean: f64,
    /// Standard deviation of triangle area.
    pub area_sd: f64,
    /// Smallest triangle area.
    pub area_min: f64,
    /// Largest triangle area.
    pub area_max: f64,
    /// Total area.
    pub area_total: f64,
}

/// Measures every triangle of `mesh`.
pub fn quality(_mesh: &Mesh) -> QualityReport {
    QualityReport::default()
}
