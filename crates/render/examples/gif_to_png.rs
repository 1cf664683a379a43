//! Dumps frames of a GIF (composited, as a viewer shows them) as PNG files, for inspection.
//!
//! `cargo run --release -p rmt-render --example gif_to_png FILE.gif OUT_PREFIX [FRAME...]`
//! writes `OUT_PREFIX_<frame>.png` (default frames: 0 and the middle one).

use rmt_render::{decode_gif, Frame};
use std::error::Error;
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn Error>> {
    let mut args = std::env::args().skip(1);
    let (Some(gif), Some(prefix)) = (args.next(), args.next()) else {
        return Err("usage: gif_to_png FILE.gif OUT_PREFIX [FRAME...]".into());
    };
    let decoded = decode_gif(&PathBuf::from(&gif))?;
    let mut frames: Vec<usize> = args.map(|a| a.parse()).collect::<Result<_, _>>()?;
    if frames.is_empty() {
        frames = vec![0, decoded.frames.len() / 2];
    }
    println!(
        "{gif}: {}x{}, {} frames, delays {:?}.., repeat {:?}",
        decoded.width,
        decoded.height,
        decoded.frames.len(),
        &decoded.delays[..decoded.delays.len().min(6)],
        decoded.repeat
    );
    for k in frames {
        let canvas = decoded
            .frames
            .get(k)
            .ok_or_else(|| format!("no frame {k}"))?;
        let frame = Frame {
            width: u32::from(decoded.width),
            height: u32::from(decoded.height),
            pixels: canvas.iter().map(|p| [p[0], p[1], p[2]]).collect(),
            coverage: Vec::new(),
        };
        let out = PathBuf::from(format!("{prefix}_{k:03}.png"));
        frame.save_png(&out)?;
        println!("wrote {}", out.display());
    }
    Ok(())
}
