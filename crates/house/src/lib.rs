//! The workspace's house rules, checked by its tests: inside every crate, modules import each
//! other downward only, so a reader can enter a crate at its root and never be sent back up.
//!
//! [`check_workspace`] reads every crate target of every workspace member (library, binaries,
//! tests, examples, benches) from its source files, without compiling anything:
//! - [`lex`] splits a file into the tokens the walk needs (comments and literals dropped);
//! - [`parse`] follows `mod` declarations from the target's root and records, per module, the
//!   items it defines, its `use` bindings and the paths and names its code mentions;
//! - [`graph`] resolves those to the files that define them (through re-exports and globs),
//!   builds the file-level import graph and finds its cycles (Tarjan's strongly connected
//!   components);
//! - [`workspace`] finds the members and targets and writes the report.
//!
//! `cargo test --release -p rmt-house -- --nocapture` prints the report; the test
//! `tests/modules.rs` fails listing every cycle with the imports that close it.
//!
//! What counts (details in [`graph`]):
//! - a node is a file; the test code of a file (`#[cfg(test)]` modules and items) is a node of
//!   its own, so a file's `mod tests { use super::*; }` is no cycle, and test code, which nothing
//!   imports, never closes one with the code it tests;
//! - an edge `a -> b` is code in `a` naming an item defined in `b`, through a `use`, a path
//!   (`crate::b::f`, `super::f`, `b::f`) or a name a glob brings in; re-exports are followed to
//!   the defining file; a module re-exporting its own children (`pub use io::Error` in
//!   `lib.rs`) is their facade and adds no edge, but a parent that both uses a child and is used
//!   by it (a shared type in `mod.rs` or `lib.rs`, a child's `impl Parent`) is a cycle.
//!
//! It reads syntax, not types: a name is followed as written (a method call on a value is not an
//! import), which is what a reader following `use` lines sees. Macro bodies are not read (their
//! paths resolve where they are expanded).

pub mod graph;
pub mod lex;
pub mod parse;
pub mod workspace;

pub use workspace::{check_workspace, render, workspace_root, PackageCheck};
