//! Process data over the system bus: the harness in the bus interface's place, cycling every
//! inverter's RPDOs and a SYNC, and taking the TPDOs the nodes answer with (CiA 301
//! synchronous PDOs; the layout `proto::nord::can::pdo_words`, not stated by the manuals).
//!
//! The harness runs the process data of the inverters the case has sent words to (as a
//! gateway configured with those inverters; a `wait` step before any runs FI 1's, 0000h).
//! Every one of them gets its RPDOs in every cycle. The cycle is the update cycle of that many
//! inverters (`proto::nord::can::update_cycle`: the SK TU3-EIP's table, else "≥ 5 ms") unless
//! their frames need longer on the wire at 250 kBaud (`cycle_bus_time_us`, worst-case frame
//! lengths): then that bus time, rounded up to the millisecond. A cycle shorter than its frames
//! could not run on a real bus.
//!
//! The nodes are started (NMT start, all nodes) before the first cycle and put back into
//! pre-operational when the case ends.

use std::thread;
use std::time::Duration;

use proto::can::CanFrame;
use proto::canopen::cob_id::{Cob, Function};
use proto::canopen::NmtCommand;
use proto::nord::can::{
    cycle_period_us, inverter_series, pdo_data, pdo_words, process_values, InverterSeries,
    SystemBusAddress,
};
use proto::nord::{Inverter, Product};

use super::link::{CanLink, CanLinkError};
use super::sdo::{describe, Client};
use crate::binding::settle::{Clocked, Cycling};
use crate::hex::can_frame;
use crate::outcome::Exchange;

/// The process data of one segment: each inverter's node, its words out and in.
#[derive(Debug)]
pub(super) struct Pdos {
    product: Product,
    series: InverterSeries,
    /// FI n's node, in FI order.
    nodes: Vec<(Inverter, u8)>,
    /// The control word and setpoints 1–5 each inverter gets.
    outputs: Vec<[u16; 6]>,
    /// The status word and actual values 1–5 of each inverter's last TPDOs, and whether its
    /// TPDO1 came in the last cycle.
    inputs: Vec<([u16; 6], bool)>,
    /// The nodes were started.
    started: bool,
    /// Whether cycles are recorded in the transcript.
    recording: bool,
    /// When the next cycle is due.
    due: Option<Duration>,
    /// The inverters the case sent words.
    pub(super) commanded: Vec<Inverter>,
}

/// Why a process-data cycle failed.
#[derive(Debug, thiserror::Error)]
pub(super) enum PdoError {
    #[error("{0}")]
    Link(#[from] CanLinkError),
    /// A frame the harness builds could not be formed (an internal error).
    #[error("{0}")]
    Frame(String),
    /// The inverter has no node on this product's system bus.
    #[error("FI {0} is not on the system bus of this product")]
    NoNode(u8),
    /// The inverter's TPDO1 did not come within the cycle.
    #[error("no TPDO1 from node {node} (FI {fi}) in {cycles} cycles of {cycle:?} after SYNC")]
    Silent {
        fi: u8,
        node: u8,
        cycles: u32,
        cycle: Duration,
    },
}

/// The inverter series the harness assumes behind `product`: one with five process values
/// where the product serves one (SK 5x0P, SK 54xE), whose PDO 2 carries values 4–5; an inverter
/// with three ignores the RPDO2 it has no mapping for, and its actual values 4–5 read 0.
fn series(product: Product) -> InverterSeries {
    let served = inverter_series(product);
    served
        .iter()
        .copied()
        .find(|s| process_values(*s) == 5)
        .unwrap_or(served[0])
}

/// The period of `inverters` inverters behind `product` (see the module documentation).
pub(super) fn period(product: Product, inverters: u8) -> Duration {
    Duration::from_micros(u64::from(cycle_period_us(
        product,
        series(product),
        inverters,
    )))
}

impl Pdos {
    /// The process data of FI 1..=`inverters` behind `product`.
    pub(super) fn new(product: Product, inverters: u8) -> Pdos {
        let nodes: Vec<(Inverter, u8)> = (1..=inverters)
            .filter_map(|n| Inverter::new(i64::from(n)).ok())
            .filter_map(|fi| {
                let node = SystemBusAddress::for_inverter(product, fi).ok()?;
                Some((fi, node.get()))
            })
            .collect();
        let n = nodes.len();
        Pdos {
            series: series(product),
            nodes,
            outputs: vec![[0; 6]; n],
            inputs: vec![([0; 6], false); n],
            product,
            started: false,
            recording: true,
            due: None,
            commanded: Vec::new(),
        }
    }

