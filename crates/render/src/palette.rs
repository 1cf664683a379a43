//! Up to 256 colours for GIF frames: a weighted median-cut quantiser and nearest-colour mapping.
//!
//! Median cut: start with one box holding every colour of a histogram; repeatedly take the box
//! with the largest weighted squared error, sort it along its channel of largest variance and
//! split it at the weighted median; each final box contributes its weighted mean. Boxes are
//! chosen and split in a fixed order, ties go to the earlier box, so the palette is a pure
//! function of the histogram. Dense regions of colour space (the many shades of a lit surface)
//! get many entries, which is what keeps smooth shading free of visible bands.
//!
//! Mapping is by squared distance in sRGB bytes, ties to the lower index; [`PaletteMapper`]
//! caches the answer per colour.

use crate::color::Rgb8;
use std::collections::HashMap;

/// A list of at most 256 colours.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Palette {
    colors: Vec<Rgb8>,
}

impl Palette {
    /// A palette from a list of colours; `None` if it is empty or longer than 256.
    pub fn new(colors: Vec<Rgb8>) -> Option<Self> {
        (!colors.is_empty() && colors.len() <= 256).then_some(Self { colors })
    }

    /// The colours, index order.
    pub fn colors(&self) -> &[Rgb8] {
        &self.colors
    }

    /// Index of the nearest colour (squared sRGB distance, ties to the lower index).
    pub fn nearest(&self, c: Rgb8) -> u8 {
        let mut best = (u32::MAX, 0usize);
        for (i, p) in self.colors.iter().enumerate() {
            let d: u32 = (0..3)
                .map(|k| (i32::from(c[k]) - i32::from(p[k])).pow(2) as u32)
                .sum();
            if d < best.0 {
                best = (d, i);
            }
        }
        best.1 as u8
    }

    /// A caching mapper (one per thread).
    pub fn mapper(&self) -> PaletteMapper<'_> {
        PaletteMapper {
            palette: self,
            cache: HashMap::new(),
        }
    }
}

/// [`Palette::nearest`] with a per-colour cache.
#[derive(Debug)]
pub struct PaletteMapper<'a> {
    palette: &'a Palette,
    cache: HashMap<Rgb8, u8>,
}

impl PaletteMapper<'_> {
    /// Index of the nearest palette colour.
    pub fn index(&mut self, c: Rgb8) -> u8 {
        *self
            .cache
            .entry(c)
            .or_insert_with(|| self.palette.nearest(c))
    }
}

/// Colour counts, sorted by colour.
pub fn histogram(pixels: impl IntoIterator<Item = Rgb8>) -> Vec<(Rgb8, u64)> {
    let mut counts: HashMap<Rgb8, u64> = HashMap::new();
    for p in pixels {
        *counts.entry(p).or_insert(0) += 1;
    }
    let mut hist: Vec<(Rgb8, u64)> = counts.into_iter().collect();
    hist.sort_unstable();
    hist
}

/// A box of the median cut: a range of histogram entries and its weighted squared error.
struct ColorBox {
    start: usize,
    end: usize,
    error: f64,
}

fn weighted_stats(entries: &[(Rgb8, u64)]) -> ([f64; 3], [f64; 3], f64) {
    let total: f64 = entries.iter().map(|e| e.1 as f64).sum();
    let mut mean = [0.0; 3];
    for (c, w) in entries {
        for k in 0..3 {
            mean[k] += f64::from(c[k]) * *w as f64;
        }
    }
    mean = mean.map(|m| m / total.max(1.0));
    let mut var = [0.0; 3];
    for (c, w) in entries {
        for k in 0..3 {
            var[k] += (f64::from(c[k]) - mean[k]).powi(2) * *w as f64;
        }
    }
    (mean, var, total)
}

