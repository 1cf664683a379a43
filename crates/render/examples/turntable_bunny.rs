//! Renders the bunny (data/bunny.obj, subdivided to ~59k triangles) as a default turntable,
//! prints the time and file size, and dumps a few frames as PNG for inspection.
//!
//! `cargo run --release -p rmt-render --example turntable_bunny [OUT_DIR]`

use rmt_mesh::Mesh;
use rmt_render::shade::Shading;
use rmt_render::wireframe::Wireframe;
use rmt_render::{render_frame, Renderer, TurntableSettings};
use std::collections::HashMap;
use std::error::Error;
use std::path::{Path, PathBuf};
use std::time::Instant;

fn load_obj(path: &Path) -> Result<Mesh, Box<dyn Error>> {
    let (models, _) = tobj::load_obj(
        path,
        &tobj::LoadOptions {
            triangulate: true,
            single_index: true,
            ..Default::default()
        },
    )?;
    let model = models.first().ok_or("no model in the OBJ file")?;
    let positions = model
        .mesh
        .positions
        .chunks_exact(3)
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    Ok(Mesh::from_triangles(positions, model.mesh.indices.clone()))
}

/// Splits every triangle into four at its edge midpoints (shared midpoints, so the mesh stays
/// closed).
fn subdivide(mesh: &Mesh) -> Mesh {
    let mut positions = mesh.positions.clone();
    let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
    let mut mid = |a: u32, b: u32, positions: &mut Vec<[f32; 3]>| {
        *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
            let (p, q) = (positions[a as usize], positions[b as usize]);
            positions.push([
                (p[0] + q[0]) / 2.0,
                (p[1] + q[1]) / 2.0,
                (p[2] + q[2]) / 2.0,
            ]);
            positions.len() as u32 - 1
        })
    };
    let mut indices = Vec::with_capacity(mesh.indices.len() * 4);
    for [a, b, c] in mesh.triangles() {
        let (ab, bc, ca) = (
            mid(a, b, &mut positions),
            mid(b, c, &mut positions),
            mid(c, a, &mut positions),
        );
        indices.extend([a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca]);
    }
    Mesh::from_triangles(positions, indices)
}

/// Process CPU time (user + system) in seconds from /proc/self/stat (Linux, USER_HZ = 100), so
/// the figure means something on a loaded machine; `None` elsewhere.
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
    let rest = stat.rsplit_once(')')?.1;
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = fields.get(11)?.parse::<f64>().ok()? + fields.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

fn main() -> Result<(), Box<dyn Error>> {
    let out = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "/tmp/render-bunny".into()),
    );
    std::fs::create_dir_all(&out)?;
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut mesh = subdivide(&subdivide(&load_obj(&root.join("data/bunny.obj"))?));
    mesh.compute_area_weighted_normals();
    let volume: f64 = mesh
        .triangles()
        .map(|t| {
            let [a, b, c] = t.map(|i| glam::Vec3::from(mesh.positions[i as usize]).as_dvec3());
            a.dot(b.cross(c)) / 6.0
        })
        .sum();
    println!(
        "bunny: {} vertices, {} triangles, signed volume {volume:.1}",
        mesh.vertex_count(),
        mesh.triangle_count()
    );

    let settings = TurntableSettings::default();
    let t0 = Instant::now();
    let renderer = Renderer::new(settings.clone())?;
    let t_palette = t0.elapsed();
    let t1 = Instant::now();
    let cpu0 = cpu_seconds();
    let animation = renderer.render(&mesh)?;
    let t_render = t1.elapsed();
    let cpu_render = cpu_seconds().zip(cpu0).map(|(b, a)| b - a);
    let t2 = Instant::now();
    let gif = out.join("bunny.gif");
    animation.write_gif(&gif)?;
    let t_encode = t2.elapsed();
    println!(
        "default turntable {} frames {}x{} ss{}: palette {:.0} ms, render {:.0} ms wall ({} CPU), \
         GIF encode {:.0} ms, {} bytes",
        settings.frames,
        settings.width,
        settings.height,
        settings.supersampling,
        t_palette.as_secs_f64() * 1e3,
        t_render.as_secs_f64() * 1e3,
        cpu_render.map_or("n/a".to_string(), |c| format!("{:.0} ms", c * 1e3)),
        t_encode.as_secs_f64() * 1e3,
        std::fs::metadata(&gif)?.len()
    );
    for k in [0usize, 18, 36, 54] {
        let frame = rmt_render::Frame {
            width: settings.width,
            height: settings.height,
            pixels: animation.frame_rgb(k),
            coverage: Vec::new(),
        };
        frame.save_png(&out.join(format!("bunny_gif_frame{k:02}.png")))?;
    }
    // Unquantised frame 0 against the GIF's frame 0: error statistics and a zoomed crop of both.
    let exact = render_frame(&mesh, &settings, 0.0)?;
    exact.save_png(&out.join("bunny_exact_frame00.png"))?;
    let quantised = animation.frame_rgb(0);
    let errors: Vec<u8> = exact
        .pixels
        .iter()
        .zip(&quantised)
        .map(|(a, b)| (0..3).map(|k| a[k].abs_diff(b[k])).max().unwrap_or(0))
        .collect();
    let mean = errors.iter().map(|&e| f64::from(e)).sum::<f64>() / errors.len() as f64;
    println!(
        "palette error on frame 0: mean {mean:.2}, max {} (channel levels)",
        errors.iter().max().unwrap_or(&0)
    );
    let (x0, y0, size, zoom) = (70u32, 60u32, 100u32, 3u32);
    let mut zoomed = Vec::new();
    for y in 0..size * zoom {
        for half in [&exact.pixels, &quantised] {
            for x in 0..size * zoom {
                zoomed.push(half[((y0 + y / zoom) * settings.width + x0 + x / zoom) as usize]);
            }
        }
    }
    let zoom_frame = rmt_render::Frame {
        width: 2 * size * zoom,
        height: size * zoom,
        pixels: zoomed,
        coverage: Vec::new(),
    };
    zoom_frame.save_png(&out.join("bunny_zoom_exact_vs_gif.png"))?;
    // A flat-shaded wireframe variant of the coarse bunny.
    let coarse = load_obj(&root.join("data/bunny.obj"))?;
    let wire = TurntableSettings {
        shading: Shading::Flat,
        wireframe: Some(Wireframe::default()),
        width: 384,
        height: 384,
        ..settings.clone()
    };
    render_frame(&coarse, &wire, 60.0)?.save_png(&out.join("bunny_coarse_flat_wire.png"))?;
    let t3 = Instant::now();
    let wire_gif = out.join("bunny_coarse_flat_wire.gif");
    rmt_render::render_turntable_gif(&coarse, &wire, &wire_gif)?;
    println!(
        "coarse bunny flat + wireframe {}x{}: {:.0} ms, {} bytes",
        wire.width,
        wire.height,
        t3.elapsed().as_secs_f64() * 1e3,
        std::fs::metadata(&wire_gif)?.len()
    );
    Ok(())
}
