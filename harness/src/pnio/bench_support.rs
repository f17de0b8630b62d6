//! What the PROFINET speed bench (`harness/benches/pnio/`, `cargo bench -p harness --bench
//! pnio`) needs of the library, and nothing of the bench itself: the harness's own IO controller
//! (the one `harness run --dut pnio://IFACE` drives) on a network interface, in data exchange
//! with the device, making complete parameter accesses over a data record and keeping the
//! kernel's receive stamps of the input CR's frames. The bench's network namespaces and served
//! device are in the bench target; its statistics in [`crate::stats`].
//!
//! [`Session::open`] finds the device by DCP (the only one answering), connects with the DAP
//! and the controller's default module (PPO 4) in FI 1's slot, and waits for the device's
//! ApplicationReady: data exchange at the 1 ms send clock, WatchdogFactor 100. The controller
//! records no transcript (a suite run's recording decodes every exchange).
//!
//! One parameter access is what a user's "read P102" over PROFINET is (BU 0620 §2.5.6.2): the
//! PKW order written to the record (IODWrite), then the record read (IODRead) until the answer
//! carries the value: a read before the inverter has processed the order is answered "Read
//! Response (−)" (PNIO status DE 80 B5 00) and is read again.

use std::time::{Duration, Instant};

use proto::eth::{EthernetFrame, MacAddr, ETHERTYPE_PROFINET};
use proto::nord::pkw::PkwRepr;
use proto::nord::pnio::{self as def, ModuleKind};
use proto::nord::ppo::PpoType;
use proto::nord::{Inverter, Product};
use proto::pnio::plan::ExpectedSub;
use proto::pnio::rt::RtRepr;
use proto::pnio::{FrameId, FrameKind};

use super::controller::Controller;
use super::link::NetLink;
use crate::net::peer::Link;
use crate::net::LinkError;
use crate::stats::Rate;

/// The record read: 101, FI 1's parameter channel (BU 0620 §2.5.6.2), in FI 1's slot.
pub const RECORD: u16 = 101;
/// The parameter each access reads: P102 (ramp-up time), read (AK 1) at index 0.
pub const PARAMETER: u16 = 102;
/// The PKW order each access writes to [`RECORD`]: "request parameter value" of
/// [`PARAMETER`] (PNU + 1000 on PROFINET).
pub fn order() -> PkwRepr {
    PkwRepr {
        ak: 1,
        spm: false,
        pnu: PARAMETER + proto::nord::pkw::PNU_OFFSET.get(),
        ind: 0,
        pwe: 0,
    }
}

/// Accesses each figure makes before it is timed.
const WARM_UP: u32 = 20;

/// Reads of one access at most before it is given up: at 1 ms per inverter cycle and some
/// 200 µs per read, an answer comes within a few reads.
pub const MAX_READS: u32 = 1_000;

/// Whether `answer` is the value answer to [`order`]: a response label that transfers a value
/// (1 word, 2 double word, 4 and 5 their array forms; BU 0620 §2.5.6.3), the order's PNU and
/// index.
pub fn is_value_answer(answer: &PkwRepr) -> bool {
    use proto::nord::pkw::ResponseLabel as R;
    let o = order();
    [R::WORD, R::DWORD, R::ARRAY_WORD, R::ARRAY_DWORD].contains(&R(answer.ak))
        && answer.pnu == o.pnu
        && answer.ind == o.ind
}

/// The submodules a Connect expects of `product`: the DAP's, and the default module (PPO 4,
/// else PPO 2) in FI 1's slot: what [`Session::open`] connects with, for another client to
/// connect with the same layout.
pub fn layout(product: Product) -> Result<Vec<ExpectedSub>, String> {
    let fi = Inverter::new(1).map_err(|e| e.to_string())?;
    let slot = def::inverter_slot(product, fi).map_err(|e| e.to_string())?;
    let module = [PpoType::TYPE_4, PpoType::TYPE_2]
        .into_iter()
        .find_map(|t| def::module(product, ModuleKind::Ppo(t)))
        .ok_or_else(|| format!("{} has no PPO module", product.name()))?;
    let mut subs = def::expected_dap();
    subs.push(def::expected_module(slot, &module));
    Ok(subs)
}