    fn slot(&self, fi: Inverter) -> Result<usize, PdoError> {
        self.nodes
            .iter()
            .position(|(f, _)| *f == fi)
            .ok_or(PdoError::NoNode(fi.get()))
    }

    /// Sets FI `fi`'s words for the next cycles.
    pub(super) fn set_words(&mut self, fi: Inverter, words: [u16; 6]) -> Result<(), PdoError> {
        let i = self.slot(fi)?;
        self.outputs[i] = words;
        if !self.commanded.contains(&fi) {
            self.commanded.push(fi);
        }
        Ok(())
    }

    /// FI `fi`'s six input words as its last TPDOs brought them, `None` when its TPDO1 did not
    /// come in the last cycle.
    pub(super) fn inputs(&self, fi: Inverter) -> Result<Option<[u16; 6]>, PdoError> {
        let (words, fresh) = self.inputs[self.slot(fi)?];
        Ok(fresh.then_some(words))
    }

    /// The node of `fi`.
    pub(super) fn node(&self, fi: Inverter) -> Result<u8, PdoError> {
        Ok(self.nodes[self.slot(fi)?].1)
    }

    /// How many inverters the segment has.
    pub(super) fn len(&self) -> u8 {
        self.nodes.len() as u8
    }

    /// The period of the cycle, for the inverters commanded so far.
    pub(super) fn cycle(&self) -> Duration {
        period(self.product, self.commanded.len().max(1) as u8)
    }

    /// Whether the nodes were started, and so must be stopped when the case ends.
    pub(super) fn started(&self) -> bool {
        self.started
    }

    /// One cycle: NMT start before the first, each inverter's RPDOs, SYNC, then the frames of
    /// the cycle's time, its TPDOs among them.
    fn run_cycle<L: CanLink>(&mut self, client: &mut Client<L>) -> Result<(), PdoError> {
        // Cycles follow each other on the schedule, not on when the last one ended: a cycle
        // that ran over its time does not push the later ones back, unless by a whole cycle.
        let now = client.link.now();
        let start = match self.due {
            Some(due) if due <= now && now - due < self.cycle() => due,
            _ => now,
        };
        let mut sent = Vec::with_capacity(2 * self.nodes.len() + 2);
        if !self.started {
            sent.push(nmt(NmtCommand::START, 0)?);
            self.started = true;
        }
        for ((fi, node), words) in self.nodes.iter().zip(&self.outputs) {
            if !self.commanded.contains(fi) {
                continue;
            }
            for number in [1, 2] {
                let rpdo = Function::Rpdo { number };
                if let Some(data) = pdo_data(rpdo, self.series, words) {
                    sent.push(frame(rpdo, *node, &data)?);
                }
            }
        }
        sent.push(CanFrame::new(0x080, &[]).map_err(|e| PdoError::Frame(e.to_string()))?);
        for f in &sent {
            client.link.send(f)?;
        }
        for (_, fresh) in &mut self.inputs {
            *fresh = false;
        }
        let end = start + self.cycle();
        self.due = Some(end);
        let mut received = Vec::new();
        // On a real clock the rest of the cycle is slept once every TPDO is in: a socket's
        // receive time-out rounds up to the kernel's tick (milliseconds), a sleep does not.
        let real_time = client.link.segment().is_none();
        let expected = self.commanded.len() * self.tpdos_per_node();
        let mut tpdos = 0;
        loop {
            if real_time && tpdos >= expected {
                thread::sleep(end.saturating_sub(client.link.now()));
                break;
            }
            let left = end.saturating_sub(client.link.now());
            let Some(f) = client.link.recv(left)? else {
                break;
            };
            client.overheard(&f);
            if matches!(
                Cob::classify(f.id()),
                Some(Cob {
                    function: Function::Tpdo { .. },
                    ..
                })
            ) {
                tpdos += 1;
            }
            self.take(&f);
            received.push(f);
            if left.is_zero() {
                break;
            }
        }
        if self.recording {
            let joined = |frames: &[CanFrame], each: fn(&CanFrame) -> String| {
                frames.iter().map(each).collect::<Vec<_>>().join("; ")
            };
            client.record(Exchange {
                sent_hex: joined(&sent, can_frame),
                sent: format!("process-data cycle: {}", joined(&sent, describe)),
                received_hex: joined(&received, can_frame),
                received: if received.is_empty() {
                    "(nothing received)".into()
                } else {
                    joined(&received, describe)
                },
            });
        }
        Ok(())
    }

