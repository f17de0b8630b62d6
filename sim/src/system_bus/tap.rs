//! The recorder of the system bus's frames, while a tap is attached
//! ([`crate::device::Device::tap_system_bus`]), so that a run can see both sides of the gateway
//! (`observe: { what: system-bus }`):
//! - a parameter of FI n read or written over CIP, CoE or POWERLINK SDO, and a PKW order to
//!   FI n that reads or changes a value kept in EEPROM (a PPO or a parameter data record): the
//!   frames the gateway ([`super::Gateway`]) and FI n's node actually exchanged
//!   ([`Tap::exchanged`]);
//! - a PKW order the gateway does not carry (a change in RAM only, labels 11–14): an image
//!   ([`Tap::parameter`]), the expedited SDO download a gateway following the project's CANopen
//!   layout would send for it and the node's answer, a refusal abort 0800 0000h "general
//!   error" (the manuals map no PKW error number to an abort code). The order itself is served
//!   on the inverter's store by the parameter channel: a node has no RAM-only download;
//! - process data: an image too. Per system-bus cycle, each inverter's RPDO1 (and RPDO2 for
//!   five values), one SYNC, and each inverter's TPDOs. A cycle starts when the field bus
//!   brings an inverter's words and the last cycle is at least the update cycle of the
//!   inverters it carried old (`proto::nord::can::cycle_period_us`): a field bus faster than
//!   the system bus (an RPI of 4 ms) has its words carried every other time.
//!
//! Behind the SK 550P, FI 1 is the device itself (BU 0620 §2.1): only FI 2…8 are on the
//! system bus. The interface's own parameters never are.

use std::time::Duration;

use proto::can::CanFrame;
use proto::canopen::cob_id::Function;
use proto::canopen::sdo::{Abort, Expedited, InitiateData, SdoRequest, SdoResponse};
use proto::canopen::SdoAbortCode;
use proto::nord::can::{pdo_data, process_values, InverterSeries, SystemBusAddress};
use proto::nord::errors::SdoAbort;
use proto::nord::{Family, Inverter, Product};

