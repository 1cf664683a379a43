//! Extractors kept between calls (their sample arrays, working tables and thread pools are
//! reused, as a game keeps them between frames), and the memory estimate checked before a
//! large extraction.

use std::sync::{Arc, Mutex, OnceLock};

use pyo3::exceptions::PyMemoryError;
use pyo3::PyResult;
use rmt_extract::{samples::sampled_lattice, ExtractSettings, Extractor, Lattice};

/// Idle extractors. A call takes one (or makes one) and gives it back, so calls from several
/// Python threads at once each have their own.
static IDLE: Mutex<Vec<Extractor>> = Mutex::new(Vec::new());

/// At most this many idle extractors are kept (each holds the buffers of its last volume).
const KEEP: usize = 4;

/// Worker pools by thread count, shared by the extractors (given with `set_pool`) and by the
/// input copy, so both run on the same warm workers.
static POOLS: Mutex<Vec<(usize, Arc<rayon::ThreadPool>)>> = Mutex::new(Vec::new());

/// The pool of `threads` workers (built once).
pub fn workers(threads: usize) -> Result<Arc<rayon::ThreadPool>, crate::errors::Error> {
    let mut pools = POOLS
        .lock()
        .map_err(|_| crate::errors::Error::Library("worker pools poisoned".into()))?;
    if let Some((_, p)) = pools.iter().find(|(n, _)| *n == threads) {
        return Ok(p.clone());
    }
    let pool =
        rmt_extract::thread_pool(threads, rmt_extract::ThreadPlacement::Os).map_err(|e| {
            crate::errors::Error::Library(format!("could not start {threads} worker threads: {e}"))
        })?;
    let pool = Arc::new(pool);
    pools.push((threads, pool.clone()));
    Ok(pool)
}

/// The machine's cores (asked once: the answer reads cgroup files).
pub fn default_threads() -> usize {
    static CORES: OnceLock<usize> = OnceLock::new();
    *CORES.get_or_init(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
}

/// An extractor for one call.
pub fn take() -> Extractor {
    IDLE.lock()
        .ok()
        .and_then(|mut idle| idle.pop())
        .unwrap_or_default()
}

/// Extractors whose sample array is larger than this are dropped after their call instead of
/// kept (16 MiB: about 160^3 points): a notebook that meshed one large volume should get its
/// memory back, while repeated calls on smaller volumes reuse the buffers.
const KEEP_BYTES: usize = 16 << 20;

/// Returns an extractor taken with [`take`].
pub fn give_back(ex: Extractor) {
    if ex.samples().bytes() > KEEP_BYTES {
        return;
    }
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
