//! The data records of the parameter channel (BU 0620 §2.5.6.1–§2.5.6.4, BU 0590 §4.2): which
//! record reaches which unit from which slot, the parameters each unit holds, the length
//! checks, the busy answer and the SK TU3-PNT's 11-byte record 47.

use serde::Serialize;

use super::{profinet, PnioError, IO_SUBSLOT};
use crate::nord::pkw::PkwRepr;
use crate::nord::product::Product;
use crate::nord::types::Inverter;
use crate::pnio::PnioStatus;

/// Record of the SK TU3-PNT's axis-addressed parameter channel (BU 0590 §4.2.2.2).
pub const RECORD_AXIS: u16 = 47;
/// Record of the bus interface's parameters (BU 0620 §2.5.6.2, BU 0590 §4.2.2.1).
pub const RECORD_INTERFACE: u16 = 100;
/// Length of the PKW records 100..108.
pub const PKW_RECORD_LEN: usize = 8;
/// Length of record 47 (BU 0590 §4.2.4.3: "LEN := 11").
pub const AXIS_RECORD_LEN: usize = 11;
/// The PNIO status of "Read Response (−)": the order is not processed yet (PNIORW B5h
/// "state conflict", the PROFIdrive busy answer).
pub const fn busy_status() -> PnioStatus {
    PnioStatus::record(false, crate::pnio::status::pniorw::STATE_CONFLICT)
}

/// Whom a data record's parameter order goes to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RecordTarget {
    /// The bus interface's own parameters (record 100).
    Interface,
    /// FI n (record 100 + n).
    Inverter(Inverter),
    /// Record 47: the order's axis byte decides ([`axis_target`]).
    ByAxis,
}

/// Whether `slot`/`subslot` takes the parameter records: SK 550P the FI slots 3..10 (BU 0620
/// Fig. 16 "Slot 3...10"); SK TU3-PNT slots 0 (§4.2.2), 2 and 3 (§4.2.1, Fig. 11); subslot 1.
pub fn takes_records(product: Product, slot: u16, subslot: u16) -> bool {
    let slot_ok = match product {
        Product::Sk550p => (3..=10).contains(&slot),
        Product::Tu3Pnt => matches!(slot, 0 | 2 | 3),
        _ => false,
    };
    slot_ok && subslot == IO_SUBSLOT
}

/// The target of record `index` written to or read from `slot`/`subslot` (BU 0620 §2.5.6.2:
/// 100 interface, 101..108 FI 1..8; BU 0590 §4.2.2: 47, 100, 101).
pub fn record_target(
    product: Product,
    slot: u16,
    subslot: u16,
    index: u16,
) -> Result<RecordTarget, PnioError> {
    profinet(product)?;
    let target = match index {
        RECORD_AXIS if product == Product::Tu3Pnt => RecordTarget::ByAxis,
        RECORD_INTERFACE => RecordTarget::Interface,
        101..=108 if index - 100 <= u16::from(product.max_inverters()) => {
            let fi = Inverter::new(i64::from(index - 100))
                .map_err(|_| PnioError::UnknownRecord(index))?;
            RecordTarget::Inverter(fi)
        }
        _ => return Err(PnioError::UnknownRecord(index)),
    };
    if !takes_records(product, slot, subslot) {
        return Err(PnioError::WrongSlot { slot, subslot });
    }
    Ok(target)
}

/// The record index of a target (the inverse of [`record_target`]; `addr::profinet` forms it
/// from a parameter address).
pub fn record_index(target: RecordTarget) -> u16 {
    match target {
        RecordTarget::Interface => RECORD_INTERFACE,
        RecordTarget::Inverter(fi) => RECORD_INTERFACE + u16::from(fi.get()),
        RecordTarget::ByAxis => RECORD_AXIS,
    }
}

/// Checks a written record's length: 11 bytes for record 47, 8 for the PKW records.
pub fn check_record_len(index: u16, got: usize) -> Result<(), PnioError> {
    let need = if index == RECORD_AXIS {
        AXIS_RECORD_LEN
    } else {
        PKW_RECORD_LEN
    };
    if got == need {
        Ok(())
    } else {
        Err(PnioError::BadLength { index, need, got })
    }
}

/// The target of a record-47 order's axis byte: 0 the SK TU3-PNT, 1 the FI (BU 0590 table 20).
pub fn axis_target(axis: u8) -> Result<RecordTarget, PnioError> {
    match axis {
        0 => Ok(RecordTarget::Interface),
        1 => Inverter::new(1)
            .map(RecordTarget::Inverter)
            .map_err(|_| PnioError::UnknownAxis(axis)),
        _ => Err(PnioError::UnknownAxis(axis)),
    }
}