/// FI 1's slot, where [`RECORD`] is read.
pub fn record_slot(product: Product) -> Result<u16, String> {
    let fi = Inverter::new(1).map_err(|e| e.to_string())?;
    def::inverter_slot(product, fi).map_err(|e| e.to_string())
}

/// The controller's link: the network link, keeping the receive stamps of the device's RT
/// frames while asked to.
struct Stamping {
    inner: NetLink,
    device: Option<MacAddr>,
    recording: bool,
    /// (cycle counter, kernel receive stamp) of each RT frame of the device, in arrival order.
    frames: Vec<(u16, Option<Duration>)>,
}

impl Stamping {
    fn note(&mut self, frame: &[u8], stamp: Option<Duration>) {
        let Ok(eth) = EthernetFrame::new_checked(frame) else {
            return;
        };
        if Some(eth.src()) != self.device || eth.inner_ethertype() != ETHERTYPE_PROFINET {
            return;
        }
        let payload = eth.inner_payload();
        let Some(id) = payload
            .get(..2)
            .map(|b| FrameId(u16::from_be_bytes([b[0], b[1]])))
        else {
            return;
        };
        if id.kind() != FrameKind::Rt {
            return;
        }
        if let Ok(rt) = RtRepr::parse(payload, None) {
            self.frames.push((rt.cycle_counter, stamp));
        }
    }
}

impl Link for Stamping {
    type Device = <NetLink as Link>::Device;

    fn now(&self) -> Duration {
        self.inner.now()
    }

    fn send(&mut self, frame: &[u8]) -> Result<(), LinkError> {
        self.inner.send(frame)
    }

    fn recv(
        &mut self,
        deadline: Duration,
    ) -> Result<Option<(Vec<u8>, Option<Duration>)>, LinkError> {
        let got = self.inner.recv(deadline)?;
        if self.recording {
            if let Some((frame, stamp)) = &got {
                self.note(frame, *stamp);
            }
        }
        Ok(got)
    }

    fn send_udp(&mut self, datagram: &[u8]) -> Result<(), LinkError> {
        self.inner.send_udp(datagram)
    }

    fn recv_udp(&mut self, deadline: Duration) -> Result<Option<Vec<u8>>, LinkError> {
        self.inner.recv_udp(deadline)
    }

    fn wait_until(&mut self, until: Duration) {
        self.inner.wait_until(until)
    }

    fn udp_ends(&mut self) -> (std::net::SocketAddr, std::net::SocketAddr) {
        self.inner.udp_ends()
    }

    fn set_udp_peer(&mut self, peer: std::net::SocketAddr) -> Result<(), LinkError> {
        self.inner.set_udp_peer(peer)
    }

    fn device(&mut self) -> Option<(&mut Self::Device, Duration)> {
        None
    }
}

/// The harness IO controller in data exchange with the device behind an interface.
pub struct Session {
    ctl: Controller<Stamping>,
    slot: u16,
    station: String,
}

/// What [`Session::parameter_accesses`] measured.
#[derive(Debug, Clone, PartialEq)]
pub struct Accesses {
    /// Timed accesses and their time.
    pub rate: Rate,
    /// The time of each timed access, from the IODWrite's request to the answer with the
    /// value, ascending.
    pub latencies: Vec<Duration>,
    /// IODReads of the timed accesses, the answering one included.
    pub reads: u64,
    /// Of those, the ones answered "Read Response (−)" (DE 80 B5 00: not processed yet).
    pub busy: u64,
    /// The PKW answer of the first access, in the manual's terms.
    pub answer: Option<String>,
}

/// What [`Session::input_frames`] saw of the input CR.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct InputFrames {
    /// (cycle number, kernel receive stamp) of every stamped input frame, in arrival order: the
    /// cycle number counts 1 ms cycles by the frame's cycle counter (31.25 µs units), so a
    /// cycle the device did not send shows as a gap, for [`crate::stats::jitter`]. The stamps
    /// are the real-time clock's (compare them with each other only).
    pub arrivals: Vec<(u32, Duration)>,
    /// Input frames without a kernel receive stamp.
    pub unstamped: u64,
    /// How long the exchange ran.
    pub elapsed: Duration,
    /// Whether the last input frame said the device runs (DataStatus RUN and StationProblem
    /// indicator OK): the AR still in data exchange at the end.
    pub running: bool,
}

