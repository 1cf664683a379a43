//! The sample objects by name: what `experiments extract --object`, a manifest's `[[objects]]`
//! and the Python package's `rmt_terrain.sample` build.
//!
//! An object is a [`ObjectKind`] plus optional [`ObjectParams`]; [`ObjectSpec::build`] turns it
//! into a scalar field placed in the sampled box. Every kind accepts only its own parameters, so a
//! misspelt or misplaced parameter is an error instead of being silently ignored.
//!
//! | kind | code | parameters (default) |
//! |---|---|---|
//! | `sphere` | `ss` | `radius` (half the box's smallest side: inscribed), centred in the box |
//! | `asteroid` | `as` | `seed` (7), `octaves` (4), `frequency` (1.5), `amplitude` (0.25), `radius` (0.7) |
//! | `gyroid` | `gs` | `frequency` (1.0), `thickness` (0.3) |
//! | `torus` | `os` | `major` (0.6 half-side), `minor` (0.25 half-side), around the y axis |
//! | `bunny` | `bs` | `mesh` (`data/bunny.obj`), `margin` (0.05 of the box per side), `band` (2 grid spacings) |
//! | `terrain` | `ts` | Svoboda's height field: `seed` (11), `octaves` (5), `frequency` (1.0), `amplitude` (0.45), `base` (0) |
//! | `caves` | `cs` | 3D noise ground with tunnels: `seed` (5), `octaves` (4), `frequency` (1.2), `amplitude` (0.5), `base` (0), `cave_frequency` (1.5), `cave_radius` (0.18), `cave_ceiling` (0.2) |
//! | `random` | `rf` | a random field of the property tests' families in the largest cube inside the box (blobs, waves, thin shells, thin tubes; a quarter quantised): `seed` (7); for topology sweeps |
//!
//! The code is the first part of a configuration id (`ss_bu`, `as_bi`, `bs_sp`), reproducing the
//! dissertation's names for sphere, asteroid and bunny (`o` for the ring-shaped torus). Seeds not
//! given take the manifest's `seed`, else the defaults above. The terrains are placed in world
//! coordinates (ground height `base` at y = 0 by default), not fitted to the box, and leave the box
//! through its sides.
//! Relative mesh paths are looked up in the current folder, then in the folders above the
//! manifest, then in the workspace root (see [`resolve_data_path`]).
//!
//! With the `clap` feature, [`ObjectParams`] is also a `clap::Args` (`--radius 0.8`, ...).
//! The crate depends on the fields and mesh crates only (no data frames), so the Python package
//! can use it.

mod bounds;
mod data;
mod kind;
mod spec;

pub use bounds::{Bounds, Resolution};
pub use data::{resolve_data_path, workspace_root};
pub use kind::{ObjectError, ObjectKind, ObjectParams};
pub use spec::{ObjectSpec, DEFAULT_BUNNY, DEFAULT_SEED};
