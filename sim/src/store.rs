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
        // An ASCII text parameter takes 0 and its characters only (BU 2100 §7.1.2 P169).
        if !def.accepts(value) && def.text_from > 0 {
            return Err(AccessError::OutOfRange);
        }
        match def.access {
            Access::ReadOnly => return Err(AccessError::ReadOnly),
            Access::ResetOnly if value != 0 => return Err(AccessError::OnlyResettable),
            _ => {}
        }
        if !(def.min..=def.max).contains(&value) {
            return Err(AccessError::OutOfRange);
        }
        self.values.insert(key, value);
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

    /// P152 "Factory setting" of a bus module (BU 2100 §7.1.1, p. 46): 1 resets every setting
    /// parameter of the bus interface, 2 its basic parameters (the NORD standard parameters
    /// P15x: "the basic settings of the bus interface can be made via NORD standard
    /// parameters", §7.1.1), 3 the i-parameters P800…P830; P152 then returns to {0}.
    /// Information parameters (P17x/P18x) show the device's state and are not settings.
    pub fn load_module_factory_setting(&mut self) {
        let Some(value) = self.values.get(&(152, 0, 0)).copied() else {
            return;
        };
        let reset: fn(u16) -> bool = match value {
            1 => |_| true,
            2 => |n| (150..=159).contains(&n),
            3 => |n| (800..=830).contains(&n),
            _ => return,
        };
        let (product, owner) = (self.product, self.owner);
        self.values.retain(|&(number, _, _), _| {
            let setting = ParamNumber::new(i64::from(number))
                .ok()
                .and_then(|n| params::lookup(product, owner, n))
                .is_some_and(|d| d.access != Access::ReadOnly);
            !(setting && reset(number))
        });
        self.values.remove(&(152, 0, 0));
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
    fn info_parameters_are_set_by_the_device() {
        let mut s = ParamStore::new(Product::Sk550p, fi1());
        s.set_info(717, 1, 1020);
        assert_eq!(s.read(n(717), None, None), Ok(1020));
        s.set_info(1000, 1, 5);
    }

    #[test]
    fn p152_loads_the_factory_settings_and_returns_to_0() {
        // BU 2100 §7.1.1 (p. 46): 1 all, 2 the basic (P15x) parameters; then P152 = {0}.
        let mut s = ParamStore::new(Product::Tu4Eip, Target::Interface);
        let e4 = ArrayElement::new(4).ok();
        s.write(n(151), None, None, 200, Persist::Eeprom).unwrap();
        s.write(n(160), None, e4, 7, Persist::Eeprom).unwrap();
        s.set_info(185, 4, 7);
        s.write(n(152), None, None, 2, Persist::Eeprom).unwrap();
        s.load_module_factory_setting();
        assert_eq!(s.read(n(151), None, None), Ok(0));
        assert_eq!(s.read(n(160), None, e4), Ok(7), "no basic parameter");
        assert_eq!(s.read(n(152), None, None), Ok(0));
        s.write(n(151), None, None, 200, Persist::Eeprom).unwrap();
        s.write(n(152), None, None, 1, Persist::Eeprom).unwrap();
        s.load_module_factory_setting();
        assert_eq!(s.read(n(151), None, None), Ok(0));
        assert_eq!(s.read(n(160), None, e4), Ok(100));
        assert_eq!(s.read(n(185), None, e4), Ok(7), "information stays");
        assert_eq!(s.read(n(152), None, None), Ok(0));
    }

    #[test]
    fn text_parameters_take_0_and_their_characters() {
        // BU 2100 §7.1.2 P169: ASCII 45…122, factory {0}.
        let mut s = ParamStore::new(Product::Tu3Eip, Target::Interface);
        let e1 = ArrayElement::new(1).ok();
        for (value, ok) in [
            (0, true),
            (1, false),
            (44, false),
            (45, true),
            (122, true),
            (123, false),
        ] {
            let r = s.write(n(169), None, e1, value, Persist::Eeprom);
            assert_eq!(r.is_ok(), ok, "{value}: {r:?}");
        }
    }
}
