//! The NORD parameter channel (PKW): parameter label PKE, index IND, value PWE.
//!
//! BU 0620 §2.5.6.3 (p. 54–57), BU 0590 (PKW area of PPO types 1 and 2). The telegram is 8
//! bytes, big-endian words as in the manuals' examples (§2.5.6.4: `16 B5 00 00 00 00 00 00`
//! reads P717):
//!
//! | bytes | field |
//! |---|---|
//! | 0–1 | PKE: AK (bits 12–15), SPM (bit 11), PNU (bits 0–10) |
//! | 2–3 | IND: parameter set (bits 8–9), array element (bits 10–15), or sub-index (bits 8–15) |
//! | 4–7 | PWE: PWE1 (high word), PWE2 (low word; the error number of a negative response) |
//!
//! Parsing never panics: a short buffer is [`PkwError::Truncated`].

use std::fmt;

use serde::Serialize;

use super::mutant::Constant;
use super::product::{Family, Product};
use super::types::{ArrayElement, ParamSet};

/// Length of a PKW telegram.
pub const PKW_LEN: usize = 8;

mod field {
    use std::ops::Range;
    pub(super) const PKE: Range<usize> = 0..2;
    pub(super) const IND: Range<usize> = 2..4;
    pub(super) const PWE: Range<usize> = 4..8;
}

/// A malformed PKW telegram.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PkwError {
    /// Fewer than 8 bytes.
    #[error("PKW telegram truncated: need {need} bytes, got {got}")]
    Truncated {
        /// Bytes needed.
        need: usize,
        /// Bytes present.
        got: usize,
    },
}

/// Checked view over a PKW telegram.
#[derive(Debug, Clone)]
pub struct PkwFrame<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> PkwFrame<T> {
    /// Wraps a buffer of at least 8 bytes.
    pub fn new_checked(buffer: T) -> Result<Self, PkwError> {
        let got = buffer.as_ref().len();
        if got < PKW_LEN {
            return Err(PkwError::Truncated { need: PKW_LEN, got });
        }
        Ok(PkwFrame { buffer })
    }

    fn word(&self, r: std::ops::Range<usize>) -> u16 {
        let b = &self.buffer.as_ref()[r];
        u16::from_be_bytes([b[0], b[1]])
    }

    /// The parameter label.
    pub fn pke(&self) -> u16 {
        self.word(field::PKE)
    }

    /// Order/response label, bits 12–15 of PKE.
    pub fn ak(&self) -> u8 {
        (self.pke() >> 12) as u8
    }

    /// Spontaneous-message toggle, bit 11 (not supported by NORD, §2.5.6.3).
    pub fn spm(&self) -> bool {
        self.pke() & 0x0800 != 0
    }

    /// Parameter number, bits 0–10.
    pub fn pnu(&self) -> u16 {
        self.pke() & 0x07FF
    }

    /// The index word.
    pub fn ind(&self) -> u16 {
        self.word(field::IND)
    }

    /// The value, PWE1:PWE2.
    pub fn pwe(&self) -> u32 {
        let b = &self.buffer.as_ref()[field::PWE];
        u32::from_be_bytes([b[0], b[1], b[2], b[3]])
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> PkwFrame<T> {
    /// Sets the parameter label (for building malformed orders in negative tests).
    pub fn set_pke(&mut self, pke: u16) {
        self.buffer.as_mut()[field::PKE].copy_from_slice(&pke.to_be_bytes());
    }
}

/// A parsed PKW telegram (order or response).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub struct PkwRepr {
    /// Order label (master → inverter) or response label (inverter → master), 0..=15.
    pub ak: u8,
    /// SPM toggle bit.
    pub spm: bool,
    /// Parameter number as transmitted (0..=2047; on PROFINET with the +1000 offset).
    pub pnu: u16,
    /// Index word.
    pub ind: u16,
    /// Value; negative values are sign-filled with FFh (§2.5.6.3 "Parameter value PWE").
    pub pwe: u32,
}

impl PkwRepr {
    /// Parses the first 8 bytes.
    pub fn parse(bytes: &[u8]) -> Result<PkwRepr, PkwError> {
        let f = PkwFrame::new_checked(bytes)?;
        Ok(PkwRepr {
            ak: f.ak(),
            spm: f.spm(),
            pnu: f.pnu(),
            ind: f.ind(),
            pwe: f.pwe(),
        })
    }

