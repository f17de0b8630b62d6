//! A PKW order (parameter channel, BU 0620 §2.5.6) to an inverter on the system bus, as the
//! gateway carries it: the order is checked as the parameter channel checks it (its label, the
//! parameter, the set and element its index names, error 5 for a label of the wrong width), and
//! then a read (labels 1 and 6) is an SDO upload from the inverter's node and a change kept in
//! EEPROM (labels 2, 3, 7, 8) an SDO download through it ([`super::Gateway`]); the node's answer
//! becomes the response label and value, or label 7 with the error number.
//!
//! What has no SDO counterpart on a node stays with the parameter channel on the inverter's
//! store (`crate::pkw_server`), not carried: the array length (label 9) and the changes in RAM
//! only (labels 11–14; an SDO download is kept as P560 says, there is no RAM-only download).
//!
//! Error numbers: the store's own reason where the node's store refused
//! ([`crate::objects::Refused`], `pkw_server::error_number`), else the abort code's
//! ([`error_of`]). The code alone is coarser than the parameter channel: 06090011h is error 3
//! "faulty sub-index" and 4 "no array" alike, 06090030h error 2 "limit exceeded" and 6 "only
//! reset" alike. Error 4 never comes from a node here (the check of the index decides it first),
//! and carrying the store's reason keeps 6 for a node's store that refused it.

use proto::can::CanFrame;
use proto::nord::ecat::{parameter_data_type, PARAMETER_BASE};
use proto::nord::errors::SdoAbort;
use proto::nord::params::Width;
use proto::nord::pkw::{ErrorNumber, OrderLabel, PkwRepr};
use proto::nord::{ArrayElement, Inverter, ParamSet};

use super::Gateway;
use crate::objects::{abort, decode_number, encode_number, Refused};
use crate::pkw_server::{error_number, refuse, resolve};
use crate::store::ParamStore;

/// The answer to `order` to FI `fi` (parameters in `store`, order labels `supported`) when the
/// gateway carries it over the system bus, the frames exchanged appended to `wire`; `None` when
/// the order is not carried (see the module documentation) and the parameter channel serves it.
pub(crate) fn serve_order(
    gateway: &mut Gateway,
    fi: Inverter,
    store: &mut ParamStore,
    supported: &[OrderLabel],
    order: &PkwRepr,
    wire: &mut Vec<CanFrame>,
) -> Option<PkwRepr> {
    if !gateway.reaches(fi) || !carries(OrderLabel(order.ak)) {
        return None;
    }
    let r = match resolve(store, supported, order) {
        Err(e) => return Some(refuse(order, e)),
        Ok(None) => return None,
        Ok(Some(r)) => r,
    };
    // The store's reading of a set or element left out: set 1, element 1.
    let set = r
        .def
        .set_dependent
        .then(|| r.set.or(ParamSet::new(1).ok()))
        .flatten();
    let element = r
        .def
        .array
        .and_then(|_| r.element.or(ArrayElement::new(1).ok()));
    let Some(sub) = sub_index(set, element) else {
        // Beyond sub-index 255: no such element.
        return Some(refuse(order, ErrorNumber::BAD_SUBINDEX));
    };
    let index = PARAMETER_BASE + r.number.get();
    if matches!(r.ak.0, 1 | 6) {
        return Some(match gateway.upload(fi, store, index, sub, wire) {
            Ok(bytes) => match value_of(&bytes, r.def) {
                Some(v) => r.answer(order, v),
                None => refuse(order, ErrorNumber::BAD_TYPE),
            },
            Err(refused) => refuse(order, error_of(refused)),
        });
    }
    let value = order.pwe as i32;
    let ty = parameter_data_type(r.def);
    let bytes = encode_number(i64::from(value), ty);
    // A value the parameter's type cannot carry is outside its range: refused as the store
    // refuses it, not cut to a value the node would take.
    if decode_number(&bytes, ty) != Ok(value) {
        return Some(refuse(order, ErrorNumber::LIMIT_EXCEEDED));
    }
    Some(
        match gateway.download(fi, store, index, sub, &bytes, wire) {
            Ok(()) => r.answer(order, value),
            Err(refused) => refuse(order, error_of(refused)),
        },
    )
}

/// The order labels the gateway carries: reads and changes kept in EEPROM.
pub(crate) fn carries(ak: OrderLabel) -> bool {
    matches!(ak.0, 1 | 2 | 3 | 6 | 7 | 8)
}

/// The parameter object's sub-index of a set and element (`proto::nord::addr::sdo_subindex`),
/// `None` beyond 255.
fn sub_index(set: Option<ParamSet>, element: Option<ArrayElement>) -> Option<u8> {
    let s = set.map_or(0, |s| u16::from(s.get()));
    let sub = match element {
        None => s,
        Some(e) if set.is_some() => (u16::from(e.get()) - 1) * 4 + s,
        Some(e) => u16::from(e.get()),
    };
    u8::try_from(sub).ok()
}

