//! What the EtherCAT speed bench (`harness/benches/ecat/`, `cargo bench -p harness --bench
//! ecat`) needs of the library, and nothing of the bench itself: the harness's own master (the
//! one `harness run --dut ecat://IFACE` drives) on a network interface, doing frame round
//! trips, CoE SDO uploads and the 1 ms process data cycle. The bench's network namespace,
//! served slave, pysoem and figures are in the bench target; its statistics in
//! [`crate::stats`].
//!
//! Each function opens the interface, scans the segment (station address 1001h for the first
//! slave) and brings it as far as the figure needs, warms up, then measures; the master records
//! its exchanges as in a suite run and the transcript is taken after each operation, as the
//! runner takes it after each step.

use std::time::{Duration, Instant};

use proto::ecat::register::AL_STATUS;
use proto::nord::nmt::EcState;

use super::master::{Master, MasterConfig, NetSegment};
use crate::stats::Rate;

/// Configured station address the master gives the first slave (the bench's only one).
pub const STATION: u16 = 0x1001;

/// Operations each figure makes before it is timed.
const WARM_UP: u32 = 100;

/// The master on `iface`, scanned and brought to `state`.
fn master(iface: &str, state: EcState) -> Result<Master<NetSegment>, String> {
    let segment = NetSegment::open(iface).map_err(|e| e.to_string())?;
    let mut m = Master::new(segment, MasterConfig::default());
    m.bring_up(state)
        .map_err(|e| format!("bring-up to {state:?}: {e}"))?;
    m.take_exchanges();
    if m.slave(STATION).is_none() {
        return Err(format!("no slave at station {STATION:04X}h after the scan"));
    }
    Ok(m)
}

/// `one` up to `count` times within `limit` after [`WARM_UP`] untimed ones; the first error
/// ends it.
fn timed(
    m: &mut Master<NetSegment>,
    count: u32,
    limit: Duration,
    mut one: impl FnMut(&mut Master<NetSegment>) -> Result<(), String>,
) -> Result<Rate, String> {
    for _ in 0..WARM_UP {
        one(m)?;
    }
    let start = Instant::now();
    let mut n = 0u64;
    while n < u64::from(count) && start.elapsed() < limit {
        one(m)?;
        n += 1;
    }
    Ok(Rate {
        count: n,
        secs: start.elapsed().as_secs_f64(),
    })
}

/// Frame round trips of the harness master on `iface`: one frame each, an FPRD of the first
/// slave's AL status register (0130h, 2 bytes, working counter 1), in Pre-Operational; up to
/// `count` of them within `limit`.
pub fn round_trips(iface: &str, count: u32, limit: Duration) -> Result<Rate, String> {
    let mut m = master(iface, EcState::PreOperational)?;
    timed(&mut m, count, limit, |m| {
        m.read_register(STATION, AL_STATUS, 2)
            .map_err(|e| format!("FPRD {STATION:04X}h:{AL_STATUS:04X}h: {e}"))?;
        m.take_exchanges();
        Ok(())
    })
}

/// CoE SDO uploads of `index`:`sub` (expedited, not complete access) from the first slave by
/// the harness master on `iface` in Pre-Operational, one after the other: up to `count` within
/// `limit`. An abort or any other error ends the figure with that error.
pub fn sdo_uploads(
    iface: &str,
    index: u16,
    sub: u8,
    count: u32,
    limit: Duration,
) -> Result<Rate, String> {
    let mut m = master(iface, EcState::PreOperational)?;
    timed(&mut m, count, limit, |m| {
        m.sdo_upload(STATION, index, sub, false)
            .map_err(|e| format!("SDO upload {index:04X}h:{sub:02X}h: {e}"))?;
        m.take_exchanges();
        Ok(())
    })
}

/// What [`pdo_cycles`] saw.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Cycles {
    /// (cycle number, kernel receive stamp of the frame that came back) of every cycle whose
    /// frame came back with a stamp, in order: for [`crate::stats::jitter`] against the cycle
    /// time. The stamps are the real-time clock's (compare them with each other only).
    pub arrivals: Vec<(u32, Duration)>,
    /// Cycles run.
    pub cycles: u32,
    /// Cycles whose frame did not come back (timeout, link error).
    pub lost: u64,
    /// Cycles whose frame came back without a receive stamp.
    pub unstamped: u64,
    /// Cycles whose working counter was not the expected one (3: outputs and inputs).
    pub wkc_errors: u64,
    /// How late each cycle's frame was sent after it was due (the master's wake-up), in
    /// cycle order.
    pub late: Vec<Duration>,
    /// Send to return of each cycle whose frame came back, on the master's clock (the wire
    /// and the slave), in cycle order.
    pub round_trips: Vec<Duration>,
}

/// The process data cycle of the harness master on `iface` in Operational for `duration`: one
/// LRW of the whole image every `cycle`, each due a cycle after the one before (a fixed
/// schedule from the first, as `run_cycles` keeps it), with the kernel's receive stamp of each
/// returning frame.
pub fn pdo_cycles(iface: &str, cycle: Duration, duration: Duration) -> Result<Cycles, String> {
    let mut m = master(iface, EcState::Operational)?;
    // From here on the bench runs the cycle itself, on a fixed schedule.
    m.stop_cycling();
    m.set_recording(false);
    let before = m.cyclic_stats();
    let n = u32::try_from(duration.as_nanos() / cycle.as_nanos().max(1)).unwrap_or(u32::MAX);
    let mut out = Cycles {
        arrivals: Vec::with_capacity(n as usize),
        cycles: 0,
        lost: 0,
        unstamped: 0,
        wkc_errors: 0,
        late: Vec::with_capacity(n as usize),
        round_trips: Vec::with_capacity(n as usize),
    };
    let mut due = m.now() + cycle;
    for i in 0..n {
        m.idle_until(due);
        let sent = m.now();
        out.late.push(sent.saturating_sub(due));
        let stamp_before = m.last_receive_stamp();
        let lost_before = m.cyclic_stats().lost;
        // A working counter error still brought the frame back: counted below.
        let result = m.cycle();
        out.cycles += 1;
        if m.cyclic_stats().lost > lost_before {
            out.lost += 1;
            // A link that fails for good would fail every cycle: give up on it.
            if out.lost > u64::from(n / 10).max(100) {
                let e = result.err().map(|e| e.to_string()).unwrap_or_default();
                return Err(format!("{} cycles lost, the last: {e}", out.lost));
            }
        } else {
            out.round_trips.push(m.now().saturating_sub(sent));
            match m.last_receive_stamp() {
                Some(t) if Some(t) != stamp_before => out.arrivals.push((i, t)),
                _ => out.unstamped += 1,
            }
        }
        due += cycle;
    }
    out.wkc_errors = m.cyclic_stats().wkc_errors - before.wkc_errors;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_unknown_interface_is_an_error_naming_it() {
        let short = Duration::from_millis(10);
        for e in [
            round_trips("no-such-if0", 1, short).unwrap_err(),
            sdo_uploads("no-such-if0", 0x1018, 1, 1, short).unwrap_err(),
            pdo_cycles("no-such-if0", short, short).unwrap_err(),
        ] {
            assert!(e.contains("no-such-if0"), "{e}");
        }
    }
}
