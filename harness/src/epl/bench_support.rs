//! What the POWERLINK speed bench (`harness/benches/epl/`, `cargo bench -p harness --bench
//! epl`) needs of the library, and nothing of the bench itself: the harness's own managing node
//! (the one `harness run --dut epl://IFACE` drives) on a network interface, doing SDO reads over
//! ASnd and over UDP and running the isochronous cycle. The bench's network namespace and served
//! node are in the bench target; its statistics in [`crate::stats`].
//!
//! Each function opens the interface, boots the node (closing the SDO connections an earlier
//! MN left open), sets the node's cycle length 1006h to the MN's cycle (BU 0620 §4.2.3: P858
//! "POWERLINK cycle", 400…2000 µs on the SK 550P), brings the node as far as the figure needs,
//! warms up, then measures. The MN records no transcript while it measures (a suite run's
//! recording decodes every frame, which is not what a bus does).

use std::net::SocketAddr;
use std::time::{Duration, Instant};

use proto::epl::sdo::Command;
use proto::epl::{NmtState, RequestedService};
use proto::eth::MacAddr;
use proto::nord::epl as def;

use super::mn::link::NetLink;
use super::mn::{Manager, MnConfig, Via};
use crate::stats::Rate;

/// The node id of the bench's node (the served node's default).
pub const NODE: u8 = 1;

/// The object read: 1018h:01h, the vendor id (BU 0620 §2.4.6 identity object).
pub const INDEX: u16 = 0x1018;
/// Its sub-index.
pub const SUB: u8 = 1;

/// The cycle length object the node synchronises to (EPSG DS 301 NMT_CycleLen_U32).
const CYCLE_LEN: u16 = 0x1006;

/// Operations (SDO reads, cycles) each figure makes before it is timed.
const WARM_UP: u32 = 100;

/// How the SDO reads of [`sdo_reads`] travel (EPSG DS 301 §6.3; BU 0620 §2.4.1
/// "asynchronous data transfer (SDO over ASND or UDP/IP)").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Transport {
    /// ASnd frames in the asynchronous phase: the MN's own slot for the request, an
    /// UnspecifiedInvite for the answer, so a read takes at least two cycles.
    Asnd,
    /// UDP datagrams to the node's port 3819, beside the running cycle.
    Udp,
}

impl Transport {
    fn via(self) -> Via {
        match self {
            Transport::Asnd => Via::Asnd,
            Transport::Udp => Via::Udp,
        }
    }
}

/// The MN on `iface` for the node at `node` (its UDP address, port 3819), cycling every
/// `cycle`, the node's cycle length set to the same, the node booted to `state`.
fn manager(
    iface: &str,
    node: SocketAddr,
    cycle: Duration,
    state: NmtState,
) -> Result<Manager<NetLink>, String> {
    let link = NetLink::open(iface, proto::eth::ETHERTYPE_POWERLINK, node, 0)
        .map_err(|e| e.to_string())?;
    let mac = MacAddr(link.mac());
    let config = MnConfig {
        node: NODE,
        ..MnConfig::default()
    };
    let mut m = Manager::new(link, config, mac);
    m.set_cycle(cycle);
    m.set_recording(false);
    m.boot(NmtState::PRE_OPERATIONAL_2)
        .map_err(|e| format!("boot to PRE_OPERATIONAL_2 on {iface}: {e}"))?;
    m.close_sdo()
        .map_err(|e| format!("closing stale SDO connections: {e}"))?;
    let us = u32::try_from(cycle.as_micros()).unwrap_or(u32::MAX);
    m.sdo(
        Via::Asnd,
        Command::write_by_index(0, CYCLE_LEN, 0, &us.to_le_bytes()),
    )
    .map_err(|e| format!("SDO write of {CYCLE_LEN:04X}h:00h = {us} µs: {e}"))?;
    if state != NmtState::PRE_OPERATIONAL_2 {
        m.boot(state)
            .map_err(|e| format!("boot to {state} on {iface}: {e}"))?;
    }
    Ok(m)
}

/// One SDO read of [`INDEX`]:[`SUB`], which must give the node's vendor id.
fn read(m: &mut Manager<NetLink>, via: Via) -> Result<(), String> {
    let data = m
        .sdo(via, Command::read_by_index(0, INDEX, SUB))
        .map_err(|e| format!("SDO read {INDEX:04X}h:{SUB:02X}h over {via:?}: {e}"))?;
    if data != def::VENDOR_ID.to_le_bytes() {
        return Err(format!(
            "SDO read {INDEX:04X}h:{SUB:02X}h over {via:?} gave {data:02X?}, not vendor id {:08X}h",
            def::VENDOR_ID
        ));
    }
    Ok(())
}