    /// Always 8.
    pub fn buffer_len(&self) -> usize {
        PKW_LEN
    }

    /// Writes the telegram into `out` (at least 8 bytes; shorter buffers are left untouched and
    /// reported).
    pub fn emit(&self, out: &mut [u8]) -> Result<(), PkwError> {
        if out.len() < PKW_LEN {
            return Err(PkwError::Truncated {
                need: PKW_LEN,
                got: out.len(),
            });
        }
        let pke =
            (u16::from(self.ak & 0x0F) << 12) | (u16::from(self.spm) << 11) | (self.pnu & 0x07FF);
        out[field::PKE].copy_from_slice(&pke.to_be_bytes());
        out[field::IND].copy_from_slice(&self.ind.to_be_bytes());
        out[field::PWE].copy_from_slice(&self.pwe.to_be_bytes());
        Ok(())
    }

    /// The telegram's 8 bytes.
    pub fn emit_bytes(&self) -> [u8; PKW_LEN] {
        let mut b = [0u8; PKW_LEN];
        // The array is exactly PKW_LEN long, so emit cannot fail.
        let _ = self.emit(&mut b);
        b
    }

    /// The value as a signed number (word responses are sign-filled by the sender).
    pub fn value(&self) -> i32 {
        self.pwe as i32
    }

    /// PWE2, the error number of a negative response (AK 7).
    pub fn error_number(&self) -> ErrorNumber {
        ErrorNumber((self.pwe & 0xFFFF) as u16)
    }

    /// The NORD parameter number PNU addresses: PNU − 1000 where it carries the offset
    /// (BU 0620 §2.5.6.2: "The parameter number plus '1000'"), else PNU as it stands (BU 0590
    /// §4.2.4.4: `70 66 …` for P102 in the cyclic PKW).
    pub fn parameter(&self) -> u16 {
        self.pnu.checked_sub(PNU_OFFSET.get()).unwrap_or(self.pnu)
    }

    fn common(&self, label: &str) -> String {
        let mut s = format!("AK {} {label}, PNU {}", self.ak, self.pnu);
        if self.pnu >= PNU_OFFSET.get() {
            s += &format!(" = P{:03}", self.parameter());
        }
        s += &format!(", IND {:04X}h ({})", self.ind, Ind(self.ind).describe());
        s
    }

    /// The telegram read as an order, in the manuals' terms.
    pub fn describe_order(&self) -> String {
        let label = OrderLabel(self.ak);
        let mut s = self.common(&format!("\"{}\"", label.meaning()));
        if label.is_change() {
            s += &format!(", PWE {}", self.value());
        }
        s
    }

    /// The telegram read as a response, in the manuals' terms.
    pub fn describe_response(&self) -> String {
        let label = ResponseLabel(self.ak);
        let mut s = self.common(&format!("\"{}\"", label.meaning()));
        if label == ResponseLabel::CANNOT_EXECUTE {
            let e = self.error_number();
            s += &format!(", error {} \"{}\"", e.0, e.meaning());
        } else if label != ResponseLabel::NONE {
            s += &format!(", PWE {}", self.value());
        }
        s
    }

    fn fields(&self, label: &'static str, meaning: String) -> PkwFields {
        let ind = Ind(self.ind);
        PkwFields {
            ak: self.ak,
            label,
            spm: self.spm,
            pnu: self.pnu,
            parameter: self.parameter(),
            ind: self.ind,
            set: ind.set(),
            element: ind.element(),
            subindex: ind.subindex(),
            pwe: self.pwe,
            value: None,
            array: None,
            dword: None,
            ram_only: None,
            error: None,
            error_meaning: None,
            meaning,
        }
    }

    /// The telegram read as an order, field by field, with [`PkwRepr::describe_order`]'s
    /// sentence as `meaning`.
    pub fn order_fields(&self) -> PkwFields {
        let label = OrderLabel(self.ak);
        PkwFields {
            value: label.is_change().then(|| self.value()),
            array: Some(label.is_array()),
            dword: Some(label.is_dword()),
            ram_only: Some(label.is_ram_only()),
            ..self.fields(label.meaning(), self.describe_order())
        }
    }

