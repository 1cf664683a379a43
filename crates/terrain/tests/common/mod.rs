//! What the level-of-detail tests share: case counts from `RMT_CASES` and the proptest set-up.

#![allow(dead_code)]

use proptest::test_runner::{Config as ProptestConfig, FileFailurePersistence};

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
