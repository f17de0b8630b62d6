//! The parameter data records of a NORD PROFINET device (BU 0620 §2.5.6, BU 0590 §4.2): the
//! parameter channel (PKW) carried by record services instead of a PPO.
//!
//! - Records 100 (the bus interface) and 101…108 (FI 1…8) hold one PKW telegram of 8 bytes
//!   (PKE with the parameter number + 1000, IND, PWE). A Write Request places an order, each
//!   Read Request asks for its answer: "Read Response (−)" until the order is processed, then
//!   "Read Response (+)" with the PKW answer (§2.5.6.1 figure 16). The (−) is the PROFIdrive
//!   record answer "state conflict" (DE 80 B5 00): the manuals print no bytes for it.
//! - Record 47 (SK TU3-PNT, BU 0590 §4.2.2.2): the order in the manual's own layout — order
//!   reference, order label, axis (0 = the module, 1 = the FI), PNU, IND, PWE — answered in the
//!   same layout with the response label.
//!
//! Which record reaches which unit from which slot is `proto::nord::pnio`'s.
//!
//! A new order always starts anew: the unit's parameter channel is cleared first, so the same
//! telegram written twice is processed twice (a record write is one order, not a repeated PPO).

use proto::nord::pkw::PkwRepr;
use proto::nord::pnio::{
    axis_target, busy_status, check_record_len, record_target, PnioError, Record47Repr,
    RecordTarget,
};
use proto::pnio::status::pniorw;
use proto::pnio::PnioStatus;

use crate::device::Device;
use crate::link::Unit;

/// An order written and not answered yet.
#[derive(Debug, Clone, Copy)]
struct Pending {
    index: u16,
    unit: Unit,
    order: PkwRepr,
    /// Record 47's order, whose layout the answer keeps.
    axis: Option<Record47Repr>,
}

/// The orders written and not yet answered, per record.
#[derive(Debug, Default, Clone)]
pub struct Records {
    pending: Vec<Pending>,
}

impl Records {
    /// A Write Request of `data` to record `index` at `slot`/`subslot`; the error is the PNIO
    /// status of the IODWrite response.
    pub fn write(
        &mut self,
        device: &mut Device,
        slot: u16,
        subslot: u16,
        index: u16,
        data: &[u8],
    ) -> Result<(), PnioStatus> {
        let refuse = |e: PnioError| e.record_status(true);
        let target = target(device, slot, subslot, index).map_err(refuse)?;
        check_record_len(index, data.len()).map_err(refuse)?;
        let (unit, order, axis) = match target {
            RecordTarget::ByAxis => {
                let r = Record47Repr::parse(data).map_err(refuse)?;
                (
                    unit_of(axis_target(r.axis).map_err(refuse)?),
                    r.pkw(),
                    Some(r),
                )
            }
            t => (
                unit_of(t),
                PkwRepr::parse(data).map_err(|_| status(true))?,
                None,
            ),
        };
        // A new order: the channel is cleared, then the order placed.
        device
            .parameter_order(unit, PkwRepr::default())
            .and_then(|_| device.parameter_order(unit, order))
            .map_err(|_| PnioStatus::record(true, pniorw::INVALID_INDEX))?;
        self.pending.retain(|p| p.index != index);
        self.pending.push(Pending {
            index,
            unit,
            order,
            axis,
        });
        Ok(())
    }

    /// A Read Request of record `index` at `slot`/`subslot`: the answer's bytes, or the PNIO
    /// status of a negative IODRead response ("Read Response (−)" while the order is
    /// processed, and when no order was written).
    pub fn read(
        &mut self,
        device: &mut Device,
        slot: u16,
        subslot: u16,
        index: u16,
    ) -> Result<Vec<u8>, PnioStatus> {
        target(device, slot, subslot, index).map_err(|e| e.record_status(false))?;
        let at = self
            .pending
            .iter()
            .position(|p| p.index == index)
            .ok_or(busy_status())?;
        let p = self.pending[at];
        let answer = device
            .parameter_order(p.unit, p.order)
            .map_err(|_| status(false))?;
        if answer.ak == 0 {
            return Err(busy_status());
        }
        self.pending.remove(at);
        match p.axis {
            Some(order) => {
                let r = Record47Repr {
                    label: answer.ak,
                    pnu: answer.pnu,
                    ind: answer.ind,
                    pwe: answer.pwe,
                    ..order
                };
                let mut out = vec![0; r.buffer_len()];
                r.emit(&mut out).map_err(|_| status(false))?;
                Ok(out)
            }
            None => {
                let mut out = vec![0; 8];
                answer.emit(&mut out).map_err(|_| status(false))?;
                Ok(out)
            }
        }
    }
}

/// The target of a record on this device: the product's rule, and an inverter the device
/// has (FI 9 of a device with 8, FI 3 of one with 2, are no index of it).
fn target(device: &Device, slot: u16, subslot: u16, index: u16) -> Result<RecordTarget, PnioError> {
    let config = device.config();
    let t = record_target(config.product, slot, subslot, index)?;
    match t {
        RecordTarget::Inverter(fi) if fi.get() > config.inverters => {
            Err(PnioError::UnknownRecord(index))
        }
        t => Ok(t),
    }
}

fn unit_of(target: RecordTarget) -> Unit {
    match target {
        RecordTarget::Inverter(fi) => Unit::Inverter(fi),
        RecordTarget::Interface | RecordTarget::ByAxis => Unit::Interface,
    }
}

