//! A unit's parameter store: values per parameter set and array element, checked against the
//! catalogue (`proto::nord::params`), with EEPROM writes counted.
//!
//! The EEPROM allows 100,000 write cycles (BU 0620 §2.5.6 "Max. 100,000 permissible writing
//! cycles"); order labels 11–14 write RAM only, so the store counts only EEPROM writes.

use std::collections::BTreeMap;

use proto::nord::params::{self, Access, Owner, ParamDef};
use proto::nord::{ArrayElement, Inverter, ParamNumber, ParamSet, Product};

/// Where an order goes: the bus interface's own parameters, or an inverter's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Target {
    /// The bus interface (data record 100).
    Interface,
    /// An inverter.
    Inverter(Inverter),
}

/// Whether a write goes to EEPROM or RAM only (order labels 11–14, BU 0620 §2.5.6.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Persist {
    /// Stored permanently.
    Eeprom,
    /// Lost at power-off.
    RamOnly,
}

/// Why an access was refused; the order server maps it to a parameter-channel error number.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum AccessError {
    /// The unit has no such parameter.
    #[error("no such parameter")]
    NoSuchParameter,
    /// An information parameter.
    #[error("parameter is read-only")]
    ReadOnly,
    /// Outside min..=max.
    #[error("value out of range")]
    OutOfRange,
    /// Array element beyond the array.
    #[error("array element does not exist")]
    BadSubIndex,
    /// An element was given for a plain parameter.
    #[error("parameter is not an array")]
    NotAnArray,
    /// Only 0 may be written.
    #[error("only 0 may be written")]
    OnlyResettable,
}

/// A unit's parameters.
#[derive(Debug, Clone)]
pub struct ParamStore {
    product: Product,
    owner: Owner,
    /// (number, set 0..3, element 0..) → value; absent = factory setting.
    values: BTreeMap<(u16, u8, u8), i32>,
    eeprom_writes: u64,
    /// Elements [-01]..[-03] of P850/P851/P852 entered under PROFINET IO and not saved yet
    /// (see [`ParamStore::write`]): (number, element index 0..2) → value.
    entered: BTreeMap<(u16, u8), i32>,
}

/// The SK 550P's IP parameters whose new value PROFINET IO saves only once element [-04] is
/// entered (BU 0620 §3.8.1 p. 72, §4.2.4 p. 82–83: P850 IP address, P851 sub-net mask, P852
/// gateway).
const IP_PARAMETERS: [u16; 3] = [850, 851, 852];
/// P870 "Present bus protocol" 1 = PROFINET IO (BU 0620 §4.3).
const PROFINET_IO: i32 = 1;

/// Whether `ip` is a host address of a network under `mask`: the mask's ones are contiguous
/// and the host part is neither all zeros (the network) nor all ones (broadcast).
pub fn conforms(ip: [u8; 4], mask: [u8; 4]) -> bool {
    let (ip, mask) = (u32::from_be_bytes(ip), u32::from_be_bytes(mask));
    let host = !mask;
    let contiguous = host & host.wrapping_add(1) == 0;
    mask != 0 && host != 0 && contiguous && ip & host != 0 && ip & host != host
}

/// The sub-net mask an IP address that does not conform with the entered one is corrected to:
/// the mask of its address class (A /8, B /16, C /24). BU 0620 §3.8.1 only says the mask "is
/// corrected automatically".
pub fn class_mask(ip: [u8; 4]) -> [u8; 4] {
    match ip[0] {
        0..=127 => [255, 0, 0, 0],
        128..=191 => [255, 255, 0, 0],
        _ => [255, 255, 255, 0],
    }
}

impl ParamStore {
    /// A store with factory settings.
    pub fn new(product: Product, target: Target) -> Self {
        let owner = match target {
            Target::Interface => Owner::Interface,
            Target::Inverter(_) => Owner::Inverter,
        };
        ParamStore {
            product,
            owner,
            values: BTreeMap::new(),
            eeprom_writes: 0,
            entered: BTreeMap::new(),
        }
    }