impl Session {
    /// The controller on `iface` (RPC from UDP 34964), the device found by DCP Identify and
    /// connected as [`layout`] says; `timeout` for each answer.
    pub fn open(iface: &str, product: Product, timeout: Duration) -> Result<Session, String> {
        let nowhere =
            std::net::SocketAddr::from((std::net::Ipv4Addr::LOCALHOST, proto::pnio::RPC_PORT));
        let inner = NetLink::open(iface, ETHERTYPE_PROFINET, nowhere, proto::pnio::RPC_PORT)
            .map_err(|e| e.to_string())?;
        let mac = MacAddr(inner.mac());
        let link = Stamping {
            inner,
            device: None,
            recording: false,
            frames: Vec::new(),
        };
        let mut ctl = Controller::new(link, mac, timeout, true);
        ctl.set_recording(false);
        let s = ctl
            .locate(None)
            .map_err(|e| format!("DCP Identify on {iface}: {e}"))?;
        let name = if s.name.is_empty() {
            "no name of station".to_string()
        } else {
            format!("{:?}", s.name)
        };
        let station = format!(
            "{name} ({}, vendor {:04X}h, device {:04X}h, {}, {})",
            s.type_of_station,
            s.vendor_id,
            s.device_id,
            s.mac,
            s.ip.map_or_else(|| "no IP".to_string(), |i| i.ip.to_string())
        );
        ctl.link_mut().device = Some(s.mac);
        let c = ctl
            .connect(&layout(product)?[def::expected_dap().len()..])
            .map_err(|e| format!("Connect: {e}"))?;
        if !c.ready {
            return Err(format!("the AR did not reach data exchange: {c:?}"));
        }
        Ok(Session {
            ctl,
            slot: record_slot(product)?,
            station,
        })
    }

    /// The device as DCP found it.
    pub fn station(&self) -> &str {
        &self.station
    }

    /// One parameter access: [`order`] written to [`RECORD`] (IODWrite in the AR), then
    /// IODRead of [`RECORD`] (the cyclic exchange running while each answer is awaited) until
    /// the answer carries the value ([`is_value_answer`]). Returns the reads it took, those
    /// answered "Read Response (−)", and the answer. A refused write, another PNIO status, an
    /// answer that is not the value's, or [`MAX_READS`] reads without one, is an error.
    fn access(&mut self) -> Result<(u64, u64, PkwRepr), String> {
        let order = order();
        let status = self
            .ctl
            .write_record(
                self.slot,
                def::IO_SUBSLOT,
                RECORD,
                &order.emit_bytes(),
                String::new(),
            )
            .map_err(|e| format!("IODWrite record {RECORD}: {e}"))?;
        if !status.is_ok() {
            return Err(format!(
                "IODWrite record {RECORD} ({}) refused: {status}",
                order.describe_order()
            ));
        }
        let mut busy = 0;
        for reads in 1..=u64::from(MAX_READS) {
            let (status, data) = self
                .ctl
                .read_record(self.slot, def::IO_SUBSLOT, RECORD, String::new())
                .map_err(|e| format!("IODRead record {RECORD}: {e}"))?;
            if status == def::busy_status() {
                busy += 1;
                continue;
            }
            if !status.is_ok() {
                return Err(format!("IODRead record {RECORD}: {status}"));
            }
            let answer = PkwRepr::parse(&data)
                .map_err(|e| format!("IODRead record {RECORD}: {data:02X?} ({e})"))?;
            if !is_value_answer(&answer) {
                return Err(format!(
                    "IODRead record {RECORD} answered {}, not the value of {}",
                    answer.describe_response(),
                    order.describe_order()
                ));
            }
            return Ok((reads, busy, answer));
        }
        Err(format!(
            "no answer with the value after {MAX_READS} IODReads of record {RECORD}"
        ))
    }

