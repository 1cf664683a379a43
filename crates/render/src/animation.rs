//! Indexed animations: GIF encoding and decoding, frame timing, side-by-side composition.
//!
//! Encoding writes one global palette, loops forever (NETSCAPE2.0 extension) and stores each frame
//! after the first as the smallest rectangle that changed since the previous one (disposal "keep"),
//! with unchanged pixels inside it transparent when that compresses better: a turntable's
//! background never changes, so only the object's box is stored. Decoding
//! composites frames onto the canvas, so a decoded frame is what a viewer shows.

use crate::color::Rgb8;
use crate::palette::{histogram, median_cut, Palette};
use crate::{io_error, RenderError, Result};
use gif::{ColorOutput, DecodeOptions, DisposalMethod, Encoder, Repeat};
use std::borrow::Cow;
use std::collections::BTreeMap;
use std::path::Path;

/// Frames of palette indices that share one palette.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct IndexedAnimation {
    /// Width in pixels.
    pub width: u16,
    /// Height in pixels.
    pub height: u16,
    /// At most 256 colours.
    pub palette: Vec<Rgb8>,
    /// One row-major `width * height` buffer of palette indices per frame.
    pub frames: Vec<Vec<u8>>,
    /// Display time of each frame in hundredths of a second (the GIF unit).
    pub delays: Vec<u16>,
}

/// Per-frame delays in hundredths of a second for `frames` frames at `fps` frames per second.
///
/// GIF delays are whole centiseconds, so 24 fps cannot be one constant delay; frame `k` lasts
/// `round(100 (k + 1) / fps) - round(100 k / fps)`, which keeps the clock exact on average (24 fps:
/// twenty frames of 4 cs and four of 5 cs per second).
pub fn frame_delays(frames: u32, fps: u32) -> Vec<u16> {
    let fps = u64::from(fps.max(1));
    let at = |k: u64| (200 * k + fps) / (2 * fps); // round(100 k / fps), halves up
    (0..u64::from(frames))
        .map(|k| (at(k + 1) - at(k)) as u16)
        .collect()
}

impl IndexedAnimation {
    /// Checks sizes, index ranges and the palette length.
    pub fn check(&self) -> std::result::Result<(), String> {
        if self.palette.is_empty() || self.palette.len() > 256 {
            return Err(format!(
                "palette has {} colours (1..=256 allowed)",
                self.palette.len()
            ));
        }
        if self.width == 0 || self.height == 0 || self.frames.is_empty() {
            return Err("empty animation".into());
        }
        if self.delays.len() != self.frames.len() {
            return Err(format!(
                "{} delays for {} frames",
                self.delays.len(),
                self.frames.len()
            ));
        }
        let n = usize::from(self.width) * usize::from(self.height);
        for (k, f) in self.frames.iter().enumerate() {
            if f.len() != n {
                return Err(format!("frame {k} has {} pixels, expected {n}", f.len()));
            }
            if let Some(&i) = f.iter().find(|&&i| usize::from(i) >= self.palette.len()) {
                return Err(format!("frame {k} uses index {i} beyond the palette"));
            }
        }
        Ok(())
    }

    /// Frame `k` as sRGB pixels.
    pub fn frame_rgb(&self, k: usize) -> Vec<Rgb8> {
        self.frames[k]
            .iter()
            .map(|&i| self.palette[usize::from(i)])
            .collect()
    }

