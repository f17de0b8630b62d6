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
//! A new order always starts anew: the unit's parameter channel is cleared first, so the same
//! telegram written twice is processed twice (a record write is one order, not a repeated PPO).

use proto::nord::pkw::PkwRepr;
use proto::nord::{Inverter, Product};
use proto::pnio::status::pniorw;
use proto::pnio::PnioStatus;

use crate::device::Device;
use crate::link::{Unit, RECORD_FI1, RECORD_INTERFACE};

/// PROFIdrive's parameter access record (BU 0590 §4.2.2.2 "data record 47").
pub const RECORD_47: u16 = 47;
/// Bytes of a record 47 order: reference, label, axis, PNU (2), IND (2), PWE (4).
const RECORD_47_LEN: usize = 11;

/// The orders written and not yet answered, per record.
#[derive(Debug, Default, Clone)]
pub struct Records {
    /// Record 100..=108 (or 47) → the unit, the order, and record 47's reference byte.
    pending: Vec<(u16, Unit, PkwRepr, u8)>,
}

impl Records {
    /// A Write Request of `data` to record `index`; the error is the PNIO status of the
    /// IODWrite response.
    pub fn write(
        &mut self,
        device: &mut Device,
        index: u16,
        data: &[u8],
    ) -> Result<(), PnioStatus> {
        let deny = |code1| Err(PnioStatus::record(true, code1));
        let (unit, order, reference) = match index {
            RECORD_47 if device.config().product == Product::Tu3Pnt => {
                if data.len() != RECORD_47_LEN {
                    return deny(pniorw::WRITE_LENGTH);
                }
                let unit = match data[2] {
                    0 => Unit::Interface,
                    1 => Unit::Inverter(Inverter::new(1).map_err(|_| status(true))?),
                    _ => return deny(pniorw::INVALID_PARAMETER),
                };
                let mut pkw = [0u8; 8];
                pkw[0] = data[1] << 4 | data[3] & 0x0F;
                pkw[1..].copy_from_slice(&data[4..]);
                let order = PkwRepr::parse(&pkw).map_err(|_| status(true))?;
                (unit, order, data[0])
            }
            _ => {
                let unit = unit_of(device, index).ok_or(status_index(true))?;
                if data.len() != 8 {
                    return deny(pniorw::WRITE_LENGTH);
                }
                let order = PkwRepr::parse(data).map_err(|_| status(true))?;
                (unit, order, 0)
            }
        };
        // A new order: the channel is cleared, then the order placed.
        device
            .parameter_order(unit, PkwRepr::default())
            .and_then(|_| device.parameter_order(unit, order))
            .map_err(|_| status_index(true))?;
        self.pending.retain(|p| p.0 != index);
        self.pending.push((index, unit, order, reference));
        Ok(())
    }

    /// A Read Request of record `index`: the answer's bytes, or the PNIO status of a
    /// negative IODRead response ("Read Response (−)" while the order is processed).
    pub fn read(&mut self, device: &mut Device, index: u16) -> Result<Vec<u8>, PnioStatus> {
        if index != RECORD_47 || device.config().product != Product::Tu3Pnt {
            unit_of(device, index).ok_or(status_index(false))?;
        }
        let Some(at) = self.pending.iter().position(|p| p.0 == index) else {
            // No order written: nothing to answer (yet).
            return Err(PnioStatus::record(false, pniorw::STATE_CONFLICT));
        };
        let (_, unit, order, reference) = self.pending[at];
        let answer = device
            .parameter_order(unit, order)
            .map_err(|_| status(false))?;
        if answer.ak == 0 {
            return Err(PnioStatus::record(false, pniorw::STATE_CONFLICT));
        }
        self.pending.remove(at);
        let mut pkw = [0u8; 8];
        answer.emit(&mut pkw).map_err(|_| status(false))?;
        Ok(if index == RECORD_47 {
            let mut out = vec![reference, pkw[0] >> 4, data_axis(unit), pkw[0] & 0x0F];
            out.extend_from_slice(&pkw[1..]);
            out
        } else {
            pkw.to_vec()
        })
    }
}