    /// The telegram read as a response, field by field, with
    /// [`PkwRepr::describe_response`]'s sentence as `meaning`.
    pub fn response_fields(&self) -> PkwFields {
        let label = ResponseLabel(self.ak);
        let refused = label == ResponseLabel::CANNOT_EXECUTE;
        let error = refused.then(|| self.error_number());
        PkwFields {
            value: (!refused && label != ResponseLabel::NONE).then(|| self.value()),
            error: error.map(|e| e.0),
            error_meaning: error.map(ErrorNumber::meaning),
            ..self.fields(label.meaning(), self.describe_response())
        }
    }
}

/// The offset PNU carries over the parameter number in data records and acyclic services
/// (BU 0620 §2.5.6.2 "PKE").
pub static PNU_OFFSET: Constant<u16> = Constant::new(
    "pnu-offset",
    1000,
    "PNU offset",
    "BU 0620 §2.5.6.2 PNU = P + 1000",
);

/// A PKW telegram's readings as typed fields (`harness decode pkw --json`): every part of the
/// sentence of [`PkwRepr::describe_order`] / [`PkwRepr::describe_response`] as a value of its
/// own. IND is given in each of the readings §2.5.6.3 allows; which one counts depends on
/// the parameter (set-dependent or not) and the label (array or not).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct PkwFields {
    /// Order or response label, bits 12–15 of PKE.
    pub ak: u8,
    /// The label's name in the manual's table of order or response labels.
    pub label: &'static str,
    /// SPM, bit 11 of PKE.
    pub spm: bool,
    /// PNU as transmitted, bits 0–10 of PKE.
    pub pnu: u16,
    /// The parameter number it addresses ([`PkwRepr::parameter`]).
    pub parameter: u16,
    /// IND as transmitted.
    pub ind: u16,
    /// IND read as parameter set, bits 8–9 (1..4).
    pub set: u8,
    /// IND read as array element, bits 10–15 (1..64).
    pub element: u8,
    /// IND read as sub-index, bits 8–15 (0-based).
    pub subindex: u8,
    /// PWE as transmitted, PWE1:PWE2.
    pub pwe: u32,
    /// The value PWE carries, signed, where the label carries one (change orders, positive
    /// responses).
    pub value: Option<i32>,
    /// Order only: the label addresses an array element.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub array: Option<bool>,
    /// Order only: the label transfers a double word.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dword: Option<bool>,
    /// Order only: the label writes RAM only (11–14), not the EEPROM.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ram_only: Option<bool>,
    /// Response AK 7 only: the error number in PWE2.
    pub error: Option<u16>,
    /// Response AK 7 only: the manual's meaning of the error number.
    pub error_meaning: Option<&'static str>,
    /// The whole reading as one sentence.
    pub meaning: String,
}

/// Order label AK, master → inverter (§2.5.6.3 "Meaning of order labels").
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct OrderLabel(pub u8);

impl OrderLabel {
    /// 0: no order.
    pub const NONE: OrderLabel = OrderLabel(0);
    /// 1: order parameter value.
    pub const REQUEST_VALUE: OrderLabel = OrderLabel(1);
    /// 2: change parameter value (word).
    pub const CHANGE_WORD: OrderLabel = OrderLabel(2);
    /// 3: change parameter value (double word).
    pub const CHANGE_DWORD: OrderLabel = OrderLabel(3);
    /// 6: order parameter value (array).
    pub const REQUEST_ARRAY_VALUE: OrderLabel = OrderLabel(6);
    /// 7: change parameter value (array, word).
    pub const CHANGE_ARRAY_WORD: OrderLabel = OrderLabel(7);
    /// 8: change parameter value (array, double word).
    pub const CHANGE_ARRAY_DWORD: OrderLabel = OrderLabel(8);
    /// 9: order the number of array elements.
    pub const REQUEST_ARRAY_LEN: OrderLabel = OrderLabel(9);
    /// 11: change parameter value (array, double word) without writing to the EEPROM.
    pub const CHANGE_ARRAY_DWORD_RAM: OrderLabel = OrderLabel(11);
    /// 12: change parameter value (array, word) without writing to the EEPROM.
    pub const CHANGE_ARRAY_WORD_RAM: OrderLabel = OrderLabel(12);
    /// 13: change parameter value (double word) without writing to the EEPROM.
    pub const CHANGE_DWORD_RAM: OrderLabel = OrderLabel(13);
    /// 14: change parameter value (word) without writing to the EEPROM.
    pub const CHANGE_WORD_RAM: OrderLabel = OrderLabel(14);