    /// The GIF file as bytes.
    ///
    /// Frames after the first store only the rectangle that changed (disposal "keep"). Inside
    /// it, the pixels that did not change may be made transparent (shown from the previous
    /// frame): long runs of the transparent index compress well when much stays put; each frame
    /// is compressed both ways and the smaller kept. Transparency needs a palette index that no
    /// frame uses: the palette's first free slot when it has fewer than 256 colours, else an
    /// unused index if there is one, else none.
    pub fn encode_gif(&self) -> std::result::Result<Vec<u8>, gif::EncodingError> {
        if let Err(message) = self.check() {
            return Err(gif::EncodingError::Io(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                message,
            )));
        }
        let mut palette: Vec<u8> = self.palette.iter().flatten().copied().collect();
        let transparent = if self.palette.len() < 256 {
            palette.extend([0, 0, 0]);
            Some(self.palette.len() as u8)
        } else {
            let mut used = [false; 256];
            for &i in self.frames.iter().flatten() {
                used[usize::from(i)] = true;
            }
            used.iter().position(|&u| !u).map(|i| i as u8)
        };
        let mut bytes = Vec::new();
        {
            let mut encoder = Encoder::new(&mut bytes, self.width, self.height, &palette)?;
            encoder.set_repeat(Repeat::Infinite)?;
            let w = usize::from(self.width);
            for (k, frame) in self.frames.iter().enumerate() {
                let previous = if k == 0 {
                    None
                } else {
                    Some(&self.frames[k - 1])
                };
                let (left, top, right, bottom) = match previous {
                    None => (0, 0, w, usize::from(self.height)),
                    Some(p) => changed_rectangle(p, frame, w).unwrap_or((0, 0, 1, 1)),
                };
                let crop = |use_transparency: bool| -> gif::Frame<'static> {
                    let buffer: Vec<u8> = (top..bottom)
                        .flat_map(|y| (left..right).map(move |x| y * w + x))
                        .map(|i| match (previous, transparent) {
                            (Some(p), Some(t)) if use_transparency && p[i] == frame[i] => t,
                            _ => frame[i],
                        })
                        .collect();
                    let mut f = gif::Frame {
                        delay: self.delays[k],
                        dispose: DisposalMethod::Keep,
                        transparent: if use_transparency { transparent } else { None },
                        left: left as u16,
                        top: top as u16,
                        width: (right - left) as u16,
                        height: (bottom - top) as u16,
                        buffer: Cow::Owned(buffer),
                        ..gif::Frame::default()
                    };
                    f.make_lzw_pre_encoded();
                    f
                };
                // Transparency pays where much stays put (a turning sphere) and can cost where
                // everything moves (a turning bunny): keep the smaller encoding of the frame.
                let mut chosen = crop(false);
                if previous.is_some() && transparent.is_some() {
                    let see_through = crop(true);
                    if see_through.buffer.len() < chosen.buffer.len() {
                        chosen = see_through;
                    }
                }
                encoder.write_lzw_pre_encoded_frame(&chosen)?;
            }
        }
        Ok(bytes)
    }

    /// Writes the GIF file.
    pub fn write_gif(&self, path: &Path) -> Result<()> {
        let bytes = self.encode_gif().map_err(|source| RenderError::GifEncode {
            path: path.to_path_buf(),
            source,
        })?;
        std::fs::write(path, bytes).map_err(io_error(path))
    }

    /// Every pixel repeated `factor x factor` times (nearest neighbour).
    pub fn upscale_nearest(&self, factor: u16) -> Result<Self> {
        let f = usize::from(factor.max(1));
        let (w, h) = (usize::from(self.width), usize::from(self.height));
        let (width, height) = checked_size(w * f, h * f)?;
        let frames = self
            .frames
            .iter()
            .map(|frame| {
                let mut out = Vec::with_capacity(w * h * f * f);
                for row in frame.chunks_exact(w) {
                    let wide: Vec<u8> = row
                        .iter()
                        .flat_map(|&i| std::iter::repeat_n(i, f))
                        .collect();
                    for _ in 0..f {
                        out.extend_from_slice(&wide);
                    }
                }
                out
            })
            .collect();
        Ok(Self {
            width,
            height,
            palette: self.palette.clone(),
            frames,
            delays: self.delays.clone(),
        })
    }
}

