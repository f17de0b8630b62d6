//! The bus interface's gateway to its inverters' process data: the PDO side of the system bus.
//! The words the field bus brings for FI n on the system bus become CAN frames to FI n's node
//! (32 + 2·(n − 1)): RPDO1 (200h + node, the control word and setpoints 1–3) and RPDO2 (300h +
//! node, setpoints 4–5, for a series with five values), then a SYNC (080h); at the SYNC the
//! node hands the words its RPDOs brought to its drive and answers with its TPDOs (180h/280h +
//! node, `crate::pdo_image`, the same node side a `crate::can::Segment` has); the gateway reads
//! the status word and actual values back from the TPDOs' bytes, and those are what the field
//! bus gets. The layout is `proto::nord::can::pdo_words`'s; the series is the SK 5x0P behind
//! the SK 550P, the SK 54xE behind a bus module (as `crate::can` has them).
//!
//! Timing. The gateway runs its process-data cycles no more often than the update cycle of the
//! inverters it carries (`proto::nord::can::cycle_period_us`: "≥ 5 ms", the SK TU3-EIP's
//! table), and on an SK CU4/TU4 no more often than P153 [-02] "TxPDO Inhibit Time" either. A
//! cycle starts when the field bus brings an inverter's words and the cycle is due; the other
//! inverters whose words the same field-bus frame brings (at the same time) join it, so that
//! one SYNC takes them all. Words that come while no cycle is due are not carried: the node
//! keeps the words it had, and the field bus gets the status word and actual values of the
//! last TPDOs the gateway received from it — the delay a real gateway adds to the field bus's
//! (BU 0620 §2.5.3: the system bus's cycle adds to the PROFINET run time). A field bus repeats
//! its words every cycle, so the words it keeps sending are carried at the next cycle.
//!
//! The tolerance. A real gateway's cycle runs on its own timer and carries, at each tick, the
//! words the field bus last brought; a field bus exactly as fast as the system bus (an RPI of
//! 5 ms) has each of its words carried, whatever microseconds its frames jitter by. The
//! simulated gateway acts only when the field bus brings words: words that come a little before
//! the cycle is due ([`EARLY`]: within a tenth of the cycle) stand for the timer's next tick and
//! are carried, and the next cycle is due one cycle after that tick, not after the words' time,
//! so that the cycles keep the timer's pace on average. Words that come later than the tick
//! start the timer afresh from their time.
//!
//! In-process and sans-IO, as the SDO side ([`super::Gateway`]): the frames are the ones
//! exchanged, in order for each inverter, handed to the caller to record ([`super::Tap`]). Each
//! node answers the one SYNC of the cycle when its inverter's words come: the nodes do not hear
//! each other, so the answers are those of RPDOs first, then the SYNC, then the TPDOs, in the
//! order the tap records them.

use std::time::Duration;

use proto::can::CanFrame;
use proto::canopen::cob_id::{Cob, Function};
use proto::canopen::sync::SyncFrame;
use proto::nord::can::{cycle_period_us, pdo_data, pdo_words, InverterSeries, SystemBusAddress};
use proto::nord::{Family, Inverter, Product};

use super::frame;
use crate::pdo_image::{read_words, PdoImage};

/// How early, in parts of the cycle, words may come and still be carried: a tenth (see the
/// module documentation).
const EARLY: u32 = 10;

/// The series of the inverters on `product`'s system bus: SK 5x0P behind the SK 550P (BU 0620
/// §2.1), SK 54xE behind a bus module (`crate::can`'s choice).
pub(super) fn series(product: Product) -> InverterSeries {
    match product.family() {
        Family::Integrated => InverterSeries::Sk5x0p,
        Family::Module => InverterSeries::Sk54xe,
    }
}

/// The process data of the gateway's inverters, FI 1 first.
#[derive(Debug)]
pub(crate) struct ProcessData {
    product: Product,
    series: InverterSeries,
    links: Vec<Link>,
    timer: Timer,
}