    /// The TPDOs a node of the assumed series answers each SYNC with.
    fn tpdos_per_node(&self) -> usize {
        [1, 2]
            .into_iter()
            .filter(|&number| pdo_words(Function::Tpdo { number }, self.series).is_some())
            .count()
    }

    /// A frame of the cycle: a TPDO fills its inverter's inputs.
    fn take(&mut self, f: &CanFrame) {
        let Some(Cob {
            function: tpdo @ Function::Tpdo { number },
            node,
        }) = Cob::classify(f.id())
        else {
            return;
        };
        let Some(i) = self.nodes.iter().position(|(_, n)| *n == node) else {
            return;
        };
        let Some((first, count)) = pdo_words(tpdo, self.series) else {
            return;
        };
        let (first, count) = (usize::from(first), usize::from(count));
        let (words, fresh) = &mut self.inputs[i];
        for (w, b) in words[first..first + count]
            .iter_mut()
            .zip(f.data().chunks_exact(2))
        {
            *w = u16::from_le_bytes([b[0], b[1]]);
        }
        *fresh |= number == 1;
    }
}

fn frame(function: Function, node: u8, data: &[u8]) -> Result<CanFrame, PdoError> {
    let id = function
        .cob_id(node)
        .map_err(|e| PdoError::Frame(e.to_string()))?;
    CanFrame::new(id, data).map_err(|e| PdoError::Frame(e.to_string()))
}

/// An NMT command to `node` (0: all).
pub(super) fn nmt(command: NmtCommand, node: u8) -> Result<CanFrame, PdoError> {
    CanFrame::new(0, &[command.0, node]).map_err(|e| PdoError::Frame(e.to_string()))
}

/// The process data and the client that carries them, as the shared cycling code drives them.
pub(super) struct PdoCycle<'a, L> {
    pub(super) client: &'a mut Client<L>,
    pub(super) pdos: &'a mut Pdos,
}

impl<L: CanLink> Cycling for PdoCycle<'_, L> {
    type Error = PdoError;

    fn run_cycles(&mut self, n: u64) -> Result<(), PdoError> {
        for _ in 0..n {
            self.pdos.run_cycle(self.client)?;
        }
        Ok(())
    }

    fn take_exchanges(&mut self) -> Vec<Exchange> {
        self.client.take_exchanges()
    }

    fn set_recording(&mut self, on: bool) {
        self.pdos.recording = on;
    }

    fn set_words(&mut self, fi: Inverter, words: [u16; 6]) -> Result<(), PdoError> {
        self.pdos.set_words(fi, words)
    }

    fn status_word(&mut self, fi: Inverter) -> Result<u16, PdoError> {
        match self.pdos.inputs(fi)? {
            Some(w) => Ok(w[0]),
            None => Err(PdoError::Silent {
                fi: fi.get(),
                node: self.pdos.node(fi)?,
                cycles: 1,
                cycle: self.pdos.cycle(),
            }),
        }
    }
}

