//! A unit's parameter store: values per parameter set and array element, checked against the
//! catalogue (`proto::nord::params`), with EEPROM writes counted.
//!
//! The EEPROM allows 100,000 write cycles (BU 0620 §2.5.6 "Max. 100,000 permissible writing
//! cycles"); order labels 11–14 write RAM only, and so does every write while P560 "Save in
//! EEPROM" is 0 (§2.5.6: "via the parameter P560 Save in EEPROM"), so the store counts only
//! EEPROM writes.

use std::collections::BTreeMap;

use proto::nord::params::{self, Access, Owner, ParamDef};
use proto::nord::pnio::{self, IpSuite};
use proto::nord::{ArrayElement, Inverter, ParamNumber, ParamSet, Product};

/// P560 "Save in EEPROM" (BU 0620 §2.5.6): 0 keeps parameter changes in RAM only.
const SAVE_IN_EEPROM: u16 = 560;

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

#[cfg(test)]
impl AccessError {
    /// Every refusal a store gives, for the tests that map each one.
    pub(crate) const ALL: [AccessError; 6] = [
        AccessError::NoSuchParameter,
        AccessError::ReadOnly,
        AccessError::OutOfRange,
        AccessError::BadSubIndex,
        AccessError::NotAnArray,
        AccessError::OnlyResettable,
    ];
}

/// A unit's parameters.
#[derive(Debug, Clone)]
pub struct ParamStore {
    product: Product,
    owner: Owner,
    /// (number, set 0..3, element 0..) → value; absent = factory setting.
    values: BTreeMap<(u16, u8, u8), i32>,
    eeprom_writes: u64,
    /// SK TU3-PNT: the IP address P160 and mask P161 last saved (`None`: the factory's).
    saved_ip: Option<[[i32; 4]; 2]>,
    /// Elements [-01]..[-03] of P850/P851/P852 entered under PROFINET IO and not saved yet
    /// (see [`ParamStore::write`]): (number, element index 0..2) → value.
    entered: BTreeMap<(u16, u8), i32>,
    /// Counts changes to the parameters a user can set (all but the read-only information
    /// parameters the device itself shows): a copy of settings taken at one revision is
    /// current while it stays (the drive's, `device::Settings`, read on every bus cycle).
    settings_revision: u64,
}

/// The SK 550P's IP parameters whose new value PROFINET IO saves only once element [-04] is
/// entered (BU 0620 §3.8.1 p. 72, §4.2.4 p. 82–83: P850 IP address, P851 sub-net mask, P852
/// gateway).
const IP_PARAMETERS: [u16; 3] = [850, 851, 852];
/// P870 "Present bus protocol" 1 = PROFINET IO (BU 0620 §4.3).
const PROFINET_IO: i32 = 1;

