//! What the level-of-detail tests share: case counts from `RMT_CASES` and the proptest set-up.

#![allow(dead_code)]

use glam::Vec3;
use proptest::test_runner::{Config as ProptestConfig, FileFailurePersistence};
use rmt_terrain::lod::{LodFrame, LodGeometry};

/// `RMT_CASES`, or `default` when it is unset or malformed.
pub fn cases(default: u32) -> u32 {
    std::env::var("RMT_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

/// `cases(64)` cases, failures kept beside the test source.
pub fn config() -> ProptestConfig {
    ProptestConfig {
        cases: cases(64),
        failure_persistence: Some(Box::new(FileFailurePersistence::WithSource("regressions"))),
        ..ProptestConfig::default()
    }
}

/// The test worlds: `[-1, 1]` along x and z (y: `[-1, 0]` for the first), where the random
/// fields live.
pub fn geometry(which: u8) -> (LodGeometry, LodFrame) {
    let (g, h) = match which {
        0 => (LodGeometry::new(2, 2, [2, 1, 2]).unwrap(), 0.125),
        1 => (LodGeometry::new(1, 2, [2, 2, 2]).unwrap(), 0.25),
        2 => (LodGeometry::new(2, 4, [1, 1, 1]).unwrap(), 0.125),
        // Larger: room for chunks far from a level change (x, z in [-1, 1], y in [-1, -2/3]).
        3 => (LodGeometry::new(2, 4, [3, 1, 3]).unwrap(), 2.0 / 48.0),
        4 => (LodGeometry::new(2, 4, [4, 1, 4]).unwrap(), 2.0 / 64.0),
        // Chunks of 8^3 cells: room for clustering inside them (y in [-1, 0]).
        _ => (LodGeometry::new(2, 8, [2, 1, 2]).unwrap(), 2.0 / 64.0),
    };
    (
        g,
        LodFrame {
            origin: Vec3::splat(-1.0),
            h,
        },
    )
}
