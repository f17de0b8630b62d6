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
//! - process data: the frames the gateway ([`super::ProcessData`]) and the nodes actually
//!   exchanged ([`Tap::cycle`]), per system-bus cycle each inverter's RPDO1 (and RPDO2 for
//!   five values), the one SYNC, and each inverter's TPDOs, in that order. When the cycles run
//!   (at the system bus's pace, a field bus faster than it having its words carried only at
//!   the next cycle) is the gateway's to say, not the tap's.
//!
//! Behind the SK 550P, FI 1 is the device itself (BU 0620 §2.1): only FI 2…8 are on the
//! system bus. The interface's own parameters never are.

use std::time::Duration;

use proto::can::CanFrame;
use proto::canopen::cob_id::Function;
use proto::canopen::sdo::{Abort, Expedited, InitiateData, SdoRequest, SdoResponse};
use proto::canopen::SdoAbortCode;
use proto::nord::can::SystemBusAddress;
use proto::nord::errors::SdoAbort;
use proto::nord::{Family, Inverter, Product};

use super::frame;
use super::process::Share;

/// What a PKW order did to a parameter, as the image of the system bus shows it.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Access<'a> {
    /// Read: the value's bytes, or the refusal.
    Read(Result<&'a [u8], SdoAbort>),
    /// Written with these bytes: done, or the refusal.
    Write(&'a [u8], Result<(), SdoAbort>),
}

/// The frames recorded so far, and the process-data cycle under way.
#[derive(Debug)]
pub(crate) struct Tap {
    product: Product,
    frames: Vec<(Duration, CanFrame)>,
    /// The cycle being gathered: when it went, the RPDOs, SYNC and TPDOs so far.
    cycle: Option<Cycle>,
    /// The last PKW order and answer recorded, per inverter (a PKW order repeats every
    /// field-bus cycle).
    orders: Vec<(Inverter, [u8; 8], [u8; 8])>,
}

/// The frames of one process-data cycle, gathered as the field bus hands the inverters' words
/// one by one: on the bus, all RPDOs go before the one SYNC, the TPDOs after it.
#[derive(Debug)]
struct Cycle {
    at: Duration,
    rpdos: Vec<CanFrame>,
    sync: Option<CanFrame>,
    tpdos: Vec<CanFrame>,
}

impl Tap {
    pub(crate) fn new(product: Product) -> Tap {
        Tap {
            product,
            frames: Vec::new(),
            cycle: None,
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
        self.close_cycle();
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
        self.close_cycle();
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

    /// One inverter's share of a process-data cycle, as the gateway and its node exchanged it.
    pub(crate) fn cycle(&mut self, share: &Share) {
        let at = share.at;
        if self.cycle.as_ref().is_some_and(|c| c.at != at) {
            self.close_cycle();
        }
        let cycle = self.cycle.get_or_insert_with(|| Cycle {
            at,
            rpdos: Vec::new(),
            sync: None,
            tpdos: Vec::new(),
        });
        cycle.rpdos.extend_from_slice(&share.rpdos);
        cycle.sync = cycle.sync.or(share.sync);
        cycle.tpdos.extend_from_slice(&share.tpdos);
    }

    /// The cycle gathered so far onto the bus: its RPDOs, the SYNC, its TPDOs.
    fn close_cycle(&mut self) {
        let Some(c) = self.cycle.take() else {
            return;
        };
        let at = c.at;
        self.frames.extend(
            c.rpdos
                .into_iter()
                .chain(c.sync)
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
    pub(crate) fn take(&mut self) -> Vec<(Duration, CanFrame)> {
        self.close_cycle();
        std::mem::take(&mut self.frames)
    }
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
            hex(&tap.take()),
            [
                "624 2B 66 20 01 FA 00 00 00",
                "5A4 60 66 20 01 00 00 00 00",
                "624 40 66 20 09 00 00 00 00",
                "5A4 80 66 20 09 11 00 09 06"
            ]
        );
    }

    #[test]
    fn a_cycles_frames_are_the_rpdos_the_sync_and_the_tpdos() {
        // Two FIs' shares of one cycle, as the gateway hands them one by one, then the next
        // cycle's.
        let f = |id: u16| CanFrame::new(id, &[0; 2]).unwrap();
        let share = |node: u16, sync: bool, at: Duration| Share {
            at,
            rpdos: vec![f(0x200 + node), f(0x300 + node)],
            sync: sync.then(|| CanFrame::new(0x080, &[]).unwrap()),
            tpdos: vec![f(0x180 + node), f(0x280 + node)],
        };
        let mut tap = Tap::new(Product::Tu4Pol);
        let ms = Duration::from_millis;
        for t in [0, 8] {
            tap.cycle(&share(0x20, true, ms(t)));
            tap.cycle(&share(0x22, false, ms(t)));
        }
        let frames = tap.take();
        let ids: Vec<u16> = frames.iter().map(|(_, f)| f.id()).collect();
        let cycle = [
            0x220, 0x320, 0x222, 0x322, 0x080, 0x1A0, 0x2A0, 0x1A2, 0x2A2,
        ];
        assert_eq!(ids, [cycle, cycle].concat());
        assert_eq!(frames[9].0, ms(8));
    }
}
