//! Serving parameter orders (PKW) from a parameter store.
//!
//! BU 0620 §2.5.6.3: the answer carries the positive response label of the order, or label 7
//! with the error number in PWE2. PNU is accepted both plain (BU 0590 §4.2.4.4: `70 66 …` for
//! P102 in the cyclic PKW) and with the +1000 offset (BU 0620 §2.5.6.2, data records); the
//! answer echoes the order's PNU and IND.

use proto::nord::params::{ParamDef, Width};
use proto::nord::pkw::{ErrorNumber, Ind, OrderLabel, PkwRepr, ResponseLabel};
use proto::nord::{ArrayElement, ParamNumber, ParamSet, Product};

use crate::store::{AccessError, ParamStore, Persist};

/// The parameter-channel error number of a refused access.
pub fn error_number(e: AccessError) -> ErrorNumber {
    match e {
        AccessError::NoSuchParameter => ErrorNumber::INVALID_PNU,
        AccessError::ReadOnly => ErrorNumber::NOT_CHANGEABLE,
        AccessError::OutOfRange => ErrorNumber::LIMIT_EXCEEDED,
        AccessError::BadSubIndex => ErrorNumber::BAD_SUBINDEX,
        AccessError::NotAnArray => ErrorNumber::NO_ARRAY,
        AccessError::OnlyResettable => ErrorNumber::ONLY_RESET,
    }
}

/// The refusal of `order` with error number `e` (response label 7).
pub(crate) fn refuse(order: &PkwRepr, e: ErrorNumber) -> PkwRepr {
    PkwRepr {
        ak: ResponseLabel::CANNOT_EXECUTE.0,
        spm: false,
        pnu: order.pnu,
        ind: order.ind,
        pwe: u32::from(e.0),
    }
}

/// Processes one order; `supported` are the order labels this unit accepts.
pub fn handle_order(store: &mut ParamStore, supported: &[OrderLabel], order: &PkwRepr) -> PkwRepr {
    match serve(store, supported, order) {
        Ok(r) => r,
        Err(e) => refuse(order, e),
    }
}

/// An order checked against the unit's order labels and the parameter's layout: what it
/// reads or writes, before the store is asked.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Resolved {
    /// The order label.
    pub(crate) ak: OrderLabel,
    /// The parameter.
    pub(crate) number: ParamNumber,
    /// Its definition.
    pub(crate) def: &'static ParamDef,
    /// The set, for a set-dependent parameter.
    pub(crate) set: Option<ParamSet>,
    /// The element, with the array labels.
    pub(crate) element: Option<ArrayElement>,
}

impl Resolved {
    /// The positive answer of value `value` (the word or double-word label of the order's
    /// kind).
    pub(crate) fn answer(&self, order: &PkwRepr, value: i32) -> PkwRepr {
        let dword = self.def.width == Width::Dword;
        let label = |word: ResponseLabel, dw: ResponseLabel| if dword { dw } else { word };
        let ak = match self.ak.0 {
            9 => ResponseLabel::ARRAY_LEN,
            1 => label(ResponseLabel::WORD, ResponseLabel::DWORD),
            6 => label(ResponseLabel::ARRAY_WORD, ResponseLabel::ARRAY_DWORD),
            _ => self.ak.positive_responses()[0],
        };
        PkwRepr {
            ak: ak.0,
            spm: false,
            pnu: order.pnu,
            ind: order.ind,
            pwe: value as u32,
        }
    }
}

