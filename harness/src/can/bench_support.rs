//! What the system-bus speed bench (`harness/benches/can/`, `cargo bench -p harness --bench
//! can`) needs of the library: the harness's own SDO client (the one `harness run --dut
//! socketcand://…` drives) on a socketcand link, and nothing of the bench itself. It records no
//! transcript worth keeping while it measures.

use std::net::SocketAddr;
use std::time::{Duration, Instant};

use super::link::Socketcand;
use super::sdo::Client;
use crate::stats::Rate;

/// The object read: P102 set 1 of FI 3, at 2066h:01h of node 36 (expedited, 2 bytes).
pub const NODE: u8 = 36;
/// Its index.
pub const INDEX: u16 = 0x2066;
/// Its sub-index.
pub const SUB: u8 = 1;

/// Reads made before the timed ones.
const WARM_UP: u32 = 100;

/// Reads timed one by one.
#[derive(Debug, Clone)]
pub struct Reads {
    /// All of them: how many in how long.
    pub rate: Rate,
    /// Each one's time, µs.
    pub each_us: Vec<f64>,
}

/// `count` complete SDO reads of [`INDEX`]:[`SUB`] of [`NODE`] on the bus `channel` of the
/// socketcand server at `addr`: each one the upload request sent and the node's answer with the
/// value received (its transcript lines rendered and dropped, as a run renders them), one after
/// the other.
pub fn sdo_reads(addr: SocketAddr, channel: &str, count: u32) -> Result<Reads, String> {
    let limit = Duration::from_secs(2);
    let link = Socketcand::connect(addr, channel, limit).map_err(|e| e.to_string())?;
    let mut client = Client::new(link, limit);
    let read = |client: &mut Client<Socketcand>| {
        let r = client.upload(NODE, INDEX, SUB).map_err(|e| e.to_string());
        client.take_exchanges();
        r
    };
    for _ in 0..WARM_UP {
        read(&mut client)?;
    }
    let mut each_us = Vec::with_capacity(count as usize);
    let start = Instant::now();
    for _ in 0..count {
        let t = Instant::now();
        let value = read(&mut client)?;
        each_us.push(t.elapsed().as_secs_f64() * 1e6);
        if value.len() != 2 {
            return Err(format!("P102 came back as {} bytes", value.len()));
        }
    }
    Ok(Reads {
        rate: Rate {
            count: u64::from(count),
            secs: start.elapsed().as_secs_f64(),
        },
        each_us,
    })
}

/// What [`pdo_cycles`] measured: the period the harness ran at, and the intervals between
/// SYNCs as another client of the bus saw them (µs, sorted).
pub struct PdoJitter {
    /// The period the harness's process data ran at.
    pub period: Duration,
    /// Intervals between consecutive SYNCs seen on the bus, sorted.
    pub intervals_us: Vec<u64>,
}

impl PdoJitter {
    /// The interval at quantile `q` (0…1), µs.
    pub fn quantile(&self, q: f64) -> u64 {
        let n = self.intervals_us.len();
        if n == 0 {
            return 0;
        }
        self.intervals_us[((n - 1) as f64 * q).round() as usize]
    }

    /// The largest deviation of an interval from the period, µs.
    pub fn worst_us(&self) -> u64 {
        let p = self.period.as_micros() as u64;
        self.intervals_us
            .iter()
            .map(|i| i.abs_diff(p))
            .max()
            .unwrap_or(0)
    }
}

/// `cycles` process-data cycles of the harness (`harness run` over socketcand drives the same
/// code) with FI 2 of the SK 550P commanded, on the bus `channel` at `addr`; a second client
/// of the bus timestamps every SYNC it sees.
pub fn pdo_cycles(addr: SocketAddr, channel: &str, cycles: u32) -> Result<PdoJitter, String> {
    use super::link::CanLink;
    use super::process::{PdoCycle, Pdos};
    use crate::binding::settle::Cycling;
    let limit = Duration::from_secs(2);
    let mut listener = Socketcand::connect(addr, channel, limit).map_err(|e| e.to_string())?;
    let watch = std::thread::spawn(move || {
        let mut seen = Vec::new();
        while let Ok(Some(f)) = listener.recv(Duration::from_millis(500)) {
            if f.id() == 0x080 {
                seen.push(Instant::now());
            }
        }
        seen
    });
    let link = Socketcand::connect(addr, channel, limit).map_err(|e| e.to_string())?;
    let mut client = Client::new(link, limit);
    let mut pdos = Pdos::new(proto::nord::Product::Sk550p, 8);
    let fi2 = proto::nord::Inverter::new(2).map_err(|e| e.to_string())?;
    pdos.set_words(fi2, [0x047E, 0, 0, 0, 0, 0])
        .map_err(|e| e.to_string())?;
    let period = pdos.cycle();
    let mut c = PdoCycle {
        client: &mut client,
        pdos: &mut pdos,
    };
    c.set_recording(false);
    c.run_cycles(u64::from(cycles)).map_err(|e| e.to_string())?;
    drop(client);
    let seen = watch
        .join()
        .map_err(|_| "the listener panicked".to_string())?;
    let mut intervals_us: Vec<u64> = seen
        .windows(2)
        .map(|w| (w[1] - w[0]).as_micros() as u64)
        .collect();
    intervals_us.sort_unstable();
    Ok(PdoJitter {
        period,
        intervals_us,
    })
}