    /// The change label for an access: array or not, double word or not, RAM only or not.
    pub fn change(array: bool, dword: bool, ram_only: bool) -> OrderLabel {
        match (array, dword, ram_only) {
            (false, false, false) => Self::CHANGE_WORD,
            (false, true, false) => Self::CHANGE_DWORD,
            (true, false, false) => Self::CHANGE_ARRAY_WORD,
            (true, true, false) => Self::CHANGE_ARRAY_DWORD,
            (false, false, true) => Self::CHANGE_WORD_RAM,
            (false, true, true) => Self::CHANGE_DWORD_RAM,
            (true, false, true) => Self::CHANGE_ARRAY_WORD_RAM,
            (true, true, true) => Self::CHANGE_ARRAY_DWORD_RAM,
        }
    }

    /// The manual's name of the label ("Reserved" for 4, 5, 10, 15).
    pub fn meaning(self) -> &'static str {
        match self.0 {
            0 => "No order",
            1 => "Order parameter value",
            2 => "Change parameter value (word)",
            3 => "Change parameter value (double word)",
            6 => "Order parameter value (array)",
            7 => "Change parameter value (array, word)",
            8 => "Change parameter value (array, double word)",
            9 => "Order the number of array elements",
            11 => "Change parameter value (array, double word) without writing to the EEPROM",
            12 => "Change parameter value (array, word) without writing to the EEPROM",
            13 => "Change parameter value (double word) without writing to the EEPROM",
            14 => "Change parameter value (word) without writing to the EEPROM",
            _ => "Reserved",
        }
    }

    /// The labels that change a value.
    pub fn is_change(self) -> bool {
        matches!(self.0, 2 | 3 | 7 | 8 | 11..=14)
    }

    /// Labels 11–14 write RAM only (§2.5.6.3; P560 "Save in EEPROM" is the other way).
    pub fn is_ram_only(self) -> bool {
        matches!(self.0, 11..=14)
    }

    /// Labels that address an array element (IND bits 10–15 or 8–15 take effect: 6, 7, 8, 11,
    /// 12 per §2.5.6.3 "Parameter index IND").
    pub fn is_array(self) -> bool {
        matches!(self.0, 6..=8 | 11 | 12)
    }

    /// Labels that transfer a double word.
    pub fn is_dword(self) -> bool {
        matches!(self.0, 3 | 8 | 11 | 13)
    }

    /// The positive response labels of the order (§2.5.6.3 table, right-hand column). Empty for
    /// reserved labels: they are answered with AK 7.
    pub fn positive_responses(self) -> &'static [ResponseLabel] {
        match self.0 {
            0 => &[ResponseLabel::NONE],
            1 => &[ResponseLabel::WORD, ResponseLabel::DWORD],
            2 | 14 => &[ResponseLabel::WORD],
            3 | 13 => &[ResponseLabel::DWORD],
            6 => &[ResponseLabel::ARRAY_WORD, ResponseLabel::ARRAY_DWORD],
            7 | 12 => &[ResponseLabel::ARRAY_WORD],
            8 | 11 => &[ResponseLabel::ARRAY_DWORD],
            9 => &[ResponseLabel::ARRAY_LEN],
            _ => &[],
        }
    }
}

impl fmt::Debug for OrderLabel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "AK {} ({})", self.0, self.meaning())
    }
}

/// Response label AK, inverter → master (§2.5.6.3 "Meaning of response labels").
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ResponseLabel(pub u8);

impl ResponseLabel {
    /// 0: no response.
    pub const NONE: ResponseLabel = ResponseLabel(0);
    /// 1: transfer parameter value (word).
    pub const WORD: ResponseLabel = ResponseLabel(1);
    /// 2: transfer parameter value (double word).
    pub const DWORD: ResponseLabel = ResponseLabel(2);
    /// 4: transfer parameter value (array, word).
    pub const ARRAY_WORD: ResponseLabel = ResponseLabel(4);
    /// 5: transfer parameter value (array, double word).
    pub const ARRAY_DWORD: ResponseLabel = ResponseLabel(5);
    /// 6: transfer the number of array elements.
    pub const ARRAY_LEN: ResponseLabel = ResponseLabel(6);
    /// 7: order cannot be executed (error number in PWE2).
    pub const CANNOT_EXECUTE: ResponseLabel = ResponseLabel(7);

