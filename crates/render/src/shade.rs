//! Lighting: a fixed rig in camera space, Blinn-Phong, smooth or flat normals, and the box filter
//! that turns `s x s` samples into one pixel.
//!
//! The rig is attached to the camera, so during a turntable the object turns under a constant
//! light: the key light comes from the upper left and slightly in front, a weaker fill from the
//! right keeps the shadow side readable, an ambient term keeps it from going black. Only the key
//! light makes a highlight. Camera space: x to the right, y up, z towards the viewer.
//!
//! colour = material * (ambient + sum_i intensity_i * max(0, n . l_i))
//!        + specular * max(0, n . h)^shininess,   h = normalize(l_key + z)
//!
//! all in linear light (the viewer is taken at infinity, so `h` is one vector per frame).

use crate::color::{linear_to_rgb8, rgb8_to_linear, Rgb8};
use crate::raster::{GBuffer, NO_TRIANGLE};
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// Which normal lights a sample.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Shading {
    /// Vertex normals interpolated per sample (perspective-correct) and renormalised: Phong
    /// shading, what a game engine shows for a mesh with smooth normals.
    #[default]
    Smooth,
    /// One normal per triangle: every facet visible.
    Flat,
}

/// A directional light fixed to the camera.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Light {
    /// Direction from the surface towards the light, camera space (need not be unit length).
    pub direction: [f32; 3],
    /// Diffuse intensity (1 = full material colour when facing the light).
    pub intensity: f32,
}

/// The light rig: ambient, a key light (which also makes the highlight) and a fill light.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LightRig {
    /// Ambient intensity.
    pub ambient: f32,
    /// The main light, from the upper left.
    pub key: Light,
    /// The secondary light, from the right.
    pub fill: Light,
    /// Strength of the white highlight of the key light.
    pub specular: f32,
    /// Blinn-Phong exponent of the highlight.
    pub shininess: u32,
}

impl Default for LightRig {
    fn default() -> Self {
        Self {
            ambient: 0.12,
            key: Light {
                direction: [-0.5, 0.6, 0.62],
                intensity: 0.85,
            },
            fill: Light {
                direction: [0.75, -0.15, 0.45],
                intensity: 0.25,
            },
            specular: 0.18,
            shininess: 32,
        }
    }
}

/// The rig, material and background of one frame, ready to shade samples.
#[derive(Clone, Copy, Debug)]
pub struct Shader {
    material: Vec3,
    background: Vec3,
    ambient: f32,
    lights: [(Vec3, f32); 2],
    half_vector: Vec3,
    specular: f32,
    shininess: i32,
}

impl Shader {
    /// A shader for `rig`, a material and a background colour (both sRGB).
    pub fn new(rig: &LightRig, material: Rgb8, background: Rgb8) -> Self {
        let key = Vec3::from(rig.key.direction).normalize_or(Vec3::Z);
        let fill = Vec3::from(rig.fill.direction).normalize_or(Vec3::Z);
        Self {
            material: rgb8_to_linear(material),
            background: rgb8_to_linear(background),
            ambient: rig.ambient,
            lights: [(key, rig.key.intensity), (fill, rig.fill.intensity)],
            half_vector: (key + Vec3::Z).normalize_or(Vec3::Z),
            specular: rig.specular,
            shininess: i32::try_from(rig.shininess).unwrap_or(i32::MAX),
        }
    }

    /// The background in linear light.
    pub fn background(&self) -> Vec3 {
        self.background
    }

    /// Linear colour of a surface with camera-space unit normal `n`.
    pub fn shade(&self, n: Vec3) -> Vec3 {
        let diffuse: f32 = self.ambient
            + self
                .lights
                .iter()
                .map(|&(l, i)| i * n.dot(l).max(0.0))
                .sum::<f32>();
        // powi is repeated multiplication: the same bits on every platform.
        let highlight = self.specular * n.dot(self.half_vector).max(0.0).powi(self.shininess);
        self.material * diffuse + Vec3::splat(highlight)
    }
}