/// Reduces a histogram (any order; weights > 0) to at most `max_colors` colours by weighted
/// median cut. Returns fewer colours when the histogram has fewer.
pub fn median_cut(histogram: &[(Rgb8, u64)], max_colors: usize) -> Vec<Rgb8> {
    let mut entries: Vec<(Rgb8, u64)> = histogram.iter().copied().filter(|e| e.1 > 0).collect();
    entries.sort_unstable();
    if entries.is_empty() || max_colors == 0 {
        return Vec::new();
    }
    let make_box = |entries: &[(Rgb8, u64)], start: usize, end: usize| {
        let (_, var, _) = weighted_stats(&entries[start..end]);
        ColorBox {
            start,
            end,
            error: var.iter().sum(),
        }
    };
    let mut boxes = vec![make_box(&entries, 0, entries.len())];
    while boxes.len() < max_colors {
        let mut pick: Option<usize> = None;
        for (i, b) in boxes.iter().enumerate() {
            if b.end - b.start >= 2 && pick.is_none_or(|p| b.error > boxes[p].error) {
                pick = Some(i);
            }
        }
        let Some(pick) = pick else { break };
        let (start, end) = (boxes[pick].start, boxes[pick].end);
        let slice = &mut entries[start..end];
        let (_, var, total) = weighted_stats(slice);
        let axis = (0..3).fold(0, |best, k| if var[k] > var[best] { k } else { best });
        slice.sort_unstable_by_key(|(c, _)| (c[axis], c[(axis + 1) % 3], c[(axis + 2) % 3]));
        let mut split = end - 1;
        let mut acc = 0.0;
        for (i, (_, w)) in slice.iter().enumerate() {
            acc += *w as f64;
            if 2.0 * acc >= total {
                split = start + i + 1;
                break;
            }
        }
        let split = split.clamp(start + 1, end - 1);
        boxes[pick] = make_box(&entries, start, split);
        boxes.push(make_box(&entries, split, end));
    }
    boxes
        .iter()
        .map(|b| {
            let (mean, _, _) = weighted_stats(&entries[b.start..b.end]);
            mean.map(|m| m.round().clamp(0.0, 255.0) as u8)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn few_colours_are_kept_exactly() {
        let hist = histogram([[1, 2, 3], [9, 9, 9], [1, 2, 3], [200, 0, 0]]);
        let mut pal = median_cut(&hist, 8);
        pal.sort_unstable();
        assert_eq!(pal, vec![[1, 2, 3], [9, 9, 9], [200, 0, 0]]);
    }

    #[test]
    fn a_grey_ramp_is_covered_evenly() {
        // 256 greys, equal weight, 16 colours: every grey within 8 levels of a palette entry.
        let hist: Vec<(Rgb8, u64)> = (0..=255u8).map(|v| ([v, v, v], 10)).collect();
        let pal = Palette::new(median_cut(&hist, 16)).unwrap();
        assert_eq!(pal.colors().len(), 16);
        for v in 0..=255u8 {
            let p = pal.colors()[pal.nearest([v, v, v]) as usize];
            assert!(
                (i32::from(p[0]) - i32::from(v)).abs() <= 8,
                "grey {v} -> {p:?}"
            );
        }
    }

    #[test]
    fn median_cut_is_deterministic_and_order_independent() {
        let mut hist: Vec<(Rgb8, u64)> = (0..2000u32)
            .map(|i| {
                (
                    [(i * 7) as u8, (i * 13) as u8, (i / 8) as u8],
                    1 + u64::from(i % 5),
                )
            })
            .collect();
        let a = median_cut(&hist, 64);
        hist.reverse();
        assert_eq!(a, median_cut(&hist, 64));
    }

    #[test]
    fn mapper_agrees_with_nearest() {
        let pal = Palette::new(vec![[0, 0, 0], [255, 255, 255], [255, 0, 0]]).unwrap();
        let mut m = pal.mapper();
        for c in [
            [10, 10, 10],
            [250, 240, 245],
            [200, 20, 30],
            [128, 128, 128],
        ] {
            assert_eq!(m.index(c), pal.nearest(c));
        }
        assert_eq!(pal.nearest([200, 20, 30]), 2);
    }
}