/// The gateway and one inverter's node.
#[derive(Debug)]
struct Link {
    /// The node's side: what its RPDOs brought.
    node: PdoImage,
    /// The status word and actual values of the last TPDOs the gateway received from the node
    /// (0 before any).
    received: [u16; 6],
}

/// The gateway's cycle timer.
#[derive(Debug)]
enum Timer {
    /// No cycle yet: the first words start one.
    Idle,
    /// The last cycle.
    Ran(Cycle),
}

#[derive(Debug)]
struct Cycle {
    /// When the words that started it came.
    at: Duration,
    /// The timer's tick it stands for: when it went on the bus, and from which the next one
    /// is due.
    tick: Duration,
    /// The inverters it carried.
    carried: Vec<Inverter>,
}

/// Where an inverter's words at a time stand.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Slot {
    /// They start a cycle, standing for the timer's tick at this time.
    Opens(Duration),
    /// They join the cycle that started at the same time.
    Joins,
    /// No cycle is due: they wait.
    Waits,
}

/// One inverter's share of a cycle: the frames the gateway and its node exchanged.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct Share {
    /// When the cycle went on the bus: the timer's tick it stands for.
    pub(crate) at: Duration,
    /// The gateway's RPDOs to the node.
    pub(crate) rpdos: Vec<CanFrame>,
    /// The cycle's SYNC, with the share of the inverter that started the cycle.
    pub(crate) sync: Option<CanFrame>,
    /// The node's TPDOs.
    pub(crate) tpdos: Vec<CanFrame>,
}

/// What the field bus's words for one inverter came to.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Exchange {
    /// The frames, when a cycle carried the words; `None` while they wait.
    pub(crate) share: Option<Share>,
    /// What the field bus gets: the status word and actual values of the last TPDOs received.
    pub(crate) answer: [u16; 6],
}

impl ProcessData {
    /// The process data of `product`'s `inverters` inverters.
    pub(crate) fn new(product: Product, inverters: u8) -> ProcessData {
        let series = series(product);
        ProcessData {
            product,
            series,
            links: (0..inverters)
                .map(|_| Link {
                    node: PdoImage::new(series),
                    received: [0; 6],
                })
                .collect(),
            timer: Timer::Idle,
        }
    }

    /// What the field bus gets for FI `fi` while its words do not reach the node: the last
    /// TPDOs' words.
    pub(crate) fn received(&self, fi: Inverter) -> [u16; 6] {
        self.links
            .get(usize::from(fi.get()) - 1)
            .map_or([0; 6], |l| l.received)
    }

    /// Where FI `fi`'s words at `now` stand. `pause_us`: P153 [-02], a least time between two
    /// cycles beside the update cycle.
    fn slot(&self, fi: Inverter, pause_us: u32, now: Duration) -> Slot {
        let Timer::Ran(last) = &self.timer else {
            return Slot::Opens(now);
        };
        match now.cmp(&last.at) {
            std::cmp::Ordering::Equal if last.carried.contains(&fi) => return Slot::Waits,
            std::cmp::Ordering::Equal => return Slot::Joins,
            // A clock that went back (a new run on the same device): the timer starts afresh.
            std::cmp::Ordering::Less => return Slot::Opens(now),
            std::cmp::Ordering::Greater => {}
        }
        let carried = u8::try_from(last.carried.len()).unwrap_or(u8::MAX);
        let period_us = cycle_period_us(self.product, self.series, carried).max(pause_us);
        let period = Duration::from_micros(u64::from(period_us));
        let due = last.tick + period;
        if now + period / EARLY >= due {
            Slot::Opens(now.max(due))
        } else {
            Slot::Waits
        }
    }

