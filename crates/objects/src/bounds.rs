//! The sampled box and the number of cells per axis, as the command line and manifests give them.

use std::str::FromStr;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::kind::ObjectError;

/// An axis-aligned box `[xmin, ymin, zmin, xmax, ymax, zmax]`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "[f32; 6]", into = "[f32; 6]")]
pub struct Bounds {
    /// Lower corner.
    pub min: Vec3,
    /// Upper corner.
    pub max: Vec3,
}

impl Default for Bounds {
    /// The cube `[-1, 1]^3`.
    fn default() -> Self {
        Self {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        }
    }
}

impl TryFrom<[f32; 6]> for Bounds {
    type Error = ObjectError;
    fn try_from(v: [f32; 6]) -> Result<Self, Self::Error> {
        let min = Vec3::new(v[0], v[1], v[2]);
        let max = Vec3::new(v[3], v[4], v[5]);
        if !(min.is_finite() && max.is_finite()) || min.cmpge(max).any() {
            return Err(ObjectError::InvalidBounds(v));
        }
        Ok(Self { min, max })
    }
}

impl From<Bounds> for [f32; 6] {
    fn from(b: Bounds) -> Self {
        [b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z]
    }
}

impl FromStr for Bounds {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let parts: Vec<&str> = s.split(',').map(str::trim).collect();
        if parts.len() != 6 {
            return Err(format!(
                "bounds need 6 comma-separated numbers xmin,ymin,zmin,xmax,ymax,zmax, got `{s}`"
            ));
        }
        let mut v = [0.0f32; 6];
        for (slot, part) in v.iter_mut().zip(&parts) {
            *slot = part
                .parse()
                .map_err(|_| format!("bounds: `{part}` is not a number"))?;
        }
        Bounds::try_from(v).map_err(|e| e.to_string())
    }
}

impl Bounds {
    /// The centre of the box.
    pub fn centre(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Half of the box's smallest side.
    pub fn half_min_side(&self) -> f32 {
        (self.max - self.min).min_element() * 0.5
    }
}

/// Cells per axis: one number (a cube) or three.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Resolution {
    /// The same number of cells on every axis.
    Cube(usize),
    /// Cells along x, y, z.
    Axes([usize; 3]),
}

impl Resolution {
    /// Cells along x, y, z.
    pub fn cells(self) -> [usize; 3] {
        match self {
            Resolution::Cube(n) => [n; 3],
            Resolution::Axes(a) => a,
        }
    }

    /// `64` for a cube, `75x40x56` otherwise (used in configuration ids).
    pub fn label(self) -> String {
        let [x, y, z] = self.cells();
        if x == y && y == z {
            x.to_string()
        } else {
            format!("{x}x{y}x{z}")
        }
    }
}

impl FromStr for Resolution {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let parse = |p: &str| {
            p.trim().parse::<usize>().map_err(|_| {
                format!("resolution: `{p}` is not a whole number of cells (use N or NX,NY,NZ)")
            })
        };
        let parts: Vec<&str> = s.split(',').collect();
        let r = match parts.as_slice() {
            [n] => Resolution::Cube(parse(n)?),
            [x, y, z] => Resolution::Axes([parse(x)?, parse(y)?, parse(z)?]),
            _ => return Err(format!("resolution: expected N or NX,NY,NZ, got `{s}`")),
        };
        if r.cells().contains(&0) {
            return Err(format!(
                "resolution: every axis needs at least one cell, got `{s}`"
            ));
        }
        Ok(r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resolution_and_bounds_parse_and_reject_bad_text() {
        assert_eq!("50".parse::<Resolution>().unwrap().cells(), [50; 3]);
        assert_eq!(
            "75,40,56".parse::<Resolution>().unwrap().label(),
            "75x40x56"
        );
        assert!("0".parse::<Resolution>().is_err());
        assert!("4,4".parse::<Resolution>().is_err());
        assert!("x".parse::<Resolution>().is_err());
        let b: Bounds = "-1,-2,-3,1,2,3".parse().unwrap();
        assert_eq!(b.max, Vec3::new(1.0, 2.0, 3.0));
        assert!("1,1,1,0,0,0".parse::<Bounds>().is_err());
        assert!("NaN,0,0,1,1,1".parse::<Bounds>().is_err());
        assert!("0,0,0,1,1".parse::<Bounds>().is_err());
    }
}