/// Checks `order` as far as it can be checked without the value: its label (`supported`), its
/// parameter, the set and element its index names, and for a change the width of its label
/// (error 5). `None` for label 0 "no order".
pub(crate) fn resolve(
    store: &ParamStore,
    supported: &[OrderLabel],
    order: &PkwRepr,
) -> Result<Option<Resolved>, ErrorNumber> {
    let ak = OrderLabel(order.ak);
    if ak == OrderLabel::NONE {
        return Ok(None);
    }
    let positive = ak.positive_responses();
    if positive.is_empty() || !supported.contains(&ak) {
        return Err(ErrorNumber::INVALID_ORDER);
    }
    let number =
        ParamNumber::new(i64::from(order.parameter())).map_err(|_| ErrorNumber::INVALID_PNU)?;
    let def = store.def(number).ok_or(ErrorNumber::INVALID_PNU)?;
    let ind = Ind(order.ind);
    let set = if def.set_dependent {
        ParamSet::new(i64::from(ind.set())).ok()
    } else {
        None
    };
    // Array elements count only with the array labels (§2.5.6.3 "Parameter index IND").
    let element = if ak.is_array() || ak == OrderLabel::REQUEST_ARRAY_LEN {
        let index = if def.set_dependent {
            ind.element()
        } else {
            ind.subindex() + 1
        };
        match def.array {
            Some(_) => {
                Some(ArrayElement::new(i64::from(index)).map_err(|_| ErrorNumber::BAD_SUBINDEX)?)
            }
            None if index == 1 => None,
            None => return Err(ErrorNumber::NO_ARRAY),
        }
    } else {
        None
    };
    // Error 5 "at present only for SK 700E" (BU 0590 §4.2.3.1 Table 24): the SK 5xxE under
    // the SK TU3-PNT takes a value in either width.
    let change = !matches!(ak.0, 1 | 6 | 9);
    let dword = def.width == Width::Dword;
    if change && ak.is_dword() != dword && store.product() != Product::Tu3Pnt {
        return Err(ErrorNumber::BAD_TYPE);
    }
    Ok(Some(Resolved {
        ak,
        number,
        def,
        set,
        element,
    }))
}