/// Whether `ip` with `mask` is an IP setting the interface saves: a host address of its
/// network (`proto::nord::pnio::check_ip_suite`: not the network or broadcast address, no
/// loopback) under a mask that conforms with it (`mask_conforms`: contiguous, no shorter than
/// the address's class mask — the reading BU 0590's P161 example gives).
fn conforms(ip: [u8; 4], mask: [u8; 4]) -> bool {
    let suite = IpSuite {
        ip: ip.into(),
        mask: mask.into(),
        gateway: std::net::Ipv4Addr::UNSPECIFIED,
    };
    pnio::check_ip_suite(&suite).is_ok() && pnio::mask_conforms(ip.into(), mask.into())
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
            settings_revision: 0,
            eeprom_writes: 0,
            saved_ip: None,
            entered: BTreeMap::new(),
        }
    }

    /// The product the unit belongs to.
    pub fn product(&self) -> Product {
        self.product
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
        self.settings_revision += 1;
        // An ASCII text parameter takes 0 and its characters only (BU 2100 §7.1.2 P169).
        if !def.accepts(value) && def.text_from > 0 {
            return Err(AccessError::OutOfRange);
        }
        match def.access {
            Access::ReadOnly => return Err(AccessError::ReadOnly),
            Access::ResetOnly if value != 0 => return Err(AccessError::OnlyResettable),
            _ => {}
        }
        if !(def.min..=def.max).contains(&value) || !params::value_allowed(def, self.product, value)
        {
            return Err(AccessError::OutOfRange);
        }
        if let Some(ip_param) = self.ip_parameter(def) {
            self.values.insert(key, value);
            // [-01]…[-03] wait in RAM for [-04]
            if key.2 == 3 {
                self.save_ip(ip_param, persist);
            }
            return Ok(());
        }
        if self.profinet_ip(def.number) {
            return self.enter_ip(key, value, persist);
        }
        self.values.insert(key, value);
        // P560 itself is always saved, so that the choice outlives a power-off.
        if persist == Persist::Eeprom && (def.number == SAVE_IN_EEPROM || self.saves_to_eeprom()) {
            self.eeprom_writes += 1;
        }
        Ok(())
    }

    /// SK TU3-PNT P160 / P161 (0 / 1): "only saved by writing it to Index 4" (BU 0590 §5.1.2).
    fn ip_parameter(&self, def: &ParamDef) -> Option<usize> {
        let module = self.product == Product::Tu3Pnt && self.owner == Owner::Interface;
        match def.number {
            160 if module => Some(0),
            161 if module => Some(1),
            _ => None,
        }
    }

    fn ip_values(&self, number: u16) -> [i32; 4] {
        let n = ParamNumber::new(i64::from(number)).ok();
        std::array::from_fn(|e| {
            n.and_then(|n| {
                self.read(n, None, ArrayElement::new(e as i64 + 1).ok())
                    .ok()
            })
            .unwrap_or(0)
        })
    }

    fn set_ip_values(&mut self, number: u16, octets: [i32; 4]) {
        for (e, v) in (0u8..).zip(octets) {
            self.values.insert((number, 0, e), v);
        }
    }

    /// Index [-04] of P160 (`which` 0) or P161 (1) was written (BU 0590 §5.1.2, p. 34): the
    /// address is saved unless it is against the convention; a mask that contradicts the saved
    /// address is corrected when the address is written (P160: "the mask is corrected
    /// automatically") and not saved when the mask is written (P161: "Saving is prevented"); in
    /// both refusals the parameters show what was saved before. 0.0.0.0 deletes the settings.
    fn save_ip(&mut self, which: usize, persist: Persist) {
        let saved = self
            .saved_ip
            .unwrap_or([self.factory_ip(160), self.factory_ip(161)]);
        let (ip, mut mask) = (self.ip_values(160), self.ip_values(161));
        let addr = |o: [i32; 4]| std::net::Ipv4Addr::from(o.map(|b| b as u8));
        let conforms =
            |ip: [i32; 4], mask: [i32; 4]| conforms(ip.map(|b| b as u8), mask.map(|b| b as u8));
        let ok = if ip == [0; 4] {
            mask = [0; 4];
            true
        } else if conforms(ip, mask) {
            true
        } else if which == 0 {
            // P160: the mask is corrected to the address's class, then the address is checked.
            mask = pnio::corrected_mask(addr(ip), addr(mask))
                .octets()
                .map(i32::from);
            conforms(ip, mask)
        } else {
            false
        };
        let keep = if ok { [ip, mask] } else { saved };
        self.set_ip_values(160, keep[0]);
        self.set_ip_values(161, keep[1]);
        if ok {
            self.saved_ip = Some(keep);
            if persist == Persist::Eeprom {
                self.eeprom_writes += 1;
            }
        }
    }

    fn factory_ip(&self, number: u16) -> [i32; 4] {
        let def = ParamNumber::new(i64::from(number))
            .ok()
            .and_then(|n| self.def(n));
        std::array::from_fn(|e| def.map_or(0, |d| params::element_default(d, e as u8 + 1)))
    }

    /// Loads the factory settings of the setting parameters `which` selects by number
    /// (information parameters keep what the device shows): a module's P152 "Factory setting"
    /// (see `Device::factory_setting`).
    pub fn load_factory_settings(&mut self, which: fn(u16) -> bool) {
        let (product, owner) = (self.product, self.owner);
        self.settings_revision += 1;
        if which(160) {
            self.saved_ip = None;
        }
        self.values.retain(|&(number, _, _), _| {
            let setting = ParamNumber::new(i64::from(number))
                .ok()
                .and_then(|n| params::lookup(product, owner, n))
                .is_some_and(|d| d.access != Access::ReadOnly);
            !(setting && which(number))
        });
        self.eeprom_writes += 1;
    }

    /// Whether parameter changes reach the EEPROM: P560 "Save in EEPROM" is not 0 (RAM only),
    /// or the unit has no P560 (the bus interface).
    fn saves_to_eeprom(&self) -> bool {
        ParamNumber::new(i64::from(SAVE_IN_EEPROM))
            .ok()
            .and_then(|n| self.read(n, None, None).ok())
            .is_none_or(|v| v != 0)
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
            850 if !conforms(new, self.ip4(851)) => {
                // "The IP sub-net mask is corrected automatically": to the address's class.
                if let Some(mask) = pnio::class_mask(new.into()) {
                    save.push((851, mask.octets()));
                }
            }
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
        if let Ok((def, key)) = self.key(n, None, e) {
            if self.values.insert(key, value) != Some(value) && def.access != Access::ReadOnly {
                self.settings_revision += 1;
            }
        }
    }

    /// The revision of the settings: it changes whenever a parameter other than a read-only
    /// one may have changed.
    pub fn settings_revision(&self) -> u64 {
        self.settings_revision
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
    fn p560_zero_keeps_changes_in_ram() {
        let mut s = ParamStore::new(Product::Sk550p, fi1());
        s.write(n(560), None, None, 0, Persist::Eeprom).unwrap();
        assert_eq!(s.eeprom_writes(), 1, "P560 itself is saved");
        s.write(n(102), None, None, 300, Persist::Eeprom).unwrap();
        assert_eq!(s.read(n(102), None, None), Ok(300));
        assert_eq!(s.eeprom_writes(), 1);
        s.write(n(560), None, None, 1, Persist::Eeprom).unwrap();
        s.write(n(102), None, None, 400, Persist::Eeprom).unwrap();
        assert_eq!(s.eeprom_writes(), 3);
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
    fn tu3_pnt_device_name_and_factory_settings() {
        // BU 0590 §5.1.2 P162: ASCII 45…122 and the closing 0; §5.1.1 P152 = 1 loads the
        // factory settings (P160 back to 192.168.20.200).
        let mut s = ParamStore::new(Product::Tu3Pnt, Target::Interface);
        assert_eq!(
            s.write(n(162), None, None, 44, Persist::Eeprom),
            Err(AccessError::OutOfRange)
        );
        assert_eq!(s.write(n(162), None, None, 45, Persist::Eeprom), Ok(()));
        assert_eq!(s.write(n(162), None, None, 0, Persist::Eeprom), Ok(()));
        let e1 = ArrayElement::new(1).ok();
        s.write(n(160), None, e1, 10, Persist::Eeprom).unwrap();
        s.set_info(172, 1, 2);
        s.load_factory_settings(|_| true);
        assert_eq!(s.read(n(160), None, e1), Ok(192));
        assert_eq!(s.read(n(172), None, None), Ok(2));
    }

    #[test]
    fn tu3_pnt_ip_saved_by_index_4() {
        // BU 0590 §5.1.2 P160/P161 (p. 34).
        let mut s = ParamStore::new(Product::Tu3Pnt, Target::Interface);
        let e = |i: i64| ArrayElement::new(i).ok();
        let w = |s: &mut ParamStore, p: i64, i: i64, v: i32| {
            s.write(n(p), None, e(i), v, Persist::Eeprom).unwrap();
        };
        w(&mut s, 160, 1, 10);
        assert_eq!(s.eeprom_writes(), 0);
        w(&mut s, 160, 4, 5);
        assert_eq!(s.eeprom_writes(), 1);
        assert_eq!(s.read(n(160), None, e(1)), Ok(10));
        // 10.168.20.5 / 255.0.0.0 would fit, but back to the class C example: not saved.
        w(&mut s, 160, 1, 192);
        w(&mut s, 161, 2, 0);
        w(&mut s, 161, 3, 0);
        w(&mut s, 161, 4, 0);
        assert_eq!(s.eeprom_writes(), 1);
        assert_eq!(s.read(n(161), None, e(2)), Ok(255));
        assert_eq!(s.read(n(160), None, e(1)), Ok(10));
        // Against the convention (loopback): not saved.
        w(&mut s, 160, 1, 127);
        w(&mut s, 160, 4, 1);
        assert_eq!(s.eeprom_writes(), 1);
        assert_eq!(s.read(n(160), None, e(1)), Ok(10));
        // A mask that contradicts the address is corrected when the address is written.
        w(&mut s, 161, 3, 0);
        w(&mut s, 160, 1, 192);
        w(&mut s, 160, 4, 7);
        assert_eq!(s.eeprom_writes(), 2);
        assert_eq!(s.read(n(161), None, e(3)), Ok(255));
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

    #[test]
    fn factory_settings_of_a_group_or_all() {
        // BU 2100 §7.1.1 (p. 46): P152 = 1 all, 2 the basic (P15x) parameters.
        let mut s = ParamStore::new(Product::Tu4Eip, Target::Interface);
        let e4 = ArrayElement::new(4).ok();
        s.write(n(151), None, None, 200, Persist::Eeprom).unwrap();
        s.write(n(160), None, e4, 7, Persist::Eeprom).unwrap();
        s.set_info(185, 4, 7);
        s.load_factory_settings(|n| (150..=159).contains(&n));
        assert_eq!(s.read(n(151), None, None), Ok(0));
        assert_eq!(s.read(n(160), None, e4), Ok(7), "no basic parameter");
        s.write(n(151), None, None, 200, Persist::Eeprom).unwrap();
        s.load_factory_settings(|_| true);
        assert_eq!(s.read(n(151), None, None), Ok(0));
        assert_eq!(s.read(n(160), None, e4), Ok(100));
        assert_eq!(s.read(n(185), None, e4), Ok(7), "information stays");
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