    /// The manual's name of the label.
    pub fn meaning(self) -> &'static str {
        match self.0 {
            0 => "No response",
            1 => "Transfer parameter value (word)",
            2 => "Transfer parameter value (double word)",
            4 => "Transfer parameter value (array, word)",
            5 => "Transfer parameter value (array, double word)",
            6 => "Transfer the number of array elements",
            7 => "Order cannot be executed",
            _ => "Undefined response label",
        }
    }
}

impl fmt::Debug for ResponseLabel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "AK {} ({})", self.0, self.meaning())
    }
}

/// Error number in PWE2 of a negative response (§2.5.6.3 "Meaning of error messages").
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ErrorNumber(pub u16);

impl ErrorNumber {
    /// 0: invalid parameter number.
    pub const INVALID_PNU: ErrorNumber = ErrorNumber(0);
    /// 1: parameter value cannot be changed.
    pub const NOT_CHANGEABLE: ErrorNumber = ErrorNumber(1);
    /// 2: lower or upper value limit exceeded.
    pub const LIMIT_EXCEEDED: ErrorNumber = ErrorNumber(2);
    /// 3: incorrect sub-index.
    pub const BAD_SUBINDEX: ErrorNumber = ErrorNumber(3);
    /// 4: no array.
    pub const NO_ARRAY: ErrorNumber = ErrorNumber(4);
    /// 5: invalid data type.
    pub const BAD_TYPE: ErrorNumber = ErrorNumber(5);
    /// 6: only resettable (only 0 may be written).
    pub const ONLY_RESET: ErrorNumber = ErrorNumber(6);
    /// 7: description element cannot be changed.
    pub const DESCRIPTION_FIXED: ErrorNumber = ErrorNumber(7);
    /// 9: description data not present.
    pub const NO_DESCRIPTION: ErrorNumber = ErrorNumber(9);
    /// 201: invalid order element in the last order received.
    pub const INVALID_ORDER: ErrorNumber = ErrorNumber(201);
    /// 202: internal response label cannot be depicted.
    pub const NO_RESPONSE_LABEL: ErrorNumber = ErrorNumber(202);

    /// Every error number the manuals list.
    pub const ALL: [ErrorNumber; 11] = [
        Self::INVALID_PNU,
        Self::NOT_CHANGEABLE,
        Self::LIMIT_EXCEEDED,
        Self::BAD_SUBINDEX,
        Self::NO_ARRAY,
        Self::BAD_TYPE,
        Self::ONLY_RESET,
        Self::DESCRIPTION_FIXED,
        Self::NO_DESCRIPTION,
        Self::INVALID_ORDER,
        Self::NO_RESPONSE_LABEL,
    ];

    /// The manual's meaning ("Unknown error number" for numbers it does not list).
    pub fn meaning(self) -> &'static str {
        match self.0 {
            0 => "Invalid parameter number",
            1 => "Parameter value cannot be changed",
            2 => "Lower or upper value limit exceeded",
            3 => "Incorrect sub-index",
            4 => "No array",
            5 => "Invalid data type",
            6 => "Only resettable (only 0 may be written)",
            7 => "Description element cannot be changed",
            9 => "Description data not present",
            201 => "Invalid order element in the last order received",
            202 => "Internal response label cannot be depicted",
            _ => "Unknown error number",
        }
    }
}

impl fmt::Debug for ErrorNumber {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "error {} ({})", self.0, self.meaning())
    }
}

