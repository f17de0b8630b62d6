//! Emergencies a case did not ask for, judged against the inverter they name, on any bus that
//! carries CiA 301's emergency (CoE on EtherCAT, EMCY on the system bus). A device may send
//! one at any time, and a master sets each aside while it waits for its own answer; but an
//! emergency reports an error (CiA 301 §7.2.7), and NORD's says which: P700 [-01] in the
//! manufacturer field's first two bytes and the FI in the third (BU 0620 §5.3, "Error
//! messages … are depicted with parameters P700 and P701"). So the harness asks the
//! inverter: an error that P700 does not show now and P701 ("last error", the five latest)
//! never held is one the inverter does not have — the device reported a fault that is not
//! there, and the step fails naming it. An emergency of code 0000h ("error reset or no
//! error") reports none.

use proto::canopen::Emergency;
use proto::nord::{ArrayElement, Inverter, ParamAddress, ParamNumber};

/// P700 "Present error" and P701 "Last error" (BU 0620 §4.5).
pub(crate) const P700: i64 = 700;
const P701: i64 = 701;
/// Elements of P701 (the latest error first).
const LAST_ERRORS: i64 = 5;
/// Emergencies judged per step at most: the reads that judge one may set aside more.
pub(crate) const AT_MOST: usize = 16;

/// What is wrong with `e` (called `what` in the message: "CoE emergency", "node 32's
/// EMCY"), if anything. `read(at)` reads the parameter at `at` over the bus: its bytes, `None`
/// when the device has no such parameter or refuses it.
pub(crate) fn judge<E>(
    e: &Emergency,
    what: &str,
    mut read: impl FnMut(ParamAddress) -> Result<Option<Vec<u8>>, E>,
) -> Result<Option<String>, E> {
    let mut read = |fi, number, element| -> Result<Option<i16>, E> {
        let (Ok(number), Ok(element)) = (ParamNumber::new(number), ArrayElement::new(element))
        else {
            return Ok(None);
        };
        let at = ParamAddress {
            inverter: fi,
            number,
            set: None,
            element: Some(element),
        };
        Ok(read(at)?
            .filter(|d| d.len() >= 2)
            .map(|d| i16::from_le_bytes([d[0], d[1]])))
    };
    if e.code == 0 {
        return Ok(None);
    }
    let error = i16::from_le_bytes([e.data[0], e.data[1]]);
    let what = format!(
        "{what} {:04X}h (error register {:02X}h) reports error {error} (P700) on FI {}",
        e.code, e.register, e.data[2]
    );
    let Ok(fi) = Inverter::new(i64::from(e.data[2])) else {
        return Ok(Some(format!("{what}, an inverter there is none of")));
    };
    let Some(present) = read(fi, P700, 1)? else {
        return Ok(Some(format!(
            "{what}, an inverter the device has no P700 of"
        )));
    };
    if present == error {
        return Ok(None);
    }
    for n in 1..=LAST_ERRORS {
        match read(fi, P701, n)? {
            Some(last) if last == error => return Ok(None),
            Some(_) => {}
            None => break,
        }
    }
    Ok(Some(format!(
        "{what}, but P700 [-01] reads {present} and P701 (the last {LAST_ERRORS} errors) does \
         not hold it: the device reported an error the inverter does not have (BU 0620 §5.3)"
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    const EMCY: Emergency = Emergency {
        code: 0x7580,
        register: 0x11,
        data: [100, 0, 1, 0, 0],
    };

    /// A reader of an inverter whose P700 is `present` and P701 `last`.
    fn inverter(
        present: i16,
        last: [i16; 5],
    ) -> impl FnMut(ParamAddress) -> Result<Option<Vec<u8>>, ()> {
        move |at| {
            assert_eq!(at.inverter.get(), 1);
            let element = at.element.map_or(0, |e| e.get()) as usize;
            Ok(match i64::from(at.number.get()) {
                P700 => Some(present.to_le_bytes().to_vec()),
                P701 => Some(last[element - 1].to_le_bytes().to_vec()),
                _ => None,
            })
        }
    }

    #[test]
    fn an_error_the_inverter_does_not_have_is_named() {
        assert_eq!(
            judge(&EMCY, "EMCY of node 32", inverter(0, [0; 5])),
            Ok(Some(
                "EMCY of node 32 7580h (error register 11h) reports error 100 (P700) on FI 1, but \
                 P700 [-01] reads 0 and P701 (the last 5 errors) does not hold it: the device \
                 reported an error the inverter does not have (BU 0620 §5.3)"
                    .into()
            ))
        );
    }

    #[test]
    fn a_present_or_a_past_error_and_an_error_reset_pass() {
        assert_eq!(judge(&EMCY, "EMCY", inverter(100, [0; 5])), Ok(None));
        assert_eq!(
            judge(&EMCY, "EMCY", inverter(0, [3, 7, 100, 0, 0])),
            Ok(None)
        );
        let reset = Emergency::default();
        assert_eq!(
            judge(&reset, "EMCY", |_| -> Result<Option<Vec<u8>>, ()> {
                panic!("an error reset needs no read")
            }),
            Ok(None)
        );
    }

    #[test]
    fn an_emergency_of_no_inverter_or_one_without_p700_is_named() {
        let nobody = Emergency {
            data: [100, 0, 0, 0, 0],
            ..EMCY
        };
        assert_eq!(
            judge(&nobody, "EMCY", inverter(0, [0; 5])).unwrap().as_deref(),
            Some("EMCY 7580h (error register 11h) reports error 100 (P700) on FI 0, an inverter there is none of")
        );
        assert!(judge(&EMCY, "EMCY", |_| Ok::<_, ()>(None))
            .unwrap()
            .unwrap()
            .ends_with("an inverter the device has no P700 of"));
        // A read that fails is the caller's error.
        assert_eq!(judge(&EMCY, "EMCY", |_| Err("link down")), Err("link down"));
    }
}
