//! Colours: sRGB bytes at the edges (settings, images, palettes), linear light inside the shader.
//!
//! Shading and the supersampling box filter work in linear light, so an edge pixel half covered
//! by a surface gets the physically half-way brightness; the result is encoded to sRGB through a
//! 4096-entry table, so the encoding is the same bytes on every run.

use glam::Vec3;
use std::sync::OnceLock;

/// An sRGB colour, 8 bits per channel.
pub type Rgb8 = [u8; 3];

/// Entries of the linear-to-sRGB table: a step of 1/4095 in linear light is below one 8-bit sRGB
/// step everywhere (the steepest part of the curve, near black, has slope 12.92).
const ENCODE_STEPS: usize = 4096;

/// The sRGB transfer function, one channel, 0..=255 to linear 0..=1.
pub fn srgb_to_linear(c: u8) -> f32 {
    let c = f32::from(c) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// An sRGB colour as linear RGB.
pub fn rgb8_to_linear(c: Rgb8) -> Vec3 {
    Vec3::new(
        srgb_to_linear(c[0]),
        srgb_to_linear(c[1]),
        srgb_to_linear(c[2]),
    )
}

fn encode_table() -> &'static [u8] {
    static TABLE: OnceLock<Vec<u8>> = OnceLock::new();
    TABLE.get_or_init(|| {
        (0..ENCODE_STEPS)
            .map(|i| {
                let l = i as f64 / (ENCODE_STEPS - 1) as f64;
                let s = if l <= 0.003_130_8 {
                    12.92 * l
                } else {
                    1.055 * l.powf(1.0 / 2.4) - 0.055
                };
                (s * 255.0).round().clamp(0.0, 255.0) as u8
            })
            .collect()
    })
}

/// Linear RGB (clamped to 0..=1) to sRGB bytes.
pub fn linear_to_rgb8(c: Vec3) -> Rgb8 {
    let table = encode_table();
    let encode = |v: f32| {
        let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
        table[(v * (ENCODE_STEPS - 1) as f32 + 0.5) as usize]
    };
    [encode(c.x), encode(c.y), encode(c.z)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_round_trip_is_exact_for_every_byte() {
        for v in 0..=255u8 {
            let back = linear_to_rgb8(rgb8_to_linear([v, v, v]));
            assert_eq!(back, [v, v, v], "byte {v}");
        }
    }

    #[test]
    fn out_of_range_values_clamp() {
        assert_eq!(linear_to_rgb8(Vec3::new(-1.0, 2.0, f32::NAN)), [0, 255, 0]);
    }
}
