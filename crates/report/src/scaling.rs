//! Time against resolution: the configurations of a run grouped into one series per method
//! (object, method, lattice, clustering, collapse threshold), and the power law `t = a N^b`
//! fitted to each by least squares on `log t` against `log N`.

use crate::data::{lattice_name, Run};

/// One method's times over the resolutions, with its fitted growth exponent.
#[derive(Clone, Debug, PartialEq)]
pub struct ScalingFit {
    /// `BCDL, none`, `marching cubes` (prefixed by the object when there are several).
    pub label: String,
    /// Object.
    pub object: String,
    /// `mt` or `mc`.
    pub method: String,
    /// Lattice.
    pub lattice: String,
    /// Clustering.
    pub clustering: String,
    /// The colour key (clustering, or marching cubes).
    pub variant: String,
    /// (cells per axis N, mean total seconds), sorted by N.
    pub points: Vec<(f64, f64)>,
    /// b of t = a N^b, with at least two resolutions.
    pub exponent: Option<f64>,
    /// a of t = a N^b.
    pub coefficient: Option<f64>,
    /// Coefficient of determination of the log-log fit (at least three resolutions).
    pub r_squared: Option<f64>,
}

impl ScalingFit {
    /// The fitted time at `n` cells per axis.
    pub fn predict(&self, n: f64) -> Option<f64> {
        Some(self.coefficient? * n.powf(self.exponent?))
    }
}

/// Least-squares fit of `ln y = ln a + b ln x` over points with positive coordinates:
/// `(a, b, R²)`; `None` below two distinct x. R² is `None` below three points (it would be 1).
pub fn power_fit(points: &[(f64, f64)]) -> Option<(f64, f64, Option<f64>)> {
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0 && x.is_finite() && y.is_finite())
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    let n = logs.len() as f64;
    if logs.len() < 2 {
        return None;
    }
    let mx = logs.iter().map(|p| p.0).sum::<f64>() / n;
    let my = logs.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = logs.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = logs.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let syy: f64 = logs.iter().map(|p| (p.1 - my).powi(2)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let b = sxy / sxx;
    let a = (my - b * mx).exp();
    let r_squared = (logs.len() >= 3).then(|| {
        if syy > 0.0 {
            (sxy * sxy) / (sxx * syy)
        } else {
            1.0
        }
    });
    Some((a, b, r_squared))
}

/// The series of a run, in order of first appearance, each fitted; series with a single
/// resolution are kept without a fit.
pub fn fit_scaling(run: &Run) -> Vec<ScalingFit> {
    let objects = run.objects();
    let mut keys: Vec<(String, String, String, String, String)> = Vec::new();
    for c in &run.configurations {
        let key = (
            c.object.clone(),
            c.method.clone(),
            c.lattice.clone(),
            c.clustering.clone(),
            c.collapse_threshold.clone(),
        );
        if !keys.contains(&key) {
            keys.push(key);
        }
    }
    let mut fits: Vec<ScalingFit> = keys
        .iter()
        .map(|(object, method, lattice, clustering, threshold)| {
            let members: Vec<_> = run
                .configurations
                .iter()
                .filter(|c| {
                    &c.object == object
                        && &c.method == method
                        && &c.lattice == lattice
                        && &c.clustering == clustering
                        && &c.collapse_threshold == threshold
                })
                .collect();
            let mut points: Vec<(f64, f64)> = members
                .iter()
                .map(|c| (c.cells_per_axis(), c.mean_time("total")))
                .collect();
            points.sort_by(|a, b| a.0.total_cmp(&b.0));
            let first = members[0];
            let mut label = if first.is_marching_cubes() {
                "marching cubes".to_string()
            } else {
                format!("{}, {}", lattice_name(lattice), clustering)
            };
            if objects.len() > 1 {
                label = format!("{object}: {label}");
            }
            let fit = power_fit(&points);
            ScalingFit {
                label,
                object: object.clone(),
                method: method.clone(),
                lattice: lattice.clone(),
                clustering: clustering.clone(),
                variant: first.variant(),
                points,
                exponent: fit.map(|f| f.1),
                coefficient: fit.map(|f| f.0),
                r_squared: fit.and_then(|f| f.2),
            }
        })
        .collect();
    // Series that differ only in the collapse threshold get it in their label.
    for i in 0..fits.len() {
        if fits
            .iter()
            .filter(|f| f.label == fits[i].label)
            .nth(1)
            .is_some()
        {
            let threshold = &keys[i].4;
            fits[i].label = format!("{} (threshold {threshold})", fits[i].label);
        }
    }
    fits
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn power_fit_recovers_an_exact_power_law() {
        let points: Vec<(f64, f64)> = [16.0, 32.0, 64.0, 128.0]
            .iter()
            .map(|&n: &f64| (n, 2e-7 * n.powf(2.9)))
            .collect();
        let (a, b, r2) = power_fit(&points).unwrap();
        assert!((b - 2.9).abs() < 1e-9, "{b}");
        assert!((a - 2e-7).abs() < 1e-15, "{a}");
        assert!((r2.unwrap() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn power_fit_needs_two_distinct_resolutions() {
        assert!(power_fit(&[(16.0, 1.0)]).is_none());
        assert!(power_fit(&[(16.0, 1.0), (16.0, 2.0)]).is_none());
        let (_, b, r2) = power_fit(&[(10.0, 1.0), (100.0, 10.0)]).unwrap();
        assert!((b - 1.0).abs() < 1e-12);
        assert_eq!(r2, None);
    }

    #[test]
    fn noisy_points_give_r_squared_below_one() {
        let (_, b, r2) = power_fit(&[(1.0, 1.0), (2.0, 9.0), (4.0, 60.0), (8.0, 500.0)]).unwrap();
        assert!(b > 2.5 && b < 3.5, "{b}");
        let r2 = r2.unwrap();
        assert!(r2 > 0.9 && r2 < 1.0, "{r2}");
    }
}