/// A read or write error of the application (the order could not be handled at all).
fn status(write: bool) -> PnioStatus {
    PnioStatus::record(
        write,
        if write {
            pniorw::WRITE_ERROR
        } else {
            pniorw::READ_ERROR
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::device::DeviceConfig;
    use proto::nord::Product;

    fn device(product: Product, answer_delay: u32) -> Device {
        Device::new(DeviceConfig {
            answer_delay,
            ..DeviceConfig::new(product)
        })
    }

    /// BU 0620 §2.5.6.4: P102 index 1 = 2.5 s through record 101, "24 4E 01 00 00 00 00 FA";
    /// the read answers response label 1 with the value written (the manual prints PWE 0
    /// there: the suites record that as an erratum).
    #[test]
    fn the_p102_write_example_lands_through_record_101() {
        let mut d = device(Product::Sk550p, 2);
        let mut r = Records::default();
        let order = [0x24, 0x4E, 0x01, 0x00, 0x00, 0x00, 0x00, 0xFA];
        r.write(&mut d, 3, 1, 101, &order).unwrap();
        // Read Response (−) while the order is processed (two cycles here).
        assert_eq!(
            r.read(&mut d, 3, 1, 101),
            Err(PnioStatus::new(0xDE, 0x80, 0xB5, 0))
        );
        let answer = r.read(&mut d, 3, 1, 101).unwrap();
        assert_eq!(answer[..4], [0x14, 0x4E, 0x01, 0x00]);
        assert_eq!(u16::from_be_bytes([answer[6], answer[7]]), 250);
        // Answered: a further read has no order.
        assert!(r.read(&mut d, 3, 1, 101).is_err());
    }

    /// Each write is one order: reading P102 again after a write reads the new value.
    #[test]
    fn the_same_order_written_twice_is_processed_twice() {
        let mut d = device(Product::Sk550p, 1);
        let mut r = Records::default();
        let read_p102 = [0x14, 0x4E, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00];
        r.write(&mut d, 3, 1, 101, &read_p102).unwrap();
        let first = r.read(&mut d, 3, 1, 101).unwrap();
        let write = [0x74, 0x4E, 0x00, 0x00, 0x00, 0x00, 0x01, 0x2C];
        r.write(&mut d, 3, 1, 101, &write).unwrap();
        let w = r.read(&mut d, 3, 1, 101).unwrap();
        assert_eq!(w[7], 0x2C, "{w:02X?}");
        r.write(&mut d, 3, 1, 101, &read_p102).unwrap();
        let again = r.read(&mut d, 3, 1, 101).unwrap();
        assert_ne!(first, again);
        assert_eq!(again[6..], [0x01, 0x2C]);
    }

    #[test]
    fn wrong_records_and_lengths_get_their_pniorw_codes() {
        let mut d = device(Product::Sk550p, 1);
        let mut r = Records::default();
        let order = [0x16, 0x4E, 0, 0, 0, 0, 0, 0];
        // FI 9 does not exist: record 109 is no index of the device.
        assert_eq!(
            r.write(&mut d, 3, 1, 109, &order),
            Err(PnioStatus::new(0xDF, 0x80, 0xB0, 0))
        );
        assert_eq!(
            r.write(&mut d, 3, 1, 101, &order[..7]),
            Err(PnioStatus::new(0xDF, 0x80, 0xB1, 0))
        );
        // Record 47 is the SK TU3-PNT's only.
        assert_eq!(
            r.read(&mut d, 3, 1, 47),
            Err(PnioStatus::new(0xDE, 0x80, 0xB0, 0))
        );
        // Slot 1 takes no records (BU 0620 figure 16: slots 3…10).
        assert_eq!(
            r.write(&mut d, 1, 1, 101, &order),
            Err(PnioStatus::new(0xDF, 0x80, 0xB2, 0))
        );
        // A device with two inverters has no record 103.
        let mut two = Device::new(DeviceConfig {
            inverters: 2,
            ..DeviceConfig::new(Product::Sk550p)
        });
        assert_eq!(
            r.write(&mut two, 5, 1, 103, &order),
            Err(PnioStatus::new(0xDF, 0x80, 0xB0, 0))
        );
    }

    /// BU 0590 §4.2.2.2: record 47 with axis 1 reads P102 of the FI, the reference mirrored.
    #[test]
    fn record_47_carries_reference_and_axis() {
        let mut d = device(Product::Tu3Pnt, 1);
        let mut r = Records::default();
        // ref 5Ah, AK 1, axis 1, PNU 1102 = 044Eh, IND 0, PWE 0.
        let order = [0x5A, 0x01, 0x01, 0x04, 0x4E, 0, 0, 0, 0, 0, 0];
        r.write(&mut d, 3, 1, 47, &order).unwrap();
        let answer = r.read(&mut d, 3, 1, 47).unwrap();
        assert_eq!(answer[..5], [0x5A, 0x01, 0x01, 0x04, 0x4E]);
        assert_eq!(answer.len(), 11);
        // Axis 2 does not exist.
        let mut bad = order;
        bad[2] = 2;
        assert_eq!(
            r.write(&mut d, 3, 1, 47, &bad),
            Err(PnioStatus::new(0xDF, 0x80, 0xB8, 0))
        );
    }
}