/// Whether a record's target holds parameter `number` (without the +1000): SK 550P record 100
/// P850…P899, records 101…108 P000…P849 and P900…P999 (BU 0620 §2.5.6.2); SK TU3-PNT record
/// 100 P150…P199, record 101 P0…P999 except P150…P199 (BU 0590 §4.2.2.1). Another number is
/// refused in the parameter channel (AK 7, error 0 "invalid parameter number").
pub fn holds_parameter(product: Product, target: RecordTarget, number: u16) -> bool {
    let interface = match product {
        Product::Sk550p => 850..=899,
        Product::Tu3Pnt => 150..=199,
        _ => return false,
    };
    match target {
        RecordTarget::Interface => interface.contains(&number),
        RecordTarget::Inverter(_) => number <= 999 && !interface.contains(&number),
        RecordTarget::ByAxis => false,
    }
}

/// Byte offsets of record 47 (BU 0590 table 20, p. 26).
mod field47 {
    pub(super) const REFERENCE: usize = 0;
    pub(super) const LABEL: usize = 1;
    pub(super) const AXIS: usize = 2;
    pub(super) const PNU: std::ops::Range<usize> = 3..5;
    pub(super) const IND: std::ops::Range<usize> = 5..7;
    pub(super) const PWE: std::ops::Range<usize> = 7..11;
}

/// Record 47 as BU 0590 table 20 lays it out: order reference, order label, axis, parameter
/// number (+1000), index, value — 11 bytes, big-endian.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub struct Record47Repr {
    /// Order reference, mirrored in the response ("definitive allocation of the response").
    pub reference: u8,
    /// Order label (the AK of §4.2.3.1, a whole byte here).
    pub label: u8,
    /// 0 = SK TU3-PNT, 1 = frequency inverter.
    pub axis: u8,
    /// Parameter number + 1000 (16 bits, no label nibble).
    pub pnu: u16,
    /// Index word (§4.2.3.2).
    pub ind: u16,
    /// Value.
    pub pwe: u32,
}

impl Record47Repr {
    /// Parses exactly 11 bytes.
    pub fn parse(bytes: &[u8]) -> Result<Record47Repr, PnioError> {
        check_record_len(RECORD_AXIS, bytes.len())?;
        let be16 =
            |r: std::ops::Range<usize>| u16::from_be_bytes([bytes[r.start], bytes[r.start + 1]]);
        let p = &bytes[field47::PWE];
        Ok(Record47Repr {
            reference: bytes[field47::REFERENCE],
            label: bytes[field47::LABEL],
            axis: bytes[field47::AXIS],
            pnu: be16(field47::PNU),
            ind: be16(field47::IND),
            pwe: u32::from_be_bytes([p[0], p[1], p[2], p[3]]),
        })
    }

    /// Always 11.
    pub fn buffer_len(&self) -> usize {
        AXIS_RECORD_LEN
    }

    /// Writes the record into the first 11 bytes of `out`.
    pub fn emit(&self, out: &mut [u8]) -> Result<(), PnioError> {
        if out.len() < AXIS_RECORD_LEN {
            return Err(PnioError::BadLength {
                index: RECORD_AXIS,
                need: AXIS_RECORD_LEN,
                got: out.len(),
            });
        }
        out[field47::REFERENCE] = self.reference;
        out[field47::LABEL] = self.label;
        out[field47::AXIS] = self.axis;
        out[field47::PNU].copy_from_slice(&self.pnu.to_be_bytes());
        out[field47::IND].copy_from_slice(&self.ind.to_be_bytes());
        out[field47::PWE].copy_from_slice(&self.pwe.to_be_bytes());
        Ok(())
    }