/// SDO reads of 1018h:01h (expedited) by the harness MN on `iface` from the node at `node` in
/// PRE_OPERATIONAL_2, one after the other, over `via`, with the cycle running every `cycle`
/// (over ASnd the cycle carries them; over UDP a cycle is run between two reads whenever one
/// is due, as an MN's cycle runs beside its SDO transfers): up to `count` within `limit`. An
/// abort, a wrong value, or the node leaving PRE_OPERATIONAL_2 ends the figure with an error.
pub fn sdo_reads(
    iface: &str,
    node: SocketAddr,
    via: Transport,
    cycle: Duration,
    count: u32,
    limit: Duration,
) -> Result<Rate, String> {
    let mut m = manager(iface, node, cycle, NmtState::PRE_OPERATIONAL_2)?;
    let via = via.via();
    let mut due = m.now();
    let mut one = |m: &mut Manager<NetLink>| -> Result<(), String> {
        if via == Via::Udp && m.now() >= due {
            m.cycle(RequestedService::NO_SERVICE)
                .map_err(|e| format!("cycle: {e}"))?;
            due = m.now() + cycle;
        }
        read(m, via)
    };
    for i in 0..WARM_UP {
        one(&mut m).map_err(|e| format!("{e} (warm-up read {})", i + 1))?;
    }
    let start = Instant::now();
    let mut n = 0u64;
    while n < u64::from(count) && start.elapsed() < limit {
        one(&mut m).map_err(|e| format!("{e} (after {n} timed reads)"))?;
        n += 1;
    }
    let rate = Rate {
        count: n,
        secs: start.elapsed().as_secs_f64(),
    };
    // The node's state as its last frame showed it: still cycling.
    m.run_cycles(1).map_err(|e| format!("cycle: {e}"))?;
    match m.node_state() {
        Some(NmtState::PRE_OPERATIONAL_2) => Ok(rate),
        other => Err(format!(
            "the node left PRE_OPERATIONAL_2 during the reads: {}",
            other.map_or_else(|| "no state seen".into(), |s| s.to_string())
        )),
    }
}

/// What [`cycles`] saw.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Cycles {
    /// Cycles run (timed).
    pub cycles: u32,
    /// (cycle number, kernel receive stamp of its PRes) of every cycle whose PRes came with a
    /// stamp, in order: for [`crate::stats::jitter`] against the cycle time. The stamps are
    /// the real-time clock's (compare them with each other only).
    pub arrivals: Vec<(u32, Duration)>,
    /// Cycles whose PRes did not come within the MN's reply time.
    pub missed: u64,
    /// Cycles whose PRes came without a kernel receive stamp.
    pub unstamped: u64,
    /// From the start of the first timed cycle to the end of the last, on the MN's clock:
    /// `elapsed / cycles` is the cycle the MN sustained.
    pub elapsed: Duration,
    /// The node's NMT state after the last cycle, as its PRes showed it (OPERATIONAL unless it
    /// counted a loss of the SoC).
    pub state: Option<String>,
}

/// The isochronous cycle of the harness MN on `iface` with the node at `node` (its UDP address)
/// OPERATIONAL: SoC, PReq, PRes, SoA (no asynchronous request) every `cycle` for `duration`,
/// after [`WARM_UP`] untimed cycles, with the kernel's receive stamp of each PRes
/// ([`Manager::record_stamps`]). The MN keeps its own schedule: each cycle is due a cycle after
/// the start of the one before.
pub fn cycles(
    iface: &str,
    node: SocketAddr,
    cycle: Duration,
    duration: Duration,
) -> Result<Cycles, String> {
    let mut m = manager(iface, node, cycle, NmtState::OPERATIONAL)?;
    m.run_cycles(u64::from(WARM_UP))
        .map_err(|e| format!("cycle: {e}"))?;
    let n = u32::try_from(duration.as_nanos() / cycle.as_nanos().max(1)).unwrap_or(u32::MAX);
    let missed_before = m.missed();
    m.record_stamps(true);
    let start = m.now();
    let ran = m.run_cycles(u64::from(n));
    let elapsed = m.now().saturating_sub(start);
    let stamps = m.record_stamps(false);
    ran.map_err(|e| format!("cycle: {e}"))?;
    let missed = m.missed() - missed_before;
    let arrivals: Vec<(u32, Duration)> = stamps
        .iter()
        .enumerate()
        .filter_map(|(i, s)| Some((u32::try_from(i).ok()?, (*s)?)))
        .collect();
    let unstamped = ((stamps.len() - arrivals.len()) as u64).saturating_sub(missed);
    Ok(Cycles {
        cycles: n,
        arrivals,
        missed,
        unstamped,
        elapsed,
        state: m.node_state().map(|s| s.to_string()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_unknown_interface_is_an_error_naming_it() {
        let node = SocketAddr::from((def::ip_address(NODE), proto::epl::SDO_UDP_PORT));
        let short = Duration::from_millis(10);
        for e in [
            sdo_reads("no-such-if0", node, Transport::Asnd, short, 1, short).unwrap_err(),
            sdo_reads("no-such-if0", node, Transport::Udp, short, 1, short).unwrap_err(),
            cycles("no-such-if0", node, short, short).unwrap_err(),
        ] {
            assert!(e.contains("no-such-if0"), "{e}");
        }
    }
}
