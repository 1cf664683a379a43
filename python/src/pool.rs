//! Extractors kept between calls (their sample arrays, working tables and thread pools are
//! reused, as a game keeps them between frames), and the memory estimate checked before a
//! large extraction.

use std::sync::Mutex;

use pyo3::exceptions::PyMemoryError;
use pyo3::PyResult;
use rmt_extract::{samples::sampled_lattice, ExtractSettings, Extractor, Lattice};

/// Idle extractors. A call takes one (or makes one) and gives it back, so calls from several
/// Python threads at once each have their own.
static IDLE: Mutex<Vec<Extractor>> = Mutex::new(Vec::new());

/// At most this many idle extractors are kept (each holds the buffers of its last volume).
const KEEP: usize = 4;

/// An extractor for one call.
pub fn take() -> Extractor {
    IDLE.lock()
        .ok()
        .and_then(|mut idle| idle.pop())
        .unwrap_or_default()
}

/// Returns an extractor taken with [`take`].
pub fn give_back(ex: Extractor) {
    if let Ok(mut idle) = IDLE.lock() {
        if idle.len() < KEEP {
            idle.push(ex);
        }
    }
}

/// Bytes per sample slot in the size estimate: the f32 sample plus the per-point tables and
/// the mesh of a dense surface (the command line's estimate).
const BYTES_PER_SLOT: u64 = 24;

/// Refuses, with a `MemoryError`, an extraction whose estimated memory exceeds what the system
/// reports as available (Linux `MemAvailable`; no check where it is unknown).
pub fn check_memory(settings: &ExtractSettings) -> PyResult<()> {
    let [nx, ny, nz] = settings.grid.cells.map(|c| c as u64);
    let slots = match sampled_lattice(settings) {
        Lattice::Simple => (nx + 1).saturating_mul(ny + 1).saturating_mul(nz + 1),
        Lattice::BodyCentred => (nx + 2)
            .saturating_mul(ny + 2)
            .saturating_mul(nz.saturating_mul(2).saturating_add(3)),
    };
    let need = slots.saturating_mul(BYTES_PER_SLOT);
    match available_memory() {
        Some(have) if need > have => Err(PyMemoryError::new_err(format!(
            "a grid of {:?} cells (x, y, z) needs an estimated {} MiB (sample array and \
             per-point tables), more than the {} MiB of memory available",
            settings.grid.cells,
            need >> 20,
            have >> 20
        ))),
        _ => Ok(()),
    }
}

/// Memory the system reports as available, if known.
fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}