    /// The field bus brings FI `fi`'s control word and setpoints (`words`, six, 0 where it has
    /// none) at `now`: when a cycle is due (or under way at `now`), the RPDOs to its node, the
    /// cycle's SYNC, at which the node gives the words to `drive` (the inverter's drive, at the
    /// cycle's time: the status word and actual values it answers), and the node's TPDOs, read
    /// back. The cycle's time is the timer's tick the words stand for: `now`, or a little later
    /// for words that came a little early (the module documentation's tolerance), so that the
    /// SYNCs are at least the update cycle apart.
    pub(crate) fn exchange(
        &mut self,
        fi: Inverter,
        words: &[u16; 6],
        pause_us: u32,
        now: Duration,
        drive: impl FnOnce(u16, &[u16], Duration) -> [u16; 6],
    ) -> Exchange {
        let slot = self.slot(fi, pause_us, now);
        let series = self.series;
        let Some(link) = self.links.get_mut(usize::from(fi.get()) - 1) else {
            return Exchange {
                share: None,
                answer: [0; 6],
            };
        };
        match slot {
            Slot::Waits => {
                return Exchange {
                    share: None,
                    answer: link.received,
                }
            }
            Slot::Joins => {
                if let Timer::Ran(cycle) = &mut self.timer {
                    cycle.carried.push(fi);
                }
            }
            Slot::Opens(tick) => {
                self.timer = Timer::Ran(Cycle {
                    at: now,
                    tick,
                    carried: vec![fi],
                });
            }
        }
        let at = match &self.timer {
            Timer::Ran(cycle) => cycle.tick,
            Timer::Idle => now,
        };
        let opens = matches!(slot, Slot::Opens(_));
        let node = SystemBusAddress::inverter(fi).get();
        let mut share = Share {
            at,
            ..Share::default()
        };
        for number in [1, 2] {
            let rpdo = Function::Rpdo { number };
            let Some(frame) = pdo_data(rpdo, series, words).and_then(|d| frame(rpdo, node, &d))
            else {
                continue;
            };
            // The node reads its RPDO from the bytes. The gateway's are as long as their
            // mapping: a node that refused one would not have started, and would answer no
            // SYNC.
            let _ = link.node.receive(rpdo, frame.data());
            share.rpdos.push(frame);
        }
        share.sync = opens
            .then(|| frame(Function::Sync, 0, &SyncFrame::default().emit()))
            .flatten();
        share.tpdos = link.node.sync(node, |control, setpoints| {
            Some(drive(control, setpoints, at))
        });
        // The gateway reads the status word and actual values from the TPDOs' bytes.
        if let Some(got) = read_back(series, node, &share.tpdos) {
            link.received = got;
        }
        Exchange {
            share: Some(share),
            answer: link.received,
        }
    }
}

