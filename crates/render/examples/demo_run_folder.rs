//! Writes a stand-in run folder with the paper's 18 configurations, for trying
//! `experiments render` and `experiments questionnaire` without running the extractor: spheres,
//! lumpy "asteroids" and the bunny, tessellated more or less finely per configuration.
//!
//! `cargo run --release -p rmt-render --example demo_run_folder [RUN_DIR]`

use rmt_mesh::Mesh;
use rmt_render::questionnaire::Manifest;
use rmt_render::shapes::uv_sphere;
use std::error::Error;
use std::path::{Path, PathBuf};

fn lumpy(mut mesh: Mesh) -> Mesh {
    for p in &mut mesh.positions {
        let [x, y, z] = *p;
        let bump =
            1.0 + 0.18 * (3.0 * x + 1.0).sin() * (2.0 * y).cos() + 0.1 * (5.0 * z + 2.0 * x).sin();
        *p = [x * bump, y * bump * 0.8, z * bump];
    }
    mesh.normals.clear();
    mesh
}

fn main() -> Result<(), Box<dyn Error>> {
    let run = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "/tmp/render-demo-run".into()),
    );
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    std::fs::create_dir_all(run.join("meshes"))?;
    std::fs::copy(
        root.join("data/questionnaire/configurations.csv"),
        run.join("configurations.csv"),
    )?;
    let manifest = Manifest::read(&run.join("configurations.csv"))?;
    let bunny = rmt_mesh::io::read_obj(root.join("data/bunny.obj"))?;
    for c in &manifest.configurations {
        let (object, lattice, clustering) = (&c.values[0], &c.values[1], &c.values[2]);
        let detail = match (lattice.as_str(), clustering.as_str()) {
            (_, "none") => 48,
            (_, "integrated") => 24,
            _ => 32,
        } + if lattice == "bcdl" { 8 } else { 0 };
        let mut mesh = match object.as_str() {
            "sphere" => uv_sphere(1.0, detail, detail / 2),
            "asteroid" => lumpy(uv_sphere(1.0, detail, detail / 2)),
            _ => bunny.clone(),
        };
        mesh.normals.clear();
        rmt_mesh::io::save_ply(
            run.join("meshes").join(format!("{}.ply", c.id)),
            &mesh,
            true,
        )?;
    }
    println!(
        "wrote {} meshes to {}",
        manifest.configurations.len(),
        run.join("meshes").display()
    );
    Ok(())
}