/// Record 47's axis byte of a unit.
fn data_axis(unit: Unit) -> u8 {
    match unit {
        Unit::Interface => 0,
        Unit::Inverter(_) => 1,
    }
}

/// The unit record `index` addresses: 100 the interface, 101…100+n the inverters present.
fn unit_of(device: &Device, index: u16) -> Option<Unit> {
    let inverters = u16::from(device.config().inverters);
    let (interface, fi1) = (u16::from(RECORD_INTERFACE), u16::from(RECORD_FI1));
    if index == interface {
        return Some(Unit::Interface);
    }
    let n = index.checked_sub(fi1)? + 1;
    (n <= inverters)
        .then(|| Inverter::new(i64::from(n)).ok().map(Unit::Inverter))
        .flatten()
}

/// "Invalid index" for a read or a write.
fn status_index(write: bool) -> PnioStatus {
    PnioStatus::record(write, pniorw::INVALID_INDEX)
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
        r.write(&mut d, 101, &order).unwrap();
        // Read Response (−) while the order is processed (two cycles here).
        assert_eq!(
            r.read(&mut d, 101),
            Err(PnioStatus::new(0xDE, 0x80, 0xB5, 0))
        );
        let answer = r.read(&mut d, 101).unwrap();
        assert_eq!(answer[..4], [0x14, 0x4E, 0x01, 0x00]);
        assert_eq!(u16::from_be_bytes([answer[6], answer[7]]), 250);
        // Answered: a further read has no order.
        assert!(r.read(&mut d, 101).is_err());
    }

    /// Each write is one order: reading P102 again after a write reads the new value.
    #[test]
    fn the_same_order_written_twice_is_processed_twice() {
        let mut d = device(Product::Sk550p, 1);
        let mut r = Records::default();
        let read_p102 = [0x14, 0x4E, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00];
        r.write(&mut d, 101, &read_p102).unwrap();
        let first = r.read(&mut d, 101).unwrap();
        let write = [0x74, 0x4E, 0x00, 0x00, 0x00, 0x00, 0x01, 0x2C];
        r.write(&mut d, 101, &write).unwrap();
        let w = r.read(&mut d, 101).unwrap();
        assert_eq!(w[7], 0x2C, "{w:02X?}");
        r.write(&mut d, 101, &read_p102).unwrap();
        let again = r.read(&mut d, 101).unwrap();
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
            r.write(&mut d, 109, &order),
            Err(PnioStatus::new(0xDF, 0x80, 0xB0, 0))
        );
        assert_eq!(
            r.write(&mut d, 101, &order[..7]),
            Err(PnioStatus::new(0xDF, 0x80, 0xB1, 0))
        );
        // Record 47 is the SK TU3-PNT's only.
        assert_eq!(
            r.read(&mut d, 47),
            Err(PnioStatus::new(0xDE, 0x80, 0xB0, 0))
        );
    }

    /// BU 0590 §4.2.2.2: record 47 with axis 1 reads P102 of the FI, the reference mirrored.
    #[test]
    fn record_47_carries_reference_and_axis() {
        let mut d = device(Product::Tu3Pnt, 1);
        let mut r = Records::default();
        // ref 5Ah, AK 1, axis 1, PNU 1102 = 044Eh, IND 0, PWE 0.
        let order = [0x5A, 0x01, 0x01, 0x04, 0x4E, 0, 0, 0, 0, 0, 0];
        r.write(&mut d, 47, &order).unwrap();
        let answer = r.read(&mut d, 47).unwrap();
        assert_eq!(answer[..5], [0x5A, 0x01, 0x01, 0x04, 0x4E]);
        assert_eq!(answer.len(), 11);
        // Axis 2 does not exist.
        let mut bad = order;
        bad[2] = 2;
        assert_eq!(
            r.write(&mut d, 47, &bad),
            Err(PnioStatus::new(0xDF, 0x80, 0xB8, 0))
        );
    }
}