fn checked_size(w: usize, h: usize) -> Result<(u16, u16)> {
    match (u16::try_from(w), u16::try_from(h)) {
        (Ok(w), Ok(h)) => Ok((w, h)),
        _ => Err(RenderError::InvalidSettings(format!(
            "{w} x {h} pixels exceeds the GIF limit of 65535 per side"
        ))),
    }
}

/// The bounding rectangle `(left, top, right, bottom)` (exclusive ends) of the pixels that differ.
fn changed_rectangle(a: &[u8], b: &[u8], width: usize) -> Option<(usize, usize, usize, usize)> {
    let mut rect: Option<(usize, usize, usize, usize)> = None;
    for (y, (ra, rb)) in a.chunks_exact(width).zip(b.chunks_exact(width)).enumerate() {
        let Some(first) = ra.iter().zip(rb).position(|(p, q)| p != q) else {
            continue;
        };
        let last = width
            - ra.iter()
                .zip(rb)
                .rev()
                .position(|(p, q)| p != q)
                .unwrap_or(0);
        rect = Some(match rect {
            None => (first, y, last, y + 1),
            Some((l, t, r, _)) => (l.min(first), t, r.max(last), y + 1),
        });
    }
    rect
}

/// A decoded GIF: every frame composited onto the canvas, as a viewer shows it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DecodedGif {
    /// Canvas width.
    pub width: u16,
    /// Canvas height.
    pub height: u16,
    /// One row-major RGBA canvas per frame (alpha 0 where nothing was ever drawn).
    pub frames: Vec<Vec<[u8; 4]>>,
    /// Frame delays in hundredths of a second.
    pub delays: Vec<u16>,
    /// The loop setting.
    pub repeat: Repeat,
}

/// Decodes a GIF file.
pub fn decode_gif(path: &Path) -> Result<DecodedGif> {
    let bytes = std::fs::read(path).map_err(io_error(path))?;
    decode_gif_bytes(&bytes).map_err(|source| RenderError::GifDecode {
        path: path.to_path_buf(),
        source,
    })
}

/// A frame's rectangle `(left, top, width, height)`, its disposal, and the canvas before it.
type PendingDisposal = ((usize, usize, usize, usize), DisposalMethod, Vec<[u8; 4]>);

/// Decodes GIF bytes.
pub fn decode_gif_bytes(bytes: &[u8]) -> std::result::Result<DecodedGif, gif::DecodingError> {
    let mut options = DecodeOptions::new();
    options.set_color_output(ColorOutput::RGBA);
    let mut decoder = options.read_info(bytes)?;
    let (width, height) = (decoder.width(), decoder.height());
    let (w, h) = (usize::from(width), usize::from(height));
    let mut canvas = vec![[0u8; 4]; w * h];
    let mut frames = Vec::new();
    let mut delays = Vec::new();
    // What to undo before the next frame: its rectangle, disposal, and the canvas before it.
    let mut pending: Option<PendingDisposal> = None;
    while let Some(frame) = decoder.read_next_frame()? {
        if let Some(((l, t, fw, fh), dispose, before)) = pending.take() {
            for y in t..(t + fh).min(h) {
                for x in l..(l + fw).min(w) {
                    match dispose {
                        DisposalMethod::Background => canvas[y * w + x] = [0; 4],
                        DisposalMethod::Previous => canvas[y * w + x] = before[y * w + x],
                        DisposalMethod::Any | DisposalMethod::Keep => {}
                    }
                }
            }
        }
        let (l, t) = (usize::from(frame.left), usize::from(frame.top));
        let (fw, fh) = (usize::from(frame.width), usize::from(frame.height));
        let before = if frame.dispose == DisposalMethod::Previous {
            canvas.clone()
        } else {
            Vec::new()
        };
        for (y, row) in frame
            .buffer
            .chunks_exact(4 * fw.max(1))
            .take(fh)
            .enumerate()
        {
            for (x, px) in row.chunks_exact(4).enumerate() {
                let (cx, cy) = (l + x, t + y);
                if cx < w && cy < h && px[3] != 0 {
                    canvas[cy * w + cx] = [px[0], px[1], px[2], px[3]];
                }
            }
        }
        frames.push(canvas.clone());
        delays.push(frame.delay);
        pending = Some(((l, t, fw, fh), frame.dispose, before));
    }
    Ok(DecodedGif {
        width,
        height,
        frames,
        delays,
        repeat: decoder.repeat(),
    })
}