/// The order labels a unit supports.
///
/// BU 0620 §2.5.6.3: "The SK 550P supports all of the above order codes. All other frequency
/// inverters connected to the NORD system bus only support the order codes 1, 2, 3, 6, 7 and
/// 8." Labels 9 and 11–14 are "only relevant for frequency inverters with a mounted bus
/// interface". `first` is the unit the interface is built into or mounted on (FI 1, or the
/// interface itself). BU 0590 §4.2.3.1 Tables 21/22: the SK TU3-PNT and its FI take label 9
/// and the RAM-only labels 11–14 ("to the frequency inverter or the technology units").
pub fn supported_orders(product: Product, first: bool) -> &'static [OrderLabel] {
    const ALL: &[OrderLabel] = &[
        OrderLabel::NONE,
        OrderLabel::REQUEST_VALUE,
        OrderLabel::CHANGE_WORD,
        OrderLabel::CHANGE_DWORD,
        OrderLabel::REQUEST_ARRAY_VALUE,
        OrderLabel::CHANGE_ARRAY_WORD,
        OrderLabel::CHANGE_ARRAY_DWORD,
        OrderLabel::REQUEST_ARRAY_LEN,
        OrderLabel::CHANGE_ARRAY_DWORD_RAM,
        OrderLabel::CHANGE_ARRAY_WORD_RAM,
        OrderLabel::CHANGE_DWORD_RAM,
        OrderLabel::CHANGE_WORD_RAM,
    ];
    const SYSTEM_BUS: &[OrderLabel] = &[
        OrderLabel::NONE,
        OrderLabel::REQUEST_VALUE,
        OrderLabel::CHANGE_WORD,
        OrderLabel::CHANGE_DWORD,
        OrderLabel::REQUEST_ARRAY_VALUE,
        OrderLabel::CHANGE_ARRAY_WORD,
        OrderLabel::CHANGE_ARRAY_DWORD,
    ];
    match (product.family(), first) {
        (Family::Integrated, true) => ALL,
        _ if product == Product::Tu3Pnt && first => ALL,
        _ => SYSTEM_BUS,
    }
}

/// The index word IND (§2.5.6.3 "Parameter index IND").
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Ind(pub u16);

impl Ind {
    /// IND for a parameter set and array element: set in bits 8–9 (0 = set 1), element in bits
    /// 10–15 (0 = element 1). For an array that does not depend on the parameter set, the
    /// element is the sub-index in bits 8–15.
    pub fn for_address(set: Option<ParamSet>, element: Option<ArrayElement>) -> Ind {
        match (set, element) {
            (None, None) => Ind(0),
            (Some(s), None) => Ind(u16::from(s.get() - 1) << 8),
            (Some(s), Some(e)) => {
                Ind((u16::from(e.get() - 1) << 10) | (u16::from(s.get() - 1) << 8))
            }
            (None, Some(e)) => Ind(u16::from(e.get() - 1) << 8),
        }
    }

    /// The word.
    pub fn raw(self) -> u16 {
        self.0
    }

    /// Parameter set, read as bits 8–9 (for set-dependent parameters).
    pub fn set(self) -> u8 {
        ((self.0 >> 8) & 0x03) as u8 + 1
    }

    /// Array element, read as bits 10–15 (arrays of set-dependent parameters).
    pub fn element(self) -> u8 {
        (self.0 >> 10) as u8 + 1
    }

    /// Sub-index, read as bits 8–15 (parameters that do not depend on the set), 0-based.
    pub fn subindex(self) -> u8 {
        (self.0 >> 8) as u8
    }

    /// The readings of the word that the manual allows, side by side.
    pub fn describe(self) -> String {
        if self.0 == 0 {
            return "set 1 / element 1".into();
        }
        format!(
            "set {} element {} | sub-index {}",
            self.set(),
            self.element(),
            self.subindex()
        )
    }
}