fn serve(
    store: &mut ParamStore,
    supported: &[OrderLabel],
    order: &PkwRepr,
) -> Result<PkwRepr, ErrorNumber> {
    let Some(r) = resolve(store, supported, order)? else {
        return Ok(PkwRepr::default());
    };
    let err = error_number;
    match r.ak.0 {
        9 => Ok(r.answer(order, i32::from(store.array_len(r.number).map_err(err)?))),
        1 | 6 => Ok(r.answer(order, store.read(r.number, r.set, r.element).map_err(err)?)),
        _ => {
            let value = order.pwe as i32;
            // P560 "Save in EEPROM" = 0 keeps changes in RAM too: the store decides that.
            let persist = if r.ak.is_ram_only() {
                Persist::RamOnly
            } else {
                Persist::Eeprom
            };
            store
                .write(r.number, r.set, r.element, value, persist)
                .map_err(err)?;
            Ok(r.answer(order, value))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::store::Target;
    use proto::nord::pkw::supported_orders;
    use proto::nord::Inverter;

    fn fi(n: i64) -> ParamStore {
        ParamStore::new(Product::Sk550p, Target::Inverter(Inverter::new(n).unwrap()))
    }

    fn order(bytes: [u8; 8]) -> PkwRepr {
        PkwRepr::parse(&bytes).unwrap()
    }

    #[test]
    fn bu0590_p102_set3_example() {
        // BU 0590 §4.2.4.4: 70 66 02 00 00 00 03 E8 → positive response "array word" = 4.
        let mut s = fi(1);
        let r = handle_order(
            &mut s,
            supported_orders(Product::Sk550p, true),
            &order([0x70, 0x66, 0x02, 0, 0, 0, 0x03, 0xE8]),
        );
        assert_eq!((r.ak, r.pnu, r.ind, r.pwe), (4, 0x66, 0x0200, 1000));
        let read = handle_order(
            &mut s,
            supported_orders(Product::Sk550p, true),
            &order([0x14, 0x4E, 0x02, 0, 0, 0, 0, 0]),
        );
        assert_eq!((read.ak, read.value()), (1, 1000));
    }

    #[test]
    fn bu0620_p102_write_example_answers_label_1() {
        // BU 0620 §2.5.6.4: 24 4E 01 00 00 00 00 FA → response label 1 with P102 = 250 in set 2.
        let mut s = fi(1);
        let r = handle_order(
            &mut s,
            supported_orders(Product::Sk550p, true),
            &order([0x24, 0x4E, 0x01, 0, 0, 0, 0, 0xFA]),
        );
        assert_eq!((r.ak, r.pnu, r.value()), (1, 1102, 250));
    }

    #[test]
    fn refusals_carry_the_manuals_error_numbers() {
        let mut s = fi(1);
        let all = supported_orders(Product::Sk550p, true);
        let cases = [
            (
                PkwRepr {
                    ak: 1,
                    pnu: 1999,
                    ..Default::default()
                },
                0,
            ),
            (
                PkwRepr {
                    ak: 2,
                    pnu: 1717,
                    pwe: 1,
                    ..Default::default()
                },
                1,
            ),
            (
                PkwRepr {
                    ak: 2,
                    pnu: 1102,
                    pwe: 40000,
                    ..Default::default()
                },
                2,
            ),
            (
                PkwRepr {
                    ak: 6,
                    pnu: 1543,
                    ind: 0x0900,
                    ..Default::default()
                },
                3,
            ),
            (
                PkwRepr {
                    ak: 9,
                    pnu: 1102,
                    ..Default::default()
                },
                4,
            ),
            (
                PkwRepr {
                    ak: 3,
                    pnu: 1102,
                    pwe: 5,
                    ..Default::default()
                },
                5,
            ),
            (
                PkwRepr {
                    ak: 4,
                    pnu: 1102,
                    ..Default::default()
                },
                201,
            ),
        ];
        for (o, e) in cases {
            let r = handle_order(&mut s, all, &o);
            assert_eq!((r.ak, r.pwe), (7, e), "{o:?}");
        }
    }

    #[test]
    fn no_error_5_behind_the_tu3_pnt() {
        // BU 0590 Table 24: error 5 "Invalid data type (at present only for SK 700E)".
        let mut s = ParamStore::new(Product::Tu3Pnt, Target::Inverter(Inverter::new(1).unwrap()));
        let o = PkwRepr {
            ak: 3,
            pnu: 1102,
            pwe: 300,
            ..Default::default()
        };
        let r = handle_order(&mut s, supported_orders(Product::Tu3Pnt, true), &o);
        assert_eq!((r.ak, r.pwe), (2, 300));
    }

    #[test]
    fn p560_zero_keeps_writes_in_ram() {
        // BU 0590 §4.2.4.4: P560 "Save in EEPROM" decides whether changes reach the EEPROM
        // (the store counts P560's own write, then no other while it is 0).
        let mut s = fi(1);
        let all = supported_orders(Product::Tu3Pnt, true);
        let write = |pnu, pwe| PkwRepr {
            ak: 2,
            pnu,
            pwe,
            ..Default::default()
        };
        assert_eq!(handle_order(&mut s, all, &write(1560, 0)).ak, 1);
        assert_eq!(s.eeprom_writes(), 1);
        assert_eq!(handle_order(&mut s, all, &write(1102, 300)).ak, 1);
        assert_eq!(s.eeprom_writes(), 1);
    }

    #[test]
    fn ram_only_labels_are_refused_on_the_system_bus_and_do_not_touch_eeprom() {
        let mut fi2 = fi(2);
        let o = PkwRepr {
            ak: 14,
            pnu: 1102,
            pwe: 300,
            ..Default::default()
        };
        assert_eq!(
            handle_order(&mut fi2, supported_orders(Product::Sk550p, false), &o).ak,
            7
        );
        let mut fi1 = fi(1);
        assert_eq!(
            handle_order(&mut fi1, supported_orders(Product::Sk550p, true), &o).ak,
            1
        );
        assert_eq!(fi1.eeprom_writes(), 0);
    }
}