impl<L: CanLink> Clocked for PdoCycle<'_, L> {
    fn now(&self) -> Duration {
        self.client.link.now()
    }

    fn run_cycles_until(&mut self, end: Duration) -> Result<u64, PdoError> {
        let mut n = 0;
        while self.client.link.now() + self.pdos.cycle() <= end {
            self.pdos.run_cycle(self.client)?;
            n += 1;
        }
        Ok(n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cycle_is_the_update_cycle_or_the_wire_time_of_its_frames() {
        // One SK 5x0P: 4 frames and a SYNC, well under 5 ms at 250 kBaud.
        assert_eq!(period(Product::Sk550p, 1), Duration::from_millis(5));
        // Eight: 33 frames need more than the 5 ms the manual allows as a minimum.
        let eight = period(Product::Sk550p, 8);
        assert!(eight > Duration::from_millis(5), "{eight:?}");
        assert_eq!(
            u64::from(proto::nord::can::cycle_bus_time_us(
                InverterSeries::Sk5x0p,
                8
            ))
            .div_ceil(1000),
            eight.as_millis() as u64
        );
        // The SK TU3-EIP's table gives 5 ms for one inverter.
        assert_eq!(period(Product::Tu3Eip, 1), Duration::from_millis(5));
    }

    #[test]
    fn status_comes_from_the_tpdo_and_a_stopped_node_is_a_named_silence() {
        let segment =
            sim::can::Segment::new(sim::device::DeviceConfig::new(Product::Sk550p)).unwrap();
        let link = super::super::link::Embedded::new(segment);
        let mut client = Client::new(link, Duration::from_millis(100));
        client.take_exchanges();
        let mut pdos = Pdos::new(Product::Sk550p, 8);
        let fi1 = Inverter::new(1).unwrap();
        pdos.set_words(fi1, [0x047E, 0, 0, 0, 0, 0]).unwrap();
        let mut c = PdoCycle {
            client: &mut client,
            pdos: &mut pdos,
        };
        c.run_cycles(6).unwrap();
        // Ready for switch-on, xx31h (BU 0620 §6.1.2.3), once the inverter has initialised.
        assert_eq!(c.status_word(fi1).unwrap() & 0xFF, 0x31);
        assert_eq!(c.now(), Duration::from_millis(30), "six cycles of 5 ms");
        c.client
            .link
            .send(&nmt(NmtCommand::STOP, 32).unwrap())
            .unwrap();
        c.run_cycles(1).unwrap();
        let e = c.status_word(fi1).unwrap_err();
        assert!(
            e.to_string().contains("no TPDO1 from node 32 (FI 1)"),
            "{e}"
        );
        let cycles = c.take_exchanges();
        assert_eq!(cycles.len(), 7);
        // NMT start before the first cycle; FI 1's RPDO1 and RPDO2, then SYNC.
        assert_eq!(
            cycles[0].sent_hex,
            "000 01 00; 220 7E 04 00 00 00 00 00 00; 320 00 00 00 00; 080"
        );
        assert!(
            cycles[5].received_hex.starts_with("1A0 31 0B"),
            "{cycles:?}"
        );
        assert_eq!(cycles[6].received, "(nothing received)");
    }

    #[test]
    fn behind_a_module_the_harness_sends_five_values() {
        assert_eq!(series(Product::Tu4Pol), InverterSeries::Sk54xe);
        assert_eq!(series(Product::Sk550p), InverterSeries::Sk5x0p);
    }
}