/// The value of a parameter's bytes as the parameter channel shows it: a word signed where the
/// parameter's range is (as the store holds it), a double word signed.
fn value_of(bytes: &[u8], def: &proto::nord::params::ParamDef) -> Option<i32> {
    match (def.width, bytes) {
        (Width::Word, [lo, hi]) if def.min < 0 => Some(i32::from(i16::from_le_bytes([*lo, *hi]))),
        (Width::Word, [lo, hi]) => Some(i32::from(u16::from_le_bytes([*lo, *hi]))),
        (Width::Dword, [a, b, c, d]) => Some(i32::from_le_bytes([*a, *b, *c, *d])),
        _ => None,
    }
}

/// The parameter-channel error number of a refusal on the system bus: the store's reason where
/// it refused, else the abort code's (BU 0620 §2.5.6.3 error numbers against CiA 301 codes).
/// A transfer that failed (time-out, protocol, an inverter not reached) has no number of its
/// own in the manuals: 202 "no response label", as no answer came.
pub(crate) fn error_of(r: Refused) -> ErrorNumber {
    if let Some(cause) = r.cause {
        return error_number(cause);
    }
    abort_error(r.abort)
}

fn abort_error(code: SdoAbort) -> ErrorNumber {
    match code {
        abort::NO_OBJECT => ErrorNumber::INVALID_PNU,
        abort::READ_ONLY => ErrorNumber::NOT_CHANGEABLE,
        abort::VALUE_RANGE | abort::VALUE_TOO_HIGH | abort::VALUE_TOO_LOW => {
            ErrorNumber::LIMIT_EXCEEDED
        }
        abort::NO_SUBINDEX => ErrorNumber::BAD_SUBINDEX,
        abort::TOO_LONG | abort::TOO_SHORT => ErrorNumber::BAD_TYPE,
        _ => ErrorNumber::NO_RESPONSE_LABEL,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::objects::abort_of;
    use crate::store::{AccessError, Target};
    use proto::nord::pkw::supported_orders;
    use proto::nord::Product;

    fn fi(n: i64) -> Inverter {
        Inverter::new(n).unwrap()
    }

    fn order(bytes: [u8; 8]) -> PkwRepr {
        PkwRepr::parse(&bytes).unwrap()
    }

    #[test]
    fn reads_and_eeprom_changes_are_sdo_transfers_with_the_node() {
        let mut gw = Gateway::new(Product::Tu3Eip, 3);
        let mut store = ParamStore::new(Product::Tu3Eip, Target::Inverter(fi(3)));
        let all = supported_orders(Product::Tu3Eip, false);
        let mut wire = Vec::new();
        // BU 0620 §2.5.6.4: 24 4E 01 00 00 00 00 FA, P102 set 2 := 250 (2066h:02).
        let write = order([0x24, 0x4E, 0x01, 0, 0, 0, 0, 0xFA]);
        let answer = serve_order(&mut gw, fi(3), &mut store, all, &write, &mut wire).unwrap();
        assert_eq!((answer.ak, answer.value()), (1, 250));
        // P102 set 2 read back (label 1), then above its range (error 2, the node's 06090031h
        // with the store's reason) and 40000, which no INTEGER16 carries (error 2, not sent).
        let read = order([0x14, 0x4E, 0x01, 0, 0, 0, 0, 0]);
        let answer = serve_order(&mut gw, fi(3), &mut store, all, &read, &mut wire).unwrap();
        assert_eq!((answer.ak, answer.value()), (1, 250));
        let high = order([0x24, 0x4E, 0x01, 0, 0, 0, 0x7D, 0x01]);
        let answer = serve_order(&mut gw, fi(3), &mut store, all, &high, &mut wire).unwrap();
        assert_eq!((answer.ak, answer.pwe), (7, 2));
        assert_eq!(wire.len(), 6);
        let wide = order([0x24, 0x4E, 0x01, 0, 0, 0, 0x9C, 0x40]);
        let answer = serve_order(&mut gw, fi(3), &mut store, all, &wide, &mut wire).unwrap();
        assert_eq!((answer.ak, answer.pwe, wire.len()), (7, 2, 6));
        assert_eq!(gw.server(fi(3)).map(|s| s.counts()), Some((3, 1)));
        assert_eq!(
            wire[5].data(),
            [0x80, 0x66, 0x20, 0x02, 0x31, 0x00, 0x09, 0x06]
        );
        // Array length: the parameter channel's, not carried.
        let len = order([0x90, 0x66, 0, 0, 0, 0, 0, 0]);
        assert!(serve_order(&mut gw, fi(3), &mut store, all, &len, &mut wire).is_none());
    }

    #[test]
    fn the_stores_reason_keeps_the_error_numbers_finer_than_the_abort_codes() {
        let errors = AccessError::ALL;
        for e in errors {
            let code = abort_of(e, 0, None);
            let with = Refused {
                abort: code,
                cause: Some(e),
            };
            assert_eq!(error_of(with), error_number(e));
            // The code alone: the same number, but for the two a code shares.
            let alone = error_of(code.into());
            match e {
                AccessError::NotAnArray => assert_eq!(alone, ErrorNumber::BAD_SUBINDEX),
                AccessError::OnlyResettable => assert_eq!(alone, ErrorNumber::LIMIT_EXCEEDED),
                _ => assert_eq!(alone, error_number(e), "{e:?}"),
            }
        }
    }
}