/// The status word and actual values node `node`'s TPDOs of one cycle carry, `None` unless
/// every TPDO that carries words of `series` (PDO 1, and PDO 2 for five values) was read from
/// them: the field bus gets one cycle's words or keeps the last ones, never the status and
/// values 1–3 of one cycle beside values 4–5 of an earlier one.
fn read_back(series: InverterSeries, node: u8, tpdos: &[CanFrame]) -> Option<[u16; 6]> {
    let mut got = [0; 6];
    let mut read = [false; 2];
    for tpdo in tpdos {
        let Some(cob) = Cob::classify(tpdo.id()).filter(|c| c.node == node) else {
            continue;
        };
        let Function::Tpdo {
            number: number @ (1 | 2),
        } = cob.function
        else {
            continue;
        };
        if read_words(cob.function, series, tpdo.data(), &mut got).is_ok() {
            read[usize::from(number) - 1] = true;
        }
    }
    let mapped = |number: u8| pdo_words(Function::Tpdo { number }, series).is_some();
    (1..=2u8)
        .all(|number| !mapped(number) || read[usize::from(number) - 1])
        .then_some(got)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::system_bus::hex;

    fn fi(n: i64) -> Inverter {
        Inverter::new(n).unwrap()
    }

    fn ms(t: u64) -> Duration {
        Duration::from_millis(t)
    }

    /// A drive that answers the control word + 1 as its status and the setpoints as actual
    /// values, and records what it took.
    fn echo(
        taken: &mut Vec<(u16, Vec<u16>)>,
    ) -> impl FnMut(u16, &[u16], Duration) -> [u16; 6] + '_ {
        move |control, setpoints, _| {
            taken.push((control, setpoints.to_vec()));
            let mut answer = [control.wrapping_add(1), 0, 0, 0, 0, 0];
            for (d, s) in answer[1..].iter_mut().zip(setpoints) {
                *d = *s;
            }
            answer
        }
    }

    #[test]
    fn a_cycle_is_rpdos_a_sync_and_tpdos_at_the_nodes_cob_ids() {
        // FI 3 behind an SK TU4-POL: node 36 (24h); SK 54xE, five values, PDO 2 too.
        let mut pd = ProcessData::new(Product::Tu4Pol, 4);
        let mut taken = Vec::new();
        let words = [0x047E, 0x2000, 1, 2, 3, 4];
        let done = pd.exchange(fi(3), &words, 0, ms(0), echo(&mut taken));
        let share = done.share.unwrap();
        assert_eq!(
            hex(&share.rpdos),
            ["224 7E 04 00 20 01 00 02 00", "324 03 00 04 00"]
        );
        assert_eq!(share.sync.map(|s| s.id()), Some(0x080));
        assert_eq!(
            hex(&share.tpdos),
            ["1A4 7F 04 00 20 01 00 02 00", "2A4 03 00 04 00"]
        );
        // The drive took what the RPDOs carried; the field bus gets what the TPDOs carried.
        assert_eq!(taken, [(0x047E, vec![0x2000, 1, 2, 3, 4])]);
        assert_eq!(done.answer, [0x047F, 0x2000, 1, 2, 3, 4]);
        // Behind the SK 550P, FI 2's node is 34 (22h); an SK 5x0P has five values too.
        let mut pd = ProcessData::new(Product::Sk550p, 2);
        let share = pd
            .exchange(fi(2), &words, 0, ms(0), echo(&mut taken))
            .share
            .unwrap();
        let ids: Vec<u16> = [share.rpdos, share.sync.into_iter().collect(), share.tpdos]
            .concat()
            .iter()
            .map(CanFrame::id)
            .collect();
        assert_eq!(ids, [0x222, 0x322, 0x080, 0x1A2, 0x2A2]);
    }

    #[test]
    fn inverters_of_one_field_bus_frame_share_the_cycles_sync() {
        let mut pd = ProcessData::new(Product::Tu3Eip, 2);
        let mut taken = Vec::new();
        let words = [0x047E, 0, 0, 0, 0, 0];
        let first = pd.exchange(fi(1), &words, 0, ms(0), echo(&mut taken));
        let second = pd.exchange(fi(2), &words, 0, ms(0), echo(&mut taken));
        assert!(first.share.unwrap().sync.is_some());
        let second = second.share.unwrap();
        assert_eq!((second.sync, second.tpdos.len()), (None, 2));
        // The same inverter again at the same time waits for the next cycle.
        let again = pd.exchange(fi(2), &[0x0406, 0, 0, 0, 0, 0], 0, ms(0), echo(&mut taken));
        assert_eq!((again.share, again.answer[0]), (None, 0x047F));
        assert_eq!(taken.len(), 2);
    }

    #[test]
    fn words_faster_than_the_update_cycle_wait_and_the_status_lags() {
        // An RPI of 4 ms, the update cycle 5 ms: the words of 4 ms wait; the drive takes the
        // words of 8 ms at the next cycle. Until then the field bus gets the status the TPDOs
        // of the cycle at 0 ms carried.
        let mut pd = ProcessData::new(Product::Tu4Eip, 1);
        let mut taken = Vec::new();
        let mut answers = Vec::new();
        for (t, control) in [(0, 0x0406), (4, 0x0407), (8, 0x040F), (12, 0x047F)] {
            let words = [control, 0, 0, 0, 0, 0];
            let done = pd.exchange(fi(1), &words, 0, ms(t), echo(&mut taken));
            answers.push((t, done.share.is_some(), done.answer[0]));
        }
        let controls: Vec<u16> = taken.iter().map(|(c, _)| *c).collect();
        assert_eq!(controls, [0x0406, 0x040F]);
        assert_eq!(
            answers,
            [
                (0, true, 0x0407),
                (4, false, 0x0407),
                (8, true, 0x0410),
                (12, false, 0x0410)
            ]
        );
    }

    #[test]
    fn a_field_bus_as_fast_as_the_update_cycle_is_carried_every_time() {
        // An RPI of 5 ms jittering by tens of µs: every frame carried, each cycle at the
        // timer's tick, at least 5 ms after the last; one a millisecond early waits.
        let mut pd = ProcessData::new(Product::Tu4Eip, 1);
        let mut drove = Vec::new();
        let words = [0x047E, 0, 0, 0, 0, 0];
        let us = Duration::from_micros;
        let ticks: Vec<Option<Duration>> = [0, 4_990, 10_020, 14_980, 19_960, 23_900]
            .into_iter()
            .map(|t| {
                let drive = |_: u16, _: &[u16], at| {
                    drove.push(at);
                    [0; 6]
                };
                pd.exchange(fi(1), &words, 0, us(t), drive)
                    .share
                    .map(|s| s.at)
            })
            .collect();
        let expected = [0, 5_000, 10_020, 15_020, 20_020].map(|t| Some(us(t)));
        assert_eq!(ticks, [&expected[..], &[None]].concat());
        // The drive takes the words at the cycle's time.
        assert_eq!(drove, expected.map(Option::unwrap));
    }

    #[test]
    fn p153_spaces_the_cycles() {
        // P153 [-02] = 20 ms on an SK TU4: field-bus cycles every 4 ms, a system-bus cycle every
        // 20 ms (BU 2100 §7.1.1 p. 46).
        let mut pd = ProcessData::new(Product::Tu4Eip, 1);
        let mut taken = Vec::new();
        let words = [0x047E, 0, 0, 0, 0, 0];
        let syncs: Vec<u64> = (0..=44)
            .step_by(4)
            .filter(|t| {
                pd.exchange(fi(1), &words, 20_000, ms(*t), echo(&mut taken))
                    .share
                    .is_some_and(|s| s.sync.is_some())
            })
            .collect();
        assert_eq!(syncs, [0, 20, 40]);
    }

    #[test]
    fn the_field_bus_gets_one_cycles_tpdo_set_or_the_last_one() {
        // SK 54xE behind a module, node 32: the status word and values 1–3 in TPDO1, values 4–5
        // in TPDO2. A cycle whose TPDO2 did not come (or came short) is not half taken: its
        // status and values 1–3 beside the values 4–5 of an earlier cycle would be two cycles'.
        let series = InverterSeries::Sk54xe;
        let tpdo = |number, data: &[u8]| frame(Function::Tpdo { number }, 32, data).unwrap();
        let tpdo1 = tpdo(1, &[0x33, 0x00, 0x00, 0x20, 1, 0, 2, 0]);
        let tpdo2 = tpdo(2, &[3, 0, 4, 0]);
        assert_eq!(
            read_back(series, 32, &[tpdo1, tpdo2]),
            Some([0x0033, 0x2000, 1, 2, 3, 4])
        );
        assert_eq!(read_back(series, 32, &[tpdo1]), None);
        assert_eq!(read_back(series, 32, &[tpdo1, tpdo(2, &[3, 0])]), None);
        assert_eq!(read_back(series, 32, &[tpdo2]), None);
        // Another node's TPDO2 is not this node's.
        let other = frame(Function::Tpdo { number: 2 }, 34, &[3, 0, 4, 0]).unwrap();
        assert_eq!(read_back(series, 32, &[tpdo1, other]), None);
        // Three values: TPDO1 is the whole set.
        let three = tpdo(1, &[0x37, 0x00, 0x00, 0x20, 1, 0, 2, 0]);
        assert_eq!(
            read_back(InverterSeries::Sk2xxe, 32, &[three]),
            Some([0x0037, 0x2000, 1, 2, 0, 0])
        );
    }
}