    /// The catalogue entry of a parameter this unit has.
    pub fn def(&self, number: ParamNumber) -> Option<&'static ParamDef> {
        params::lookup(self.product, self.owner, number)
    }

    /// Resolves set and element to storage indices (set `None` = set 1; element `None` = 1).
    fn key(
        &self,
        number: ParamNumber,
        set: Option<ParamSet>,
        element: Option<ArrayElement>,
    ) -> Result<(&'static ParamDef, (u16, u8, u8)), AccessError> {
        let def = self.def(number).ok_or(AccessError::NoSuchParameter)?;
        let set = if def.set_dependent {
            set.map_or(0, |s| s.get() - 1)
        } else {
            0
        };
        let element = match (def.array, element) {
            (None, Some(e)) if e.get() > 1 => return Err(AccessError::NotAnArray),
            (None, _) => 0,
            (Some(n), Some(e)) if e.get() > n => return Err(AccessError::BadSubIndex),
            (Some(_), e) => e.map_or(0, |e| e.get() - 1),
        };
        Ok((def, (def.number, set, element)))
    }

    /// Reads a value.
    pub fn read(
        &self,
        number: ParamNumber,
        set: Option<ParamSet>,
        element: Option<ArrayElement>,
    ) -> Result<i32, AccessError> {
        let (def, key) = self.key(number, set, element)?;
        Ok(self
            .values
            .get(&key)
            .copied()
            .unwrap_or_else(|| params::element_default(def, key.2 + 1)))
    }

    /// Writes a value through the parameter channel.
    pub fn write(
        &mut self,
        number: ParamNumber,
        set: Option<ParamSet>,
        element: Option<ArrayElement>,
        value: i32,
        persist: Persist,
    ) -> Result<(), AccessError> {
        let (def, key) = self.key(number, set, element)?;
        match def.access {
            Access::ReadOnly => return Err(AccessError::ReadOnly),
            Access::ResetOnly if value != 0 => return Err(AccessError::OnlyResettable),
            _ => {}
        }
        if !(def.min..=def.max).contains(&value) {
            return Err(AccessError::OutOfRange);
        }
        if self.profinet_ip(def.number) {
            return self.enter_ip(key, value, persist);
        }
        self.values.insert(key, value);
        if persist == Persist::Eeprom {
            self.eeprom_writes += 1;
        }
        Ok(())
    }

    /// Whether `number` is an IP parameter of the SK 550P's interface under PROFINET IO.
    fn profinet_ip(&self, number: u16) -> bool {
        self.owner == Owner::Interface
            && self.product == Product::Sk550p
            && IP_PARAMETERS.contains(&number)
            && self.values.get(&(870, 0, 0)) == Some(&PROFINET_IO)
    }

    /// The four elements of an IP parameter as stored.
    fn ip4(&self, number: u16) -> [u8; 4] {
        let def = ParamNumber::new(i64::from(number))
            .ok()
            .and_then(|n| self.def(n));
        std::array::from_fn(|i| {
            let value = self
                .values
                .get(&(number, 0, i as u8))
                .copied()
                .unwrap_or_else(|| def.map_or(0, |d| params::element_default(d, i as u8 + 1)));
            u8::try_from(value).unwrap_or(0)
        })
    }

    /// PROFINET IO (BU 0620 §4.2.4, §3.8.1): a new IP address, sub-net mask or gateway "is
    /// only saved after a value is entered in the element [-04]" — elements [-01]..[-03] are
    /// held until then. On [-04] the new address is saved and a mask it does not conform with
    /// is corrected (to the class mask); a new mask that does not conform with the address
    /// in P850 is not saved.
    fn enter_ip(
        &mut self,
        key: (u16, u8, u8),
        value: i32,
        persist: Persist,
    ) -> Result<(), AccessError> {
        let (number, _, element) = key;
        if element < 3 {
            self.entered.insert((number, element), value);
            return Ok(());
        }
        let mut new = self.ip4(number);
        for (i, b) in new.iter_mut().enumerate().take(3) {
            if let Some(v) = self.entered.remove(&(number, i as u8)) {
                *b = u8::try_from(v).unwrap_or(0);
            }
        }
        new[3] = u8::try_from(value).unwrap_or(0);
        let mut save = vec![(number, new)];
        match number {
            850 if !conforms(new, self.ip4(851)) => save.push((851, class_mask(new))),
            851 if !conforms(self.ip4(850), new) => return Ok(()),
            _ => {}
        }
        for (n, bytes) in save {
            for (i, b) in bytes.iter().enumerate() {
                self.values.insert((n, 0, i as u8), i32::from(*b));
            }
        }
        if persist == Persist::Eeprom {
            self.eeprom_writes += 1;
        }
        Ok(())
    }

    /// Elements of an array parameter.
    pub fn array_len(&self, number: ParamNumber) -> Result<u8, AccessError> {
        self.def(number)
            .ok_or(AccessError::NoSuchParameter)?
            .array
            .ok_or(AccessError::NotAnArray)
    }

    /// Sets an information parameter from the device's own state (actual values, status);
    /// ignores numbers the unit does not have.
    pub fn set_info(&mut self, number: u16, element: u8, value: i32) {
        let Ok(n) = ParamNumber::new(i64::from(number)) else {
            return;
        };
        let e = ArrayElement::new(i64::from(element)).ok();
        if let Ok((_, key)) = self.key(n, None, e) {
            self.values.insert(key, value);
        }
    }

    /// EEPROM writes so far.
    pub fn eeprom_writes(&self) -> u64 {
        self.eeprom_writes
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn n(v: i64) -> ParamNumber {
        ParamNumber::new(v).unwrap()
    }
    fn fi1() -> Target {
        Target::Inverter(Inverter::new(1).unwrap())
    }

    #[test]
    fn sets_are_separate_and_ram_writes_are_not_counted() {
        let mut s = ParamStore::new(Product::Sk550p, fi1());
        let set3 = ParamSet::new(3).ok();
        s.write(n(102), set3, None, 1000, Persist::Eeprom).unwrap();
        assert_eq!(s.read(n(102), set3, None), Ok(1000));
        assert_eq!(s.read(n(102), None, None), Ok(200));
        s.write(n(102), None, None, 300, Persist::RamOnly).unwrap();
        assert_eq!(s.eeprom_writes(), 1);
    }

    #[test]
    fn refusals() {
        let mut s = ParamStore::new(Product::Sk550p, fi1());
        assert_eq!(
            s.read(n(999), None, None),
            Err(AccessError::NoSuchParameter)
        );
        assert_eq!(
            s.write(n(717), None, None, 1, Persist::Eeprom),
            Err(AccessError::ReadOnly)
        );
        assert_eq!(
            s.write(n(102), None, None, 32001, Persist::Eeprom),
            Err(AccessError::OutOfRange)
        );
        assert_eq!(
            s.read(n(543), None, ArrayElement::new(6).ok()),
            Err(AccessError::BadSubIndex)
        );
        assert_eq!(
            s.read(n(102), None, ArrayElement::new(2).ok()),
            Err(AccessError::NotAnArray)
        );
        assert_eq!(s.array_len(n(543)), Ok(5));
        assert_eq!(s.eeprom_writes(), 0);
    }

    #[test]
    fn profinet_saves_ip_parameters_with_element_4() {
        let e = |i: i64| ArrayElement::new(i).ok();
        let mut s = ParamStore::new(Product::Sk550p, Target::Interface);
        for (i, b) in [192, 168, 20, 200].into_iter().enumerate() {
            s.set_info(850, i as u8 + 1, b);
        }
        // Not under PROFINET: every element is saved at once.
        s.write(n(852), None, e(1), 10, Persist::Eeprom).unwrap();
        assert_eq!(s.read(n(852), None, e(1)), Ok(10));
        s.set_info(870, 1, PROFINET_IO);
        s.write(n(852), None, e(1), 192, Persist::Eeprom).unwrap();
        assert_eq!(s.read(n(852), None, e(1)), Ok(10), "held until [-04]");
        s.write(n(852), None, e(4), 1, Persist::Eeprom).unwrap();
        assert_eq!(s.read(n(852), None, e(1)), Ok(192));
        // A mask the address is no host of is not saved: 192.168.20.200 under /30 is 200 & 3 = 0.
        s.write(n(851), None, e(4), 252, Persist::Eeprom).unwrap();
        assert_eq!(s.read(n(851), None, e(4)), Ok(0));
        // An address the mask does not fit (10.0.0.255 is a broadcast under /24): corrected.
        for (i, b) in [10, 0, 0, 255].into_iter().enumerate() {
            s.write(n(850), None, e(i as i64 + 1), b, Persist::Eeprom)
                .unwrap();
        }
        assert_eq!(s.read(n(850), None, e(1)), Ok(10));
        assert_eq!(
            (1..=4)
                .map(|i| s.read(n(851), None, e(i)).unwrap())
                .collect::<Vec<_>>(),
            [255, 0, 0, 0]
        );
    }

    #[rstest::rstest]
    #[case([192, 168, 20, 200], [255, 255, 255, 0], true)]
    #[case([192, 168, 20, 0], [255, 255, 255, 0], false)]
    #[case([192, 168, 20, 255], [255, 255, 255, 0], false)]
    #[case([192, 168, 20, 200], [255, 0, 255, 0], false)]
    #[case([10, 0, 0, 255], [255, 0, 0, 0], true)]
    fn conformance(#[case] ip: [u8; 4], #[case] mask: [u8; 4], #[case] ok: bool) {
        assert_eq!(conforms(ip, mask), ok);
    }

    #[test]
    fn info_parameters_are_set_by_the_device() {
        let mut s = ParamStore::new(Product::Sk550p, fi1());
        s.set_info(717, 1, 1020);
        assert_eq!(s.read(n(717), None, None), Ok(1020));
        s.set_info(1000, 1, 5);
    }
}
