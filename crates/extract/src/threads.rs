//! The worker threads of an extraction: how a pool is built, and where its workers run.
//!
//! [`ThreadPlacement::Os`] (the default) leaves the placement of the workers to the operating
//! system. [`ThreadPlacement::Pinned`] binds worker `i` of a pool to the `i`-th CPU that the
//! building thread may run on (wrapping when the pool has more workers than CPUs), on Linux; on
//! other systems it is the same as `Os`.
//!
//! Why pinning exists: on the 2-vCPU Firecracker VMs this project is measured on (Linux 6.18),
//! a pool whose workers had slept for 30 ms or more ran its next parallel job on one CPU: the
//! woken worker evidently queued on the CPU of the worker that woke it, and the two shared it
//! while the other CPU stayed idle (binding each worker to its own CPU removes the effect, which
//! is what the placement, not the work, would predict). A job of 10 ms of work split into 64
//! parts took 10.0 ms on 2 threads after 30 or 100 ms of idleness (5.1-5.4 ms after 0-10 ms),
//! and 5.2-5.6 ms in every case with pinned workers. Extraction pools sit idle between calls whenever the caller does something
//! else (a game between strokes, the benchmark between methods), so this decides what a second
//! thread gains. Pinning is an opt-in: a process that runs several pinned pools at once (tests
//! in parallel, say) would crowd them onto the same CPUs.
//!
//! ```text
//!   Os:      wake-up ──> worker 2 queued behind worker 1 on CPU 0      CPU 1 idle
//!   Pinned:  wake-up ──> worker 2 runs on CPU 1 (its only CPU)         both busy
//! ```

/// Where the workers of an extractor's thread pools run (see the module doc).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ThreadPlacement {
    /// The operating system places the workers (the default).
    #[default]
    Os,
    /// Worker `i` is bound to the `i`-th CPU the building thread may run on (Linux; elsewhere
    /// the same as `Os`). Binding is best effort: a worker that cannot be bound runs unbound.
    Pinned,
}

impl ThreadPlacement {
    /// Both placements, in order.
    pub const ALL: [ThreadPlacement; 2] = [ThreadPlacement::Os, ThreadPlacement::Pinned];

    /// The name used on command lines and in reports: `os` or `pinned`.
    pub fn name(self) -> &'static str {
        match self {
            ThreadPlacement::Os => "os",
            ThreadPlacement::Pinned => "pinned",
        }
    }

    /// The placement called `name` ([`ThreadPlacement::name`]), or `None`.
    ///
    /// ```
    /// use rmt_extract::ThreadPlacement;
    /// assert_eq!(ThreadPlacement::parse("pinned"), Some(ThreadPlacement::Pinned));
    /// assert_eq!(ThreadPlacement::parse("pin"), None);
    /// ```
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|p| p.name() == name)
    }
}

/// A rayon pool of `threads` workers placed as `placement` says.
///
/// ```
/// use rmt_extract::{thread_pool, ThreadPlacement};
/// let pool = thread_pool(2, ThreadPlacement::Pinned).unwrap();
/// assert_eq!(pool.current_num_threads(), 2);
/// assert_eq!(pool.install(|| 6 * 7), 42);
/// ```
pub fn thread_pool(
    threads: usize,
    placement: ThreadPlacement,
) -> Result<rayon::ThreadPool, rayon::ThreadPoolBuildError> {
    let builder = rayon::ThreadPoolBuilder::new().num_threads(threads);
    match placement {
        ThreadPlacement::Os => builder.build(),
        ThreadPlacement::Pinned => {
            // The CPUs are read once, on the building thread (workers inherit its mask).
            let cpus = allowed_cpus();
            builder
                .start_handler(move |i| {
                    if !cpus.is_empty() {
                        pin_current_thread(cpus[i % cpus.len()]);
                    }
                })
                .build()
        }
    }
}

