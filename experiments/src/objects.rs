//! The sample objects by name: what `extract --object` and a manifest's `[[objects]]` build.
//!
//! They live in [`rmt_objects`] (shared with the Python package); this module re-exports them
//! under the runner's historical path `experiments::objects` (kinds, parameters, bounds,
//! resolutions, [`ObjectSpec`] and [`resolve_data_path`]).

pub use rmt_objects::{
    resolve_data_path, workspace_root, Bounds, ObjectError, ObjectKind, ObjectParams, ObjectSpec,
    Resolution, DEFAULT_BUNNY, DEFAULT_SEED,
};