    /// [`WARM_UP`] parameter accesses untimed, then up to `count` within `limit`, each timed
    /// (one access: the PKW order written, then the record read until the answer with the
    /// value; see the module's documentation).
    pub fn parameter_accesses(&mut self, count: u32, limit: Duration) -> Result<Accesses, String> {
        let mut answer = None;
        for i in 0..WARM_UP {
            let (_, _, a) = self
                .access()
                .map_err(|e| format!("{e} (warm-up access {})", i + 1))?;
            answer.get_or_insert_with(|| a.describe_response());
        }
        let mut got = Accesses {
            rate: Rate {
                count: 0,
                secs: 0.0,
            },
            latencies: Vec::with_capacity(count as usize),
            reads: 0,
            busy: 0,
            answer,
        };
        let start = Instant::now();
        let mut n = 0u64;
        while n < u64::from(count) && start.elapsed() < limit {
            let t = Instant::now();
            let (reads, busy, _) = self
                .access()
                .map_err(|e| format!("{e} (after {n} timed accesses)"))?;
            got.latencies.push(t.elapsed());
            got.reads += reads;
            got.busy += busy;
            n += 1;
        }
        got.rate = Rate {
            count: n,
            secs: start.elapsed().as_secs_f64(),
        };
        got.latencies.sort_unstable();
        Ok(got)
    }

    /// Keeps the AR in data exchange for `duration` (after 100 ms untimed), the controller's
    /// output frame every 1 ms, and collects the kernel's receive stamps of the input CR's
    /// frames.
    pub fn input_frames(&mut self, duration: Duration) -> Result<InputFrames, String> {
        let cycle = |e| format!("cyclic exchange: {e}");
        self.ctl
            .run_for(Duration::from_millis(100))
            .map_err(cycle)?;
        let link = self.ctl.link_mut();
        link.frames.clear();
        link.recording = true;
        let start = Instant::now();
        let ran = self.ctl.run_for(duration);
        let elapsed = start.elapsed();
        let link = self.ctl.link_mut();
        link.recording = false;
        let frames = std::mem::take(&mut link.frames);
        ran.map_err(cycle)?;
        // Cycle numbers from the cycle counter: 32 units of 31.25 µs a 1 ms cycle, the 16-bit
        // counter wrapping every 2.048 s.
        let mut arrivals = Vec::with_capacity(frames.len());
        let mut unstamped = 0;
        let mut number = 0u32;
        let mut last: Option<u16> = None;
        for (counter, stamp) in frames {
            if let Some(prev) = last {
                number = number.wrapping_add(u32::from(counter.wrapping_sub(prev) / 32));
            }
            last = Some(counter);
            match stamp {
                Some(at) => arrivals.push((number, at)),
                None => unstamped += 1,
            }
        }
        let running = self
            .ctl
            .input_status()
            .is_some_and(|s| s.run() && s.station_ok());
        Ok(InputFrames {
            arrivals,
            unstamped,
            elapsed,
            running,
        })
    }

    /// Release: the AR ends, the device free for another controller.
    pub fn release(mut self) -> Result<(), String> {
        let status = self.ctl.release().map_err(|e| format!("Release: {e}"))?;
        if status.is_ok() {
            Ok(())
        } else {
            Err(format!("Release refused: {status}"))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_unknown_interface_is_an_error_naming_it() {
        let e = Session::open("no-such-if0", Product::Sk550p, Duration::from_millis(10))
            .err()
            .expect("no such interface");
        assert!(e.contains("no-such-if0"), "{e}");
    }

    #[test]
    fn the_layout_is_the_dap_and_fi_1s_module() {
        let subs = layout(Product::Sk550p).unwrap();
        assert_eq!(subs.len(), def::expected_dap().len() + 1);
        assert_eq!(
            subs.last().unwrap().slot,
            record_slot(Product::Sk550p).unwrap()
        );
        assert_eq!(order().pnu, 1102);
    }

    #[test]
    fn only_the_value_of_the_order_ends_an_access() {
        let value = PkwRepr {
            ak: 1,
            pwe: 300,
            ..order()
        };
        assert!(is_value_answer(&value));
        assert!(is_value_answer(&PkwRepr { ak: 2, ..value }));
        // Refused (AK 7), no answer yet (AK 0), another parameter's or index's answer.
        assert!(!is_value_answer(&PkwRepr { ak: 7, ..value }));
        assert!(!is_value_answer(&PkwRepr { ak: 0, ..value }));
        assert!(!is_value_answer(&PkwRepr { pnu: 1103, ..value }));
        assert!(!is_value_answer(&PkwRepr {
            ind: 0x0100,
            ..value
        }));
    }
}
