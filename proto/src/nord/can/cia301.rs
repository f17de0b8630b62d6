//! What the manuals leave to CANopen, chosen here (see the `can` module documentation): the
//! PDO layout of an inverter's node and the SDO objects of its parameters. The COB-IDs are the
//! CiA 301 pre-defined connection set's ([`crate::canopen::cob_id`]) at the node's address.

use super::super::addr::{sdo_subindex, SdoAddress};
use super::super::ecat::{inputs_index, outputs_index, PARAMETER_BASE};
use super::super::product::Product;
use super::super::types::{Inverter, ParamAddress};
use super::{CanError, InverterSeries, SystemBusAddress};
use crate::canopen::cob_id::Function;

/// Setpoints per inverter (actual values likewise): 3 on SK 1x0E/2xxE and SK 500E…535E, 5 on
/// SK 54xE (BU 2100 §6.2.5 p. 39, BU 2200 §6.3.4 p. 38) and SK 5x0P (BU 0620 §6.1.2.4 p. 112).
pub fn process_values(series: InverterSeries) -> u8 {
    match series {
        InverterSeries::Sk54xe | InverterSeries::Sk5x0p => 5,
        _ => 3,
    }
}

/// The process-data words a PDO of an inverter's node carries, as (first word, count): word 0
/// the control word (RPDO, to the FI) or status word (TPDO, from the FI), words 1…5 setpoints or
/// actual values. PDO 1 words 0…3, PDO 2 words 4…5 (8 bytes per CAN frame). `None` for PDO 3/4,
/// PDO 2 of an FI with three values, and the other objects. Not stated by the manuals: the
/// layout is this project's choice (see the module documentation). Setpoints go to the inverter,
/// actual values come from it (BU 0620 §6.1.2.4 "To/From the frequency inverter"; BU 2100
/// §6.2.5 and BU 2200 §6.3.4 label the same rows "To/From bus interface", seen from the master).
pub fn pdo_words(function: Function, series: InverterSeries) -> Option<(u8, u8)> {
    let words = 1 + process_values(series);
    match function {
        Function::Rpdo { number: 1 } | Function::Tpdo { number: 1 } => Some((0, 4)),
        Function::Rpdo { number: 2 } | Function::Tpdo { number: 2 } if words > 4 => {
            Some((4, words - 4))
        }
        _ => None,
    }
}

/// The data bytes of PDO `function` for an inverter's six words (control/status word and
/// values 1…5): the words [`pdo_words`] gives it, UNSIGNED16 little-endian; `None` where the
/// PDO carries none.
pub fn pdo_data(function: Function, series: InverterSeries, words: &[u16; 6]) -> Option<Vec<u8>> {
    let (first, count) = pdo_words(function, series)?;
    let (first, count) = (usize::from(first), usize::from(count));
    Some(
        words[first..first + count]
            .iter()
            .flat_map(|w| w.to_le_bytes())
            .collect(),
    )
}

/// The CiA 301 mapping entries (index · 10000h + sub-index · 100h + 16 bits) of a PDO: the
/// words of [`pdo_words`] as entries 1…6 of 7000h (RPDO) or 6000h (TPDO), the objects of FI 1
/// in the project's EtherCAT layout.
pub fn pdo_mapping(function: Function, series: InverterSeries) -> Vec<u32> {
    let fi1 = Inverter::new(1).expect("FI 1");
    let index = match function {
        Function::Rpdo { .. } => outputs_index(fi1),
        _ => inputs_index(fi1),
    };
    let Some((first, count)) = pdo_words(function, series) else {
        return Vec::new();
    };
    (first..first + count)
        .map(|w| u32::from(index) << 16 | u32::from(w + 1) << 8 | 16)
        .collect()
}

/// The node and SDO object of a parameter over the system bus: the inverter's address, index
/// 2000h + P, sub-index from set and element. Not stated by the manuals (see the module
/// documentation); refused beyond the inverters `product` serves.
pub fn parameter_sdo(
    product: Product,
    a: ParamAddress,
) -> Result<(SystemBusAddress, SdoAddress), CanError> {
    let node = SystemBusAddress::for_inverter(product, a.inverter)?;
    Ok((
        node,
        SdoAddress {
            index: PARAMETER_BASE + a.number.get(),
            subindex: sdo_subindex(a.set, a.element),
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nord::addr;
    use crate::nord::types::ParamNumber;

    fn fi(n: i64) -> Inverter {
        Inverter::new(n).unwrap()
    }

    #[test]
    fn pdo_layout_choice() {
        // Three values: one PDO each way; five (SK 54xE, SK 5x0P): a second with two words.
        assert_eq!(
            pdo_words(Function::Rpdo { number: 1 }, InverterSeries::Sk2xxe),
            Some((0, 4))
        );
        assert_eq!(
            pdo_words(Function::Rpdo { number: 2 }, InverterSeries::Sk2xxe),
            None
        );
        assert_eq!(
            pdo_words(Function::Tpdo { number: 2 }, InverterSeries::Sk5x0p),
            Some((4, 2))
        );
        assert_eq!(
            pdo_words(Function::Tpdo { number: 3 }, InverterSeries::Sk5x0p),
            None
        );
        // RPDO 1: 7000h sub 1…4 (control word, setpoints 1…3), 16 bits each.
        assert_eq!(
            pdo_mapping(Function::Rpdo { number: 1 }, InverterSeries::Sk54xe),
            [0x7000_0110, 0x7000_0210, 0x7000_0310, 0x7000_0410]
        );
        assert_eq!(
            pdo_mapping(Function::Tpdo { number: 2 }, InverterSeries::Sk54xe),
            [0x6000_0510, 0x6000_0610]
        );
        assert!(pdo_mapping(Function::Sync, InverterSeries::Sk54xe).is_empty());
    }

    #[test]
    fn parameter_sdo_of_fi_3() {
        // P102 of FI 3: node 36, index 2000h + 66h (EtherCAT puts it at 3066h, §2.2.7 p. 20).
        let a = ParamAddress {
            inverter: fi(3),
            number: ParamNumber::new(102).unwrap(),
            set: None,
            element: None,
        };
        let (node, sdo) = parameter_sdo(Product::Sk550p, a).unwrap();
        assert_eq!((node.get(), sdo.index, sdo.subindex), (36, 0x2066, 0));
        assert_eq!(
            addr::coe(Product::Sk550p, a).unwrap().index - 0x1000,
            sdo.index
        );
        let far = ParamAddress {
            inverter: fi(5),
            ..a
        };
        assert!(parameter_sdo(Product::Tu4Eip, far).is_err());
    }
}
