//! Where and how a run was made: tool version and git commit, build profile, CPU model, core
//! count, OS, date. Recorded in `run.json` once per session (a resumed run may continue on
//! another machine, and its timings should say so).

use serde::{Deserialize, Serialize};
use std::path::Path;
use std::process::Command;

/// The machine, build and time of one run session.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    /// `experiments`.
    pub tool: String,
    /// The package version.
    pub version: String,
    /// The git commit of the source tree the tool was built from, if git could tell.
    pub git_commit: Option<String>,
    /// Whether that tree had uncommitted changes to tracked files.
    pub git_dirty: Option<bool>,
    /// `release` or `debug` (debug timings are not comparable).
    pub build_profile: String,
    /// CPU model name (`/proc/cpuinfo`), if known.
    pub cpu_model: Option<String>,
    /// Logical CPUs this process may use.
    pub cores: usize,
    /// Operating system and architecture (`linux x86_64`).
    pub os: String,
    /// Distribution name (`/etc/os-release`), if known.
    pub os_release: Option<String>,
    /// Kernel version, if known.
    pub kernel: Option<String>,
    /// Start of the session, UTC, ISO 8601.
    pub date: String,
    /// The machine's host name, if known (tells the shards of a cluster run apart).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hostname: Option<String>,
    /// The Slurm job this session ran in (`job 123_4 on node n01`), when run by Slurm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slurm: Option<String>,
}

impl Provenance {
    /// Collects the provenance of this process now.
    pub fn collect() -> Self {
        let source = Path::new(env!("CARGO_MANIFEST_DIR"));
        Self {
            tool: env!("CARGO_PKG_NAME").to_string(),
            version: env!("CARGO_PKG_VERSION").to_string(),
            git_commit: git(source, &["rev-parse", "HEAD"]),
            git_dirty: git(source, &["status", "--porcelain", "--untracked-files=no"])
                .map(|s| !s.is_empty()),
            build_profile: if cfg!(debug_assertions) {
                "debug"
            } else {
                "release"
            }
            .to_string(),
            cpu_model: cpu_model(),
            cores: std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1),
            os: format!("{} {}", std::env::consts::OS, std::env::consts::ARCH),
            os_release: os_release(),
            kernel: std::fs::read_to_string("/proc/sys/kernel/osrelease")
                .ok()
                .map(|s| s.trim().to_string()),
            date: utc_now_iso(),
            hostname: std::fs::read_to_string("/proc/sys/kernel/hostname")
                .ok()
                .map(|s| s.trim().to_string())
                .filter(|s| !s.is_empty()),
            slurm: slurm_job(),
        }
    }
}

/// `job <id> on node <name>` from Slurm's environment (array tasks as `<array>_<task>`).
fn slurm_job() -> Option<String> {
    let var = |k: &str| std::env::var(k).ok().filter(|v| !v.is_empty());
    let job = match (var("SLURM_ARRAY_JOB_ID"), var("SLURM_ARRAY_TASK_ID")) {
        (Some(a), Some(t)) => format!("{a}_{t}"),
        _ => var("SLURM_JOB_ID")?,
    };
    let node = var("SLURMD_NODENAME").unwrap_or_else(|| "?".into());
    Some(format!("job {job} on node {node}"))
}

/// Output of `git -C dir args`, trimmed, when git runs and succeeds.
fn git(dir: &Path, args: &[&str]) -> Option<String> {
    let out = Command::new("git")
        .arg("-C")
        .arg(dir)
        .args(args)
        .output()
        .ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

fn cpu_model() -> Option<String> {
    let text = std::fs::read_to_string("/proc/cpuinfo").ok()?;
    text.lines()
        .find(|l| {
            l.starts_with("model name") || l.starts_with("Model") || l.starts_with("cpu model")
        })
        .and_then(|l| l.split_once(':'))
        .map(|(_, v)| v.trim().to_string())
}

fn os_release() -> Option<String> {
    let text = std::fs::read_to_string("/etc/os-release").ok()?;
    let line = text.lines().find(|l| l.starts_with("PRETTY_NAME="))?;
    Some(line["PRETTY_NAME=".len()..].trim_matches('"').to_string())
}

/// Seconds since the Unix epoch.
pub fn unix_now() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0)
}

/// Civil date (year, month, day) of a day count since 1970-01-01 (Howard Hinnant's algorithm).
fn civil_from_days(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    (yoe + era * 400 + i64::from(m <= 2), m, d)
}

/// `(date, time)` parts of a Unix time, UTC.
fn split(secs: u64) -> ((i64, u32, u32), (u64, u64, u64)) {
    let days = (secs / 86_400) as i64;
    let rest = secs % 86_400;
    (
        civil_from_days(days),
        (rest / 3600, rest % 3600 / 60, rest % 60),
    )
}

/// `2026-03-01T12:34:56Z` for a Unix time.
pub fn iso_utc(secs: u64) -> String {
    let ((y, mo, d), (h, mi, s)) = split(secs);
    format!("{y:04}-{mo:02}-{d:02}T{h:02}:{mi:02}:{s:02}Z")
}

/// The current time as [`iso_utc`].
pub fn utc_now_iso() -> String {
    iso_utc(unix_now())
}

/// `20260301-123456` (UTC), for folder names.
pub fn stamp(secs: u64) -> String {
    let ((y, mo, d), (h, mi, s)) = split(secs);
    format!("{y:04}{mo:02}{d:02}-{h:02}{mi:02}{s:02}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dates_are_converted_to_the_civil_calendar() {
        assert_eq!(iso_utc(0), "1970-01-01T00:00:00Z");
        assert_eq!(iso_utc(951_782_400), "2000-02-29T00:00:00Z");
        assert_eq!(iso_utc(1_709_251_199), "2024-02-29T23:59:59Z");
        assert_eq!(stamp(1_700_000_000), "20231114-221320");
    }

    #[test]
    fn collect_reports_this_build() {
        let p = Provenance::collect();
        assert_eq!(p.tool, "experiments");
        assert!(p.cores >= 1);
        assert_eq!(
            p.build_profile,
            if cfg!(debug_assertions) {
                "debug"
            } else {
                "release"
            }
        );
        assert!(p.date.ends_with('Z'));
    }
}
