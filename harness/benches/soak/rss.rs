//! The served process's resident memory, sampled from `/proc/PID/status` (`VmRSS`) while the
//! soak runs: what "memory stays flat" is judged on; and the processor time it used
//! (`/proc/PID/stat`), which tells a device that cannot keep up from a busy host.

use std::time::{Duration, Instant};

use harness::stats::slope;

/// The served process's resident set in KiB; `None` once it has ended.
pub(crate) fn rss_kib(pid: u32) -> Option<u64> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
}

/// The processor time the served process has used so far (user and system), `None` once it
/// has ended. Counted in the kernel's clock ticks, 100 a second on Linux.
pub(crate) fn cpu_time(pid: u32) -> Option<Duration> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // The command name in parentheses may hold spaces: the fields are counted after it.
    let fields: Vec<&str> = stat.rsplit_once(')')?.1.split_whitespace().collect();
    // utime and stime are fields 14 and 15, the 12th and 13th after the name and state.
    let ticks: u64 = fields.get(11)?.parse::<u64>().ok()? + fields.get(12)?.parse::<u64>().ok()?;
    Some(Duration::from_millis(ticks * 10))
}

/// Samples taken: seconds since the soak began, and KiB.
#[derive(Debug, Default)]
pub(crate) struct Samples(pub(crate) Vec<(f64, f64)>);

impl Samples {
    /// Takes one sample of `pid` at `since.elapsed()`; `false` when the process is gone.
    pub(crate) fn take(&mut self, pid: u32, since: Instant) -> bool {
        match rss_kib(pid) {
            Some(kib) => {
                self.0.push((since.elapsed().as_secs_f64(), kib as f64));
                true
            }
            None => false,
        }
    }

    /// The samples taken from `from` on (seconds since the soak began).
    pub(crate) fn after(&self, from: Duration) -> Samples {
        let from = from.as_secs_f64();
        Samples(self.0.iter().copied().filter(|s| s.0 >= from).collect())
    }

    pub(crate) fn first(&self) -> Option<f64> {
        self.0.first().map(|s| s.1)
    }

    pub(crate) fn last(&self) -> Option<f64> {
        self.0.last().map(|s| s.1)
    }

    pub(crate) fn max(&self) -> Option<f64> {
        self.0.iter().map(|s| s.1).reduce(f64::max)
    }

    /// KiB per second, least squares.
    pub(crate) fn slope(&self) -> Option<f64> {
        slope(&self.0)
    }
}