/// The CPUs the calling thread may run on, in increasing order (empty where unknown).
pub(crate) fn allowed_cpus() -> Vec<usize> {
    #[cfg(target_os = "linux")]
    {
        // SAFETY: `cpu_set_t` is plain data (all-zero is the empty set), and the size passed
        // is the size of the set the kernel writes into.
        unsafe {
            let mut set: libc::cpu_set_t = std::mem::zeroed();
            if libc::sched_getaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &mut set) != 0 {
                return Vec::new();
            }
            (0..libc::CPU_SETSIZE as usize)
                .filter(|&c| libc::CPU_ISSET(c, &set))
                .collect()
        }
    }
    #[cfg(not(target_os = "linux"))]
    {
        Vec::new()
    }
}

/// Binds the calling thread to `cpu`; returns whether the system accepted it.
fn pin_current_thread(cpu: usize) -> bool {
    #[cfg(target_os = "linux")]
    {
        if cpu >= libc::CPU_SETSIZE as usize {
            return false;
        }
        // SAFETY: as in `allowed_cpus`; `cpu` is below `CPU_SETSIZE`.
        unsafe {
            let mut set: libc::cpu_set_t = std::mem::zeroed();
            libc::CPU_SET(cpu, &mut set);
            libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &set) == 0
        }
    }
    #[cfg(not(target_os = "linux"))]
    {
        let _ = cpu;
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What each worker of `pool` may run on.
    fn worker_cpus(pool: &rayon::ThreadPool) -> Vec<Vec<usize>> {
        pool.broadcast(|_| allowed_cpus())
    }

    #[test]
    #[cfg(target_os = "linux")]
    fn pinned_workers_each_get_their_own_cpu_in_order() {
        let cpus = allowed_cpus();
        assert!(!cpus.is_empty(), "the test process may run somewhere");
        for threads in [1, 2, 3] {
            let pool = thread_pool(threads, ThreadPlacement::Pinned).unwrap();
            let seen = worker_cpus(&pool);
            assert_eq!(seen.len(), threads);
            for (i, mask) in seen.iter().enumerate() {
                assert_eq!(
                    mask,
                    &vec![cpus[i % cpus.len()]],
                    "worker {i} of {threads}: bound to one CPU, the {i}-th allowed one"
                );
            }
        }
    }

    #[test]
    fn os_placement_leaves_the_workers_unbound() {
        let cpus = allowed_cpus();
        let pool = thread_pool(2, ThreadPlacement::Os).unwrap();
        for mask in worker_cpus(&pool) {
            assert_eq!(mask, cpus, "a worker inherits the process's CPUs");
        }
    }

    #[test]
    fn binding_to_a_cpu_outside_the_set_is_refused_not_fatal() {
        // On a thread of its own, so the test thread keeps its CPUs.
        let ok = std::thread::spawn(|| pin_current_thread(usize::MAX))
            .join()
            .unwrap();
        assert!(!ok);
    }

    #[test]
    #[cfg(target_os = "linux")]
    fn a_new_placement_rebuilds_the_extractors_own_pools_and_keeps_given_ones() {
        let mut ex = crate::Extractor::new();
        let own = ex.pool(1).unwrap();
        let given = std::sync::Arc::new(thread_pool(2, ThreadPlacement::Os).unwrap());
        ex.set_pool(given.clone());
        ex.set_thread_placement(ThreadPlacement::Pinned);
        assert!(std::sync::Arc::ptr_eq(&ex.pool(2).unwrap(), &given));
        let rebuilt = ex.pool(1).unwrap();
        assert!(!std::sync::Arc::ptr_eq(&rebuilt, &own));
        let cpus = allowed_cpus();
        assert_eq!(worker_cpus(&rebuilt), vec![vec![cpus[0]]]);
        // The same placement again changes nothing.
        ex.set_thread_placement(ThreadPlacement::Pinned);
        assert!(std::sync::Arc::ptr_eq(&ex.pool(1).unwrap(), &rebuilt));
    }
}
