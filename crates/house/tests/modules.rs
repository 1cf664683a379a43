//! The house rule over the whole workspace: no two modules of a crate import each other, directly
//! or around a circle. `cargo test --release -p rmt-house -- --nocapture` prints the report.

use std::path::Path;

#[test]
fn no_crate_has_an_import_cycle() {
    let root = rmt_house::workspace_root(Path::new(env!("CARGO_MANIFEST_DIR")))
        .expect("the workspace root");
    let packages = rmt_house::check_workspace(&root).expect("read the workspace's sources");
    let report = rmt_house::render(&packages);
    println!("{report}");
    for expected in ["rmt-extract", "experiments", "rmt-house"] {
        let package = packages.iter().find(|p| p.name == expected);
        assert!(
            package.is_some_and(|p| p.targets.iter().any(|t| t.graph.nodes.len() > 1)),
            "{expected} not read:\n{report}"
        );
    }
    // A module file the walk could not find would be a module the check never saw.
    let unread: Vec<&String> = packages
        .iter()
        .flat_map(|p| &p.targets)
        .flat_map(|t| &t.problems)
        .collect();
    assert!(unread.is_empty(), "module files not found: {unread:?}");
    let cycles: usize = packages
        .iter()
        .map(rmt_house::PackageCheck::cycle_count)
        .sum();
    assert_eq!(cycles, 0, "modules import each other in a cycle:\n{report}");
}