/// Where the normal of a sample comes from, in camera space.
#[derive(Clone, Copy, Debug)]
pub enum Normals<'a> {
    /// Per-vertex normals, interpolated with the G-buffer's barycentrics; the index buffer maps
    /// triangles to vertices. Where the interpolated normal vanishes the face normal is used.
    Smooth {
        /// One normal per vertex.
        vertex: &'a [Vec3],
        /// One unit normal per triangle.
        face: &'a [Vec3],
        /// Three vertex indices per triangle.
        indices: &'a [u32],
    },
    /// One unit normal per triangle.
    Flat(&'a [Vec3]),
}

impl Normals<'_> {
    fn at(&self, triangle: usize, [b1, b2]: [f32; 2]) -> Vec3 {
        match *self {
            Normals::Flat(face) => face[triangle],
            Normals::Smooth {
                vertex,
                face,
                indices,
            } => {
                let t = &indices[3 * triangle..3 * triangle + 3];
                let n = vertex[t[0] as usize] * (1.0 - b1 - b2)
                    + vertex[t[1] as usize] * b1
                    + vertex[t[2] as usize] * b2;
                n.normalize_or(face[triangle])
            }
        }
    }
}

/// Shades every sample of `gbuffer` and averages each `supersampling x supersampling` block into
/// one pixel of `pixels` (sRGB) and `coverage` (share of covered samples), row-major.
pub fn resolve(
    gbuffer: &GBuffer,
    supersampling: u32,
    shader: &Shader,
    normals: Normals<'_>,
    pixels: &mut Vec<Rgb8>,
    coverage: &mut Vec<f32>,
) {
    let s = supersampling as usize;
    let (width, height) = (gbuffer.width as usize / s, gbuffer.height as usize / s);
    let samples_per_pixel = (s * s) as f32;
    pixels.clear();
    coverage.clear();
    let background = linear_to_rgb8(shader.background);
    for py in 0..height {
        for px in 0..width {
            // Most pixels of a turntable see only the background: skip the filter there (the
            // result is the background byte-exact, which the palette keeps as index 0).
            let empty = (py * s..(py + 1) * s).all(|sy| {
                let row = sy * gbuffer.width as usize;
                gbuffer.triangle[row + px * s..row + (px + 1) * s]
                    .iter()
                    .all(|&t| t == NO_TRIANGLE)
            });
            if empty {
                pixels.push(background);
                coverage.push(0.0);
                continue;
            }
            let mut sum = Vec3::ZERO;
            let mut covered = 0u32;
            for sy in py * s..(py + 1) * s {
                let row = sy * gbuffer.width as usize;
                for sx in px * s..(px + 1) * s {
                    let i = row + sx;
                    let t = gbuffer.triangle[i];
                    if t == NO_TRIANGLE {
                        sum += shader.background;
                    } else {
                        covered += 1;
                        sum += shader.shade(normals.at(t as usize, gbuffer.barycentric[i]));
                    }
                }
            }
            pixels.push(linear_to_rgb8(sum / samples_per_pixel));
            coverage.push(covered as f32 / samples_per_pixel);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn surfaces_facing_the_key_light_are_brighter_than_those_facing_away() {
        let rig = LightRig::default();
        let shader = Shader::new(&rig, [140, 160, 190], [240, 240, 240]);
        let towards = shader.shade(Vec3::from(rig.key.direction).normalize());
        let away = shader.shade(-Vec3::from(rig.key.direction).normalize());
        let upper_left = shader.shade(Vec3::new(-0.5, 0.5, 0.7).normalize());
        let lower_right = shader.shade(Vec3::new(0.5, -0.5, 0.7).normalize());
        assert!(towards.x > away.x && towards.y > away.y && towards.z > away.z);
        assert!(upper_left.length() > lower_right.length());
        // Facing away from every light leaves the ambient term only.
        let ambient = shader.material * rig.ambient;
        assert!((shader.shade(Vec3::new(0.0, 0.0, -1.0)) - ambient).length() < 1e-6);
    }
}