    /// The same order as an 8-byte PKW telegram (label in the AK nibble; the PNU keeps its
    /// low 11 bits, which hold every P + 1000).
    pub fn pkw(&self) -> PkwRepr {
        PkwRepr {
            ak: self.label & 0x0F,
            spm: false,
            pnu: self.pnu & 0x07FF,
            ind: self.ind,
            pwe: self.pwe,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    fn fi(n: i64) -> Inverter {
        Inverter::new(n).unwrap()
    }

    #[rstest]
    // BU 0620 §2.5.6.2: 100 interface, 101…108 FI 1…8, sent to slot 3…10.
    #[case(Product::Sk550p, 3, 100, Ok(RecordTarget::Interface))]
    #[case(Product::Sk550p, 3, 102, Ok(RecordTarget::Inverter(fi(2))))]
    #[case(Product::Sk550p, 10, 108, Ok(RecordTarget::Inverter(fi(8))))]
    #[case(Product::Sk550p, 3, 109, Err(PnioError::UnknownRecord(109)))]
    #[case(Product::Sk550p, 3, 47, Err(PnioError::UnknownRecord(47)))]
    #[case(Product::Sk550p, 0, 101, Err(PnioError::WrongSlot { slot: 0, subslot: 1 }))]
    // BU 0590 §4.2.2: 47 by axis, 100 TU, 101 FI; slots 0, 2, 3.
    #[case(Product::Tu3Pnt, 0, 47, Ok(RecordTarget::ByAxis))]
    #[case(Product::Tu3Pnt, 2, 100, Ok(RecordTarget::Interface))]
    #[case(Product::Tu3Pnt, 3, 101, Ok(RecordTarget::Inverter(fi(1))))]
    #[case(Product::Tu3Pnt, 3, 102, Err(PnioError::UnknownRecord(102)))]
    #[case(Product::Tu3Pnt, 4, 101, Err(PnioError::WrongSlot { slot: 4, subslot: 1 }))]
    fn record_targets(
        #[case] p: Product,
        #[case] slot: u16,
        #[case] index: u16,
        #[case] want: Result<RecordTarget, PnioError>,
    ) {
        assert_eq!(record_target(p, slot, IO_SUBSLOT, index), want);
        if let Ok(t) = want {
            assert_eq!(record_index(t), index);
        }
    }

    #[test]
    fn record_refusals_and_their_status() {
        let e = record_target(Product::Sk550p, 3, 0x8000, 101).unwrap_err();
        assert_eq!(e.record_status(true).to_bytes(), [0xDF, 0x80, 0xB2, 0x00]);
        assert_eq!(
            PnioError::UnknownRecord(99).record_status(false).to_bytes(),
            [0xDE, 0x80, 0xB0, 0x00]
        );
        let short = check_record_len(101, 7).unwrap_err();
        assert_eq!(
            short,
            PnioError::BadLength {
                index: 101,
                need: 8,
                got: 7
            }
        );
        assert_eq!(
            short.record_status(true).to_bytes(),
            [0xDF, 0x80, 0xB1, 0x00]
        );
        assert_eq!(check_record_len(47, 11), Ok(()));
        // "Read Response (−)": DE 80 B5 00.
        assert_eq!(busy_status().to_bytes(), [0xDE, 0x80, 0xB5, 0x00]);
    }

    #[test]
    fn parameter_ranges_per_record() {
        // BU 0620 §2.5.6.2: P717 is no interface parameter (the manual's record-100 example).
        assert!(!holds_parameter(
            Product::Sk550p,
            RecordTarget::Interface,
            717
        ));
        assert!(holds_parameter(
            Product::Sk550p,
            RecordTarget::Inverter(fi(1)),
            717
        ));
        assert!(holds_parameter(
            Product::Sk550p,
            RecordTarget::Interface,
            854
        ));
        assert!(!holds_parameter(
            Product::Sk550p,
            RecordTarget::Inverter(fi(1)),
            870
        ));
        assert!(holds_parameter(
            Product::Sk550p,
            RecordTarget::Inverter(fi(1)),
            900
        ));
        // BU 0590 §4.2.2.1: P170 via record 100, P102 via 101, P160 not via 101.
        assert!(holds_parameter(
            Product::Tu3Pnt,
            RecordTarget::Interface,
            170
        ));
        assert!(holds_parameter(
            Product::Tu3Pnt,
            RecordTarget::Inverter(fi(1)),
            102
        ));
        assert!(!holds_parameter(
            Product::Tu3Pnt,
            RecordTarget::Inverter(fi(1)),
            160
        ));
        assert!(!holds_parameter(Product::Tu3Pnt, RecordTarget::ByAxis, 160));
    }

    #[test]
    fn record_47_example_of_bu0590() {
        // BU 0590 §4.2.4.3 p. 32: P105 = 60 Hz on the FI.
        let order = [
            0x05, // order reference (xx)
            0x02, // order label 2: change parameter value (word)
            0x01, // axis 1: frequency inverter
            0x04, 0x51, // PNU 451h = 105 + 1000
            0x00, 0x00, // IND 0: parameter set 1
            0x00, 0x00, 0x02, 0x58, // 600 = 60.0 Hz
        ];
        let r = Record47Repr::parse(&order).unwrap();
        assert_eq!(
            (r.reference, r.label, r.axis, r.pnu, r.ind, r.pwe),
            (5, 2, 1, 0x451, 0, 600)
        );
        assert_eq!(axis_target(r.axis), Ok(RecordTarget::Inverter(fi(1))));
        assert_eq!(axis_target(0), Ok(RecordTarget::Interface));
        assert_eq!(axis_target(2), Err(PnioError::UnknownAxis(2)));
        assert_eq!(r.pkw().emit_bytes(), [0x24, 0x51, 0, 0, 0, 0, 0x02, 0x58]);
        let mut out = [0u8; 11];
        r.emit(&mut out).unwrap();
        assert_eq!(out, order);
        for n in 0..=12 {
            assert_eq!(Record47Repr::parse(&[0; 12][..n]).is_ok(), n == 11, "{n}");
        }
        assert!(r.emit(&mut [0u8; 10]).is_err());
    }

    mod properties {
        use super::*;
        use proptest::prelude::*;

        fn record47() -> impl Strategy<Value = Record47Repr> {
            any::<(u8, u8, u8, u16, u16, u32)>().prop_map(
                |(reference, label, axis, pnu, ind, pwe)| Record47Repr {
                    reference,
                    label,
                    axis,
                    pnu,
                    ind,
                    pwe,
                },
            )
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn emit_then_parse_round_trips(r in record47(), extra in 0usize..4) {
                let mut buf = vec![0u8; r.buffer_len() + extra];
                r.emit(&mut buf).unwrap();
                prop_assert_eq!(Record47Repr::parse(&buf[..r.buffer_len()]), Ok(r));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..16)) {
                let _ = Record47Repr::parse(&bytes);
            }
        }
    }
}