impl fmt::Debug for Ind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "IND {:04X}h ({})", self.0, self.describe())
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use rstest::rstest;

    #[test]
    fn p717_read_order_of_bu0620_2_5_6_4() {
        // BU 0620 §2.5.6.4 p. 58: data record 100, "16h,B5h, 00h,00h, 00h,00h, 00h,00h".
        let r = PkwRepr::parse(&[0x16, 0xB5, 0, 0, 0, 0, 0, 0]).unwrap();
        assert_eq!((r.ak, r.pnu, r.ind, r.pwe), (1, 1717, 0, 0));
        // Response "16h,B5h, 00h,00h, 00h,00h, 03h,FCh": AK 1, P717 = 1020.
        let a = PkwRepr::parse(&[0x16, 0xB5, 0, 0, 0, 0, 0x03, 0xFC]).unwrap();
        assert_eq!(a.value(), 1020);
        assert_eq!(a.emit_bytes(), [0x16, 0xB5, 0, 0, 0, 0, 0x03, 0xFC]);
    }

    #[test]
    fn p102_write_order_of_bu0620_2_5_6_4() {
        // p. 59: "24h, 4Eh, 01h, 00h, 00h, 00h, 00h, FAh": AK 2, PNU 1102, IND 0100h, 250.
        let r = PkwRepr::parse(&[0x24, 0x4E, 0x01, 0x00, 0, 0, 0, 0xFA]).unwrap();
        assert_eq!((r.ak, r.pnu, r.ind, r.value()), (2, 1102, 0x0100, 250));
        assert_eq!(
            OrderLabel(r.ak).positive_responses(),
            &[ResponseLabel::WORD]
        );
        assert_eq!(Ind(r.ind).set(), 2);
    }

    #[rstest]
    // §2.5.6.3 p. 57 examples. The rule ("0 = Array element 1") gives element 5 = 000100b and
    // element 21 = 010100b; the manual prints 000101b (1500h) and 010101b (5700h), one more than
    // its own rule: an erratum, recorded in suites/bu0620/pkw-ind.yaml.
    #[case(2, 5, 0x1100)]
    #[case(4, 21, 0x5300)]
    fn ind_examples(#[case] set: i64, #[case] element: i64, #[case] raw: u16) {
        let ind = Ind::for_address(
            Some(ParamSet::new(set).unwrap()),
            Some(ArrayElement::new(element).unwrap()),
        );
        assert_eq!(ind.raw(), raw);
        assert_eq!((ind.set(), ind.element()), (set as u8, element as u8));
    }

    #[test]
    fn negative_values_are_sign_filled() {
        let r = PkwRepr {
            ak: 2,
            pwe: (-5i32) as u32,
            ..Default::default()
        };
        assert_eq!(&r.emit_bytes()[4..], &[0xFF, 0xFF, 0xFF, 0xFB]);
        assert_eq!(PkwRepr::parse(&r.emit_bytes()).unwrap().value(), -5);
    }

    #[test]
    fn truncation_at_every_length() {
        let full = [0x16, 0xB5, 0, 0, 0, 0, 0, 0];
        for n in 0..PKW_LEN {
            assert_eq!(
                PkwRepr::parse(&full[..n]),
                Err(PkwError::Truncated { need: 8, got: n })
            );
        }
        let mut short = [0u8; 4];
        assert!(PkwRepr::default().emit(&mut short).is_err());
    }

    #[test]
    fn round_trip_every_label() {
        for ak in 0..16u8 {
            let r = PkwRepr {
                ak,
                spm: ak % 2 == 0,
                pnu: 2047,
                ind: 0xABCD,
                pwe: 0xDEAD_BEEF,
            };
            assert_eq!(PkwRepr::parse(&r.emit_bytes()), Ok(r));
        }
    }

    #[rstest]
    #[case(OrderLabel(1), &[1, 2])]
    #[case(OrderLabel(2), &[1])]
    #[case(OrderLabel(3), &[2])]
    #[case(OrderLabel(6), &[4, 5])]
    #[case(OrderLabel(7), &[4])]
    #[case(OrderLabel(8), &[5])]
    #[case(OrderLabel(9), &[6])]
    #[case(OrderLabel(11), &[5])]
    #[case(OrderLabel(12), &[4])]
    #[case(OrderLabel(13), &[2])]
    #[case(OrderLabel(14), &[1])]
    #[case(OrderLabel(4), &[])]
    #[case(OrderLabel(10), &[])]
    fn order_to_positive_response(#[case] order: OrderLabel, #[case] want: &[u8]) {
        let got: Vec<u8> = order.positive_responses().iter().map(|r| r.0).collect();
        assert_eq!(got, want);
    }

    #[test]
    fn supported_labels_per_unit() {
        assert_eq!(supported_orders(Product::Sk550p, true).len(), 12);
        assert!(!supported_orders(Product::Sk550p, false).contains(&OrderLabel::CHANGE_WORD_RAM));
        // BU 0590 §4.2.3.1 Tables 21/22: the SK TU3-PNT takes 9 and 11–14.
        assert_eq!(supported_orders(Product::Tu3Pnt, true).len(), 12);
    }

    #[test]
    fn order_fields_give_every_reading() {
        // BU 0590 §4.2.4.4: `70 66 02 00 00 00 03 E8`, AK 7 (array, word), P102, IND 0200h,
        // PWE 1000.
        let r = PkwRepr::parse(&[0x70, 0x66, 0x02, 0x00, 0x00, 0x00, 0x03, 0xE8]).unwrap();
        let f = r.order_fields();
        assert_eq!((f.ak, f.pnu, f.parameter, f.ind), (7, 0x66, 102, 0x0200));
        // IND 0200h: set 3 (bits 8–9 = 10b), element 1 (bits 10–15 = 0), sub-index 2.
        assert_eq!((f.set, f.element, f.subindex), (3, 1, 2));
        assert_eq!(f.label, "Change parameter value (array, word)");
        assert_eq!(f.value, Some(1000));
        assert_eq!(
            (f.array, f.dword, f.ram_only),
            (Some(true), Some(false), Some(false))
        );
        assert_eq!((f.error, f.error_meaning), (None, None));
        assert_eq!(f.meaning, r.describe_order());
        // A read order carries no value.
        let read = PkwRepr::parse(&[0x16, 0xB5, 0, 0, 0, 0, 0, 0]).unwrap();
        let f = read.order_fields();
        assert_eq!((f.pnu, f.parameter, f.value), (1717, 717, None));
    }

    #[test]
    fn response_fields_give_the_value_or_the_error() {
        // §2.5.6.4 p. 58: "16h,B5h, 00h,00h, 00h,00h, 03h,FCh": AK 1, P717 = 1020.
        let ok = PkwRepr::parse(&[0x16, 0xB5, 0, 0, 0, 0, 0x03, 0xFC]).unwrap();
        let f = ok.response_fields();
        assert_eq!(
            (f.ak, f.parameter, f.value, f.error),
            (1, 717, Some(1020), None)
        );
        assert_eq!(f.label, "Transfer parameter value (word)");
        assert_eq!(f.array, None);
        let refused = PkwRepr {
            ak: 7,
            pnu: 1102,
            pwe: 2,
            ..Default::default()
        };
        let f = refused.response_fields();
        assert_eq!((f.value, f.error), (None, Some(2)));
        assert_eq!(f.error_meaning, Some("Lower or upper value limit exceeded"));
        assert_eq!(f.meaning, refused.describe_response());
        assert_eq!(f.parameter, 102);
    }

    #[test]
    fn describe_in_manual_terms() {
        let r = PkwRepr::parse(&[0x70, 0x66, 0x02, 0x00, 0x00, 0x00, 0x03, 0xE8]).unwrap();
        let s = r.describe_order();
        assert!(
            s.contains("Change parameter value (array, word)") && s.contains("PWE 1000"),
            "{s}"
        );
        let e = PkwRepr {
            ak: 7,
            pnu: 1102,
            pwe: 2,
            ..Default::default()
        }
        .describe_response();
        assert!(
            e.contains("error 2 \"Lower or upper value limit exceeded\""),
            "{e}"
        );
    }

    /// The strategy of a PKW telegram, also for the PPO's properties that carry one.
    pub(crate) mod properties {
        use super::*;
        use proptest::prelude::*;

        /// Every telegram the codec represents: AK 4 bits, PNU 11 bits, IND and PWE whole.
        pub(crate) fn pkw_repr() -> impl Strategy<Value = PkwRepr> {
            (
                0u8..=15,
                any::<bool>(),
                0u16..=0x07FF,
                any::<u16>(),
                any::<u32>(),
            )
                .prop_map(|(ak, spm, pnu, ind, pwe)| PkwRepr {
                    ak,
                    spm,
                    pnu,
                    ind,
                    pwe,
                })
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn emit_then_parse_round_trips(r in pkw_repr()) {
                let mut buf = vec![0u8; r.buffer_len()];
                r.emit(&mut buf).unwrap();
                prop_assert_eq!(PkwRepr::parse(&buf).unwrap(), r);
                prop_assert_eq!(&r.emit_bytes()[..], &buf[..]);
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..16)) {
                let _ = PkwRepr::parse(&bytes);
            }
        }
    }
}
