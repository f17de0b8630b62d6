//! The NORD parameter objects 2000h + 800h·(FI−1) + P (BU 0620 §2.2.7) and their sub-indices.

use super::super::params::{ParamDef, Width};
use super::super::types::{ArrayElement, Inverter, ParamSet};
use super::od::DataType;

/// First index of the NORD parameter objects (§2.2.7 "Start offset").
pub const PARAMETER_BASE: u16 = 0x2000;
/// Index step from one inverter to the next (§2.2.7 "Device offset").
pub const PARAMETER_DEVICE_OFFSET: u16 = 0x800;

/// The inverter and raw parameter number (0..7FFh; the manual's numbers are 0..999) an index
/// in 2000h..5FFFh addresses (§2.2.7 formula inverted; `proto::nord::addr::coe` forms it).
pub fn parameter_object(index: u16) -> Option<(Inverter, u16)> {
    let offset = index.checked_sub(PARAMETER_BASE)?;
    let fi = offset / PARAMETER_DEVICE_OFFSET + 1;
    let inverter = Inverter::new(i64::from(fi)).ok()?;
    Some((inverter, offset % PARAMETER_DEVICE_OFFSET))
}

/// What a sub-index of a parameter object addresses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParamSub {
    /// Sub-index 0 of a parameter with a sub-index: "the maximum size of the array" (§2.2.7).
    Count(u8),
    /// A value: its set and element (per `proto::nord::addr::sdo_subindex`).
    Value(Option<ParamSet>, Option<ArrayElement>),
}

/// The number of sub-indices of a parameter (sets × elements), `None` for a plain parameter
/// (whose value is at sub-index 0).
pub fn parameter_count(set_dependent: bool, array: Option<u8>) -> Option<u8> {
    match (set_dependent, array) {
        (false, None) => None,
        (true, None) => Some(4),
        (false, Some(n)) => Some(n),
        (true, Some(n)) => Some(n.saturating_mul(4)),
    }
}

/// Decodes a parameter object's sub-index (the inverse of `addr::sdo_subindex`); `None` when
/// the sub-index does not exist for that parameter (abort 06090011h).
pub fn parameter_subindex(sub: u8, set_dependent: bool, array: Option<u8>) -> Option<ParamSub> {
    let Some(count) = parameter_count(set_dependent, array) else {
        return (sub == 0).then_some(ParamSub::Value(None, None));
    };
    if sub == 0 {
        return Some(ParamSub::Count(count));
    }
    if sub > count {
        return None;
    }
    let n = i64::from(sub);
    Some(match (set_dependent, array) {
        (true, Some(_)) => ParamSub::Value(
            ParamSet::new((n - 1) % 4 + 1).ok(),
            ArrayElement::new((n - 1) / 4 + 1).ok(),
        ),
        (true, None) => ParamSub::Value(ParamSet::new(n).ok(), None),
        _ => ParamSub::Value(None, ArrayElement::new(n).ok()),
    })
}

/// The CoE type of a parameter's value: INTEGER16 for words (signed, so that a value below the
/// range is "too small" rather than a large unsigned one), UNSIGNED16 for words whose range
/// exceeds 7FFFh (bit fields such as P872), INTEGER32 for positions (§4: "position values are
/// communicated as double words").
pub fn parameter_data_type(def: &ParamDef) -> DataType {
    match def.width {
        Width::Dword => DataType::I32,
        Width::Word if def.max > i32::from(i16::MAX) => DataType::U16,
        Width::Word => DataType::I16,
    }
}

#[cfg(test)]
mod tests {
    use super::super::*;
    use crate::nord::addr::sdo_subindex;
    use crate::nord::Inverter;

    fn fi(n: i64) -> Inverter {
        Inverter::new(n).unwrap()
    }

    #[test]
    fn identity_of_1018h() {
        let od = object_dictionary(1);
        let id = od.iter().find(|o| o.index == 0x1018).unwrap();
        assert_eq!(id.entry(0).unwrap().value, Value::Number(4));
        assert_eq!(id.entry(1).unwrap().value, Value::Number(0x538));
        assert!(id.entry(5).is_none());
    }

    #[test]
    fn pdo_mapping_of_fi_3() {
        // 12 bytes per FI (§2.2.6.1): control word + setpoints 1..5 from 7020h:01..06.
        let rx = &rx_pdos(3)[2];
        assert_eq!((rx.index, rx.sm), (0x1602, 2));
        assert_eq!(rx.entries[0].mapping(), 0x7020_0110);
        assert_eq!(rx.entries[5].mapping(), 0x7020_0610);
        let bits: u16 = rx.entries.iter().map(|e| u16::from(e.bits)).sum();
        assert_eq!(bits / 8, BYTES_PER_INVERTER);
        assert_eq!(tx_pdos(8)[7].entries[0].mapping(), 0x6070_0110);
    }

    #[test]
    fn assignment_and_sm_layout() {
        let od = object_dictionary(4);
        let a = od.iter().find(|o| o.index == 0x1C12).unwrap();
        assert_eq!(a.entry(0).unwrap().value, Value::Number(4));
        assert_eq!(a.entry(4).unwrap().value, Value::Number(0x1603));
        let t = od.iter().find(|o| o.index == 0x1C00).unwrap();
        let types: Vec<_> = t.entries.iter().map(|e| e.value.clone()).collect();
        assert_eq!(types, [4, 1, 2, 3, 4].map(Value::Number));
        let sms = sync_managers(8);
        assert_eq!(sms[2].len, 96);
        // Three buffers of SM2 end before SM3 starts.
        assert!(OUTPUTS_START + 3 * sms[2].len <= INPUTS_START);
        const { assert!(SM_MAILBOX_IN.start + SM_MAILBOX_IN.len <= OUTPUTS_START) };
        let mut idx: Vec<u16> = od.iter().map(|o| o.index).collect();
        idx.dedup();
        assert_eq!(idx.len(), od.len(), "indices unique");
    }

    #[test]
    fn parameter_objects_invert_the_formula() {
        // §2.2.7: FI 3, P102 → 3066h.
        assert_eq!(parameter_object(0x3066), Some((fi(3), 102)));
        assert_eq!(parameter_object(0x5FFF), Some((fi(8), 0x7FF)));
        assert_eq!(parameter_object(0x1FFF), None);
        assert_eq!(parameter_object(0x6000), None);
    }

    #[test]
    fn sub_indices_invert_sdo_subindex() {
        for (sets, array) in [
            (false, None),
            (true, None),
            (false, Some(5)),
            (true, Some(3)),
        ] {
            let count = parameter_count(sets, array).unwrap_or(0);
            for sub in 1..=count {
                let Some(ParamSub::Value(s, e)) = parameter_subindex(sub, sets, array) else {
                    panic!("{sub}");
                };
                assert_eq!(sdo_subindex(s, e), sub);
            }
            assert_eq!(parameter_subindex(count + 1, sets, array), None);
        }
        assert_eq!(parameter_subindex(0, true, None), Some(ParamSub::Count(4)));
        assert_eq!(
            parameter_subindex(0, false, None),
            Some(ParamSub::Value(None, None))
        );
    }
}