/// What a PKW order did to a parameter, as the image of the system bus shows it.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Access<'a> {
    /// Read: the value's bytes, or the refusal.
    Read(Result<&'a [u8], SdoAbort>),
    /// Written with these bytes: done, or the refusal.
    Write(&'a [u8], Result<(), SdoAbort>),
}

/// The frames recorded so far, and the cycle under way.
#[derive(Debug)]
pub(crate) struct Tap {
    product: Product,
    series: InverterSeries,
    frames: Vec<(Duration, CanFrame)>,
    /// The cycle being gathered: when it started, the RPDOs and TPDOs so far.
    cycle: Option<Cycle>,
    /// When the last cycle started, and how many inverters it carried.
    last_cycle: Option<(Duration, u8)>,
    /// The last PKW order and answer recorded, per inverter (a PKW order repeats every
    /// field-bus cycle).
    orders: Vec<(Inverter, [u8; 8], [u8; 8])>,
}

#[derive(Debug)]
struct Cycle {
    at: Duration,
    inverters: Vec<Inverter>,
    rpdos: Vec<CanFrame>,
    tpdos: Vec<CanFrame>,
}

impl Tap {
    pub(crate) fn new(product: Product) -> Tap {
        let series = match product.family() {
            Family::Integrated => InverterSeries::Sk5x0p,
            Family::Module => InverterSeries::Sk54xe,
        };
        Tap {
            product,
            series,
            frames: Vec::new(),
            cycle: None,
            last_cycle: None,
            orders: Vec::new(),
        }
    }

    /// Whether `order` with `answer` is new for FI `fi` (and remembers it).
    pub(crate) fn first_answer(&mut self, fi: Inverter, order: [u8; 8], answer: [u8; 8]) -> bool {
        match self.orders.iter_mut().find(|(f, ..)| *f == fi) {
            Some(seen) if (seen.1, seen.2) == (order, answer) => false,
            Some(seen) => {
                *seen = (fi, order, answer);
                true
            }
            None => {
                self.orders.push((fi, order, answer));
                true
            }
        }
    }

    /// The node of `fi` on the system bus; `None` for the SK 550P's own FI 1.
    fn node(&self, fi: Inverter) -> Option<u8> {
        if self.product.family() == Family::Integrated && fi.get() == 1 {
            return None;
        }
        Some(SystemBusAddress::inverter(fi).get())
    }

    /// Frames the gateway and a node exchanged at `now`, in order.
    pub(crate) fn exchanged(&mut self, frames: &[CanFrame], now: Duration) {
        if frames.is_empty() {
            return;
        }
        self.close_cycle(now);
        self.frames.extend(frames.iter().map(|f| (now, *f)));
    }

    /// The image of the parameter access of a PKW order the gateway does not carry, to FI `fi`
    /// at `index`:`sub`, at `now`.
    pub(crate) fn parameter(
        &mut self,
        fi: Inverter,
        index: u16,
        sub: u8,
        access: Access<'_>,
        now: Duration,
    ) {
        let Some(node) = self.node(fi) else {
            return;
        };
        self.close_cycle(now);
        let refuse = |code: SdoAbort| {
            SdoResponse::Abort(Abort {
                index,
                sub,
                code: SdoAbortCode(code.0),
            })
        };
        let expedited = |b: &[u8]| Expedited::new(b).ok().map(InitiateData::Expedited);
        let (request, response) = match access {
            Access::Read(result) => (
                SdoRequest::InitiateUpload { index, sub },
                match result {
                    Ok(b) => match expedited(b) {
                        Some(data) => SdoResponse::InitiateUpload { index, sub, data },
                        None => return,
                    },
                    Err(code) => refuse(code),
                },
            ),
            Access::Write(bytes, result) => {
                let Some(data) = expedited(bytes) else {
                    return;
                };
                (
                    SdoRequest::InitiateDownload { index, sub, data },
                    match result {
                        Ok(()) => SdoResponse::InitiateDownload { index, sub },
                        Err(code) => refuse(code),
                    },
                )
            }
        };
        self.push(Function::SdoRx, node, &request.emit(), now);
        self.push(Function::SdoTx, node, &response.emit(), now);
    }

    /// FI `fi`'s words of one field-bus cycle at `now`: the control word and setpoints it
    /// got, the status word and actual values it answered. `pause_us`: the module's P153 [-02]
    /// "TxPDO Inhibit Time" (0 without one), a least time between two cycles beside the
    /// update cycle.
    pub(crate) fn process(
        &mut self,
        fi: Inverter,
        sent: &[u16],
        answer: &[u16],
        pause_us: u32,
        now: Duration,
    ) {
        let Some(node) = self.node(fi) else {
            return;
        };
        if self.cycle.as_ref().is_some_and(|c| c.at != now) {
            self.close_cycle(now);
        }
        if self.cycle.is_none() {
            if let Some((t, carried)) = self.last_cycle {
                let period = proto::nord::can::cycle_period_us(self.product, self.series, carried)
                    .max(pause_us);
                if now < t + Duration::from_micros(u64::from(period)) {
                    return;
                }
            }
            self.last_cycle = Some((now, 1));
            self.cycle = Some(Cycle {
                at: now,
                inverters: Vec::new(),
                rpdos: Vec::new(),
                tpdos: Vec::new(),
            });
        }
        let series = self.series;
        let Some(cycle) = self.cycle.as_mut() else {
            return;
        };
        if cycle.inverters.contains(&fi) {
            return;
        }
        cycle.inverters.push(fi);
        if let Some((_, carried)) = self.last_cycle.as_mut() {
            *carried = cycle.inverters.len() as u8;
        }
        let values = usize::from(process_values(series));
        let mut out = [0u16; 6];
        let mut back = [0u16; 6];
        for (d, w) in out.iter_mut().zip(sent).take(1 + values) {
            *d = *w;
        }
        for (d, w) in back.iter_mut().zip(answer).take(1 + values) {
            *d = *w;
        }
        for number in [1, 2] {
            for (function, words, to) in [
                (Function::Rpdo { number }, &out, &mut cycle.rpdos),
                (Function::Tpdo { number }, &back, &mut cycle.tpdos),
            ] {
                let Some(data) = pdo_data(function, series, words) else {
                    continue;
                };
                if let Some(f) = frame(function, node, &data) {
                    to.push(f);
                }
            }
        }
    }

    /// The cycle gathered so far onto the bus: its RPDOs, the SYNC, its TPDOs.
    fn close_cycle(&mut self, _now: Duration) {
        let Some(c) = self.cycle.take() else {
            return;
        };
        let sync = CanFrame::new(0x080, &[]).ok();
        let at = c.at;
        self.frames.extend(
            c.rpdos
                .into_iter()
                .chain(sync)
                .chain(c.tpdos)
                .map(|f| (at, f)),
        );
    }

    fn push(&mut self, function: Function, node: u8, data: &[u8], now: Duration) {
        if let Some(f) = frame(function, node, data) {
            self.frames.push((now, f));
        }
    }

    /// The frames recorded since the last call, each with its time.
    pub(crate) fn take(&mut self, now: Duration) -> Vec<(Duration, CanFrame)> {
        self.close_cycle(now);
        std::mem::take(&mut self.frames)
    }
}

fn frame(function: Function, node: u8, data: &[u8]) -> Option<CanFrame> {
    CanFrame::new(function.cob_id(node).ok()?, data).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fi(n: i64) -> Inverter {
        Inverter::new(n).unwrap()
    }

    fn hex(frames: &[(Duration, CanFrame)]) -> Vec<String> {
        frames
            .iter()
            .map(|(_, f)| {
                let data: Vec<String> = f.data().iter().map(|b| format!("{b:02X}")).collect();
                format!("{:03X} {}", f.id(), data.join(" "))
                    .trim()
                    .to_string()
            })
            .collect()
    }

    #[test]
    fn a_parameter_write_is_an_sdo_download_to_the_inverters_node() {
        let mut tap = Tap::new(Product::Tu4Eip);
        let ms = Duration::from_millis;
        tap.parameter(
            fi(3),
            0x2066,
            1,
            Access::Write(&250i16.to_le_bytes(), Ok(())),
            ms(1),
        );
        tap.parameter(
            fi(3),
            0x2066,
            9,
            Access::Read(Err(SdoAbort(0x0609_0011))),
            ms(2),
        );
        assert_eq!(
            hex(&tap.take(ms(3))),
            [
                "624 2B 66 20 01 FA 00 00 00",
                "5A4 60 66 20 01 00 00 00 00",
                "624 40 66 20 09 00 00 00 00",
                "5A4 80 66 20 09 11 00 09 06"
            ]
        );
    }

    #[test]
    fn process_data_are_rpdos_a_sync_and_tpdos_once_per_update_cycle() {
        let mut tap = Tap::new(Product::Tu4Pol);
        let ms = Duration::from_millis;
        let sent = [0x047E, 0x2000, 0, 0, 0, 0];
        let back = [0x0B31, 0, 0, 0, 0, 0];
        // Two FIs in one field-bus cycle, the next field-bus cycle 4 ms later (too soon), the
        // one after at 8 ms.
        for t in [0, 4, 8] {
            tap.process(fi(1), &sent, &back, 5000, ms(t));
            tap.process(fi(2), &sent, &back, 5000, ms(t));
        }
        let frames = tap.take(ms(9));
        let ids: Vec<u16> = frames.iter().map(|(_, f)| f.id()).collect();
        let cycle = [
            0x220, 0x320, 0x222, 0x322, 0x080, 0x1A0, 0x2A0, 0x1A2, 0x2A2,
        ];
        assert_eq!(ids, [cycle, cycle].concat());
        assert_eq!(frames[9].0, ms(8));
        assert_eq!(hex(&frames[..1]), ["220 7E 04 00 20 00 00 00 00"]);
        // Behind the SK 550P, FI 1 is the device itself.
        let mut tap = Tap::new(Product::Sk550p);
        tap.process(fi(1), &sent, &back, 0, ms(0));
        assert!(tap.take(ms(1)).is_empty());
    }

    #[test]
    fn p153_spaces_the_cycles() {
        // P153 [-02] = 20 ms on an SK TU4: field-bus cycles every 4 ms, a system-bus cycle every
        // 20 ms (BU 2100 §7.1.1 p. 46).
        let mut tap = Tap::new(Product::Tu4Eip);
        let ms = Duration::from_millis;
        let words = [0x047E, 0, 0, 0, 0, 0];
        for t in (0..=44).step_by(4) {
            tap.process(fi(1), &words, &words, 20_000, ms(t));
        }
        let syncs: Vec<Duration> = tap
            .take(ms(45))
            .into_iter()
            .filter(|(_, f)| f.id() == 0x080)
            .map(|(t, _)| t)
            .collect();
        assert_eq!(syncs, [ms(0), ms(20), ms(40)]);
    }
}