/// Puts two animations next to each other, `gap` pixels apart on a `gap_color` background, and
/// scales the result by `scale` (nearest neighbour).
///
/// The animations must have the same size, frame count and delays (true for any two turntables
/// rendered with the same settings). Their colours are kept exactly when together they use at
/// most 255 (true when they share the settings' palette of 255); otherwise the composition is
/// quantised by median cut. `left_name` and `right_name` only label errors.
pub fn side_by_side(
    left: &DecodedGif,
    right: &DecodedGif,
    gap: u16,
    gap_color: Rgb8,
    scale: u16,
    (left_name, right_name): (&str, &str),
) -> Result<IndexedAnimation> {
    let mismatch = |message: String| RenderError::Mismatch {
        left: left_name.to_string(),
        right: right_name.to_string(),
        message,
    };
    if (left.width, left.height) != (right.width, right.height) {
        return Err(mismatch(format!(
            "sizes {}x{} and {}x{}",
            left.width, left.height, right.width, right.height
        )));
    }
    if left.frames.len() != right.frames.len() || left.frames.is_empty() {
        return Err(mismatch(format!(
            "frame counts {} and {}",
            left.frames.len(),
            right.frames.len()
        )));
    }
    if left.delays != right.delays {
        return Err(mismatch("frame delays differ".into()));
    }
    let (w, h) = (usize::from(left.width), usize::from(left.height));
    let g = usize::from(gap);
    let (cw, _) = checked_size(2 * w + g, h)?;
    let cw = usize::from(cw);
    let opaque = |p: [u8; 4]| {
        if p[3] == 0 {
            gap_color
        } else {
            [p[0], p[1], p[2]]
        }
    };
    let composed: Vec<Vec<Rgb8>> = left
        .frames
        .iter()
        .zip(&right.frames)
        .map(|(lf, rf)| {
            let mut out = Vec::with_capacity(cw * h);
            for y in 0..h {
                out.extend(lf[y * w..(y + 1) * w].iter().map(|&p| opaque(p)));
                out.extend(std::iter::repeat_n(gap_color, g));
                out.extend(rf[y * w..(y + 1) * w].iter().map(|&p| opaque(p)));
            }
            out
        })
        .collect();
    let hist = histogram(composed.iter().flatten().copied());
    // At most 255 colours leaves the encoder a transparent index.
    let colors: Vec<Rgb8> = if hist.len() <= 255 {
        hist.iter().map(|e| e.0).collect()
    } else {
        median_cut(&hist, 255)
    };
    let palette = Palette::new(colors).ok_or_else(|| mismatch("no colours".into()))?;
    let exact: BTreeMap<Rgb8, u8> = palette
        .colors()
        .iter()
        .enumerate()
        .map(|(i, &c)| (c, i as u8))
        .collect();
    let mut mapper = palette.mapper();
    let frames = composed
        .iter()
        .map(|f| {
            f.iter()
                .map(|c| exact.get(c).copied().unwrap_or_else(|| mapper.index(*c)))
                .collect()
        })
        .collect();
    let joined = IndexedAnimation {
        width: cw as u16,
        height: left.height,
        palette: palette.colors().to_vec(),
        frames,
        delays: left.delays.clone(),
    };
    joined.upscale_nearest(scale)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn toy(width: u16, height: u16, frames: usize, seed: u8) -> IndexedAnimation {
        let palette: Vec<Rgb8> = (0..5u8)
            .map(|i| [i * 50, 255 - i * 40, seed.wrapping_mul(i)])
            .collect();
        let n = usize::from(width) * usize::from(height);
        IndexedAnimation {
            width,
            height,
            palette,
            frames: (0..frames)
                .map(|k| {
                    (0..n)
                        .map(|p| ((p / 3 + k * usize::from(seed)) % 5) as u8)
                        .collect()
                })
                .collect(),
            delays: frame_delays(frames as u32, 24),
        }
    }

    #[test]
    fn delays_average_to_the_frame_rate() {
        let d = frame_delays(72, 24);
        assert_eq!(d.iter().map(|&d| u32::from(d)).sum::<u32>(), 300);
        assert!(d.iter().all(|&d| d == 4 || d == 5));
        assert_eq!(frame_delays(10, 25), vec![4; 10]);
    }

    #[test]
    fn gif_round_trip_keeps_frames_size_and_loop() {
        let anim = toy(13, 7, 6, 3);
        let bytes = anim.encode_gif().unwrap();
        let decoded = decode_gif_bytes(&bytes).unwrap();
        assert_eq!((decoded.width, decoded.height), (13, 7));
        assert_eq!(decoded.frames.len(), 6);
        assert_eq!(decoded.delays, anim.delays);
        assert_eq!(decoded.repeat, Repeat::Infinite);
        for (k, f) in decoded.frames.iter().enumerate() {
            let rgb: Vec<Rgb8> = f.iter().map(|p| [p[0], p[1], p[2]]).collect();
            assert_eq!(rgb, anim.frame_rgb(k), "frame {k}");
        }
    }

    #[test]
    fn unchanged_frames_still_count_and_keep_their_pixels() {
        let mut anim = toy(5, 4, 3, 2);
        anim.frames[2] = anim.frames[1].clone();
        let decoded = decode_gif_bytes(&anim.encode_gif().unwrap()).unwrap();
        assert_eq!(decoded.frames.len(), 3);
        assert_eq!(decoded.frames[2], decoded.frames[1]);
    }

    #[test]
    fn side_by_side_frames_equal_the_inputs_upscaled() {
        let (a, b) = (toy(6, 5, 4, 1), toy(6, 5, 4, 2));
        let da = decode_gif_bytes(&a.encode_gif().unwrap()).unwrap();
        let db = decode_gif_bytes(&b.encode_gif().unwrap()).unwrap();
        let gap_color = [9, 8, 7];
        let joined = side_by_side(&da, &db, 3, gap_color, 2, ("a", "b")).unwrap();
        let dj = decode_gif_bytes(&joined.encode_gif().unwrap()).unwrap();
        assert_eq!((dj.width, dj.height), ((6 * 2 + 3) * 2, 10));
        assert_eq!(dj.frames.len(), 4);
        for k in 0..4 {
            let (fa, fb) = (a.frame_rgb(k), b.frame_rgb(k));
            for y in 0..10usize {
                for x in 0..30usize {
                    let (sx, sy) = (x / 2, y / 2);
                    let expected = if sx < 6 {
                        fa[sy * 6 + sx]
                    } else if sx < 9 {
                        gap_color
                    } else {
                        fb[sy * 6 + sx - 9]
                    };
                    let p = dj.frames[k][y * 30 + x];
                    assert_eq!([p[0], p[1], p[2]], expected, "frame {k} pixel ({x}, {y})");
                }
            }
        }
    }

    #[test]
    fn side_by_side_rejects_different_lengths() {
        let da = decode_gif_bytes(&toy(4, 4, 3, 1).encode_gif().unwrap()).unwrap();
        let db = decode_gif_bytes(&toy(4, 4, 5, 1).encode_gif().unwrap()).unwrap();
        let err = side_by_side(&da, &db, 2, [0, 0, 0], 2, ("abcd", "efgh")).unwrap_err();
        assert!(err.to_string().contains("abcd") && err.to_string().contains("frame counts"));
    }
}
