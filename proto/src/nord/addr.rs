//! Protocol addresses of a parameter: the formulas of every manual.
//!
//! | protocol | formula | source |
//! |---|---|---|
//! | EtherCAT CoE | index 2000h + 800h·(FI−1) + P | BU 0620 §2.2.7 p. 20 |
//! | POWERLINK SDO (SK 550P) | index 2000h + 600h·(FI−1) + P | BU 0620 §2.4.6 p. 36 |
//! | POWERLINK SDO (modules) | index 2000h (interface) / 2000h + 800h·FI + P, FU1..FU4 only | BU 2200 §6.4 (German) |
//! | EtherNet/IP CIP | class 100 + FI (100 = module), attribute P, instance from set and element | BU 0620 §2.3.5, BU 2100 §6 |
//! | PROFINET | data record 100 + FI (100 = interface), PNU P + 1000 | BU 0620 §2.5.6.2, BU 0590 §4.2.2 |
//! | System bus | CAN ID 32 + 2·(FI−1), absolute encoder + 1 | BU 0620 §3.1 p. 61 |
//!
//! Sub-indices (CoE and POWERLINK) and CIP instances share one rule: plain parameters 0;
//! set-dependent ones the set (1..4; CIP: 0..3); arrays the element (1..; CIP 0..); arrays per set
//! 4·(element−1) + set (CIP: 4·(element−1) + set − 1). Sub-index 0 holds the array size.

use std::fmt;

use serde::Serialize;

use super::mutant::Constant;

use super::pkw::Ind;
use super::product::{Product, Protocol};
use super::types::{ArrayElement, Inverter, ParamAddress, ParamNumber, ParamSet};

/// An address that cannot be formed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum AddrError {
    /// The product does not reach that many inverters.
    #[error("{product} reaches FI 1..{max}, not FI {inverter}")]
    NoSuchInverter {
        /// Product name.
        product: &'static str,
        /// Inverter asked for.
        inverter: u8,
        /// Its maximum.
        max: u8,
    },
    /// The product carries the inverter, but the manual's SDO device-id table has no row for
    /// it: BU 2200 §6.4 lists FU1..FU4, the SK TU3-POL carries FU1..FU8
    /// ([`super::epl::device_id_inverters`]).
    #[error("BU 2200 §6.4 lists no SDO device id for FU{inverter}: its table ends at FU{last} (the {product} carries FU{inverter} in process data and on its system bus only)")]
    NoDeviceId {
        /// Product name.
        product: &'static str,
        /// Inverter asked for.
        inverter: u8,
        /// The last inverter the table lists.
        last: u8,
    },
    /// The product does not speak the protocol.
    #[error("{product} does not speak {protocol:?}")]
    NoProtocol {
        /// Product name.
        product: &'static str,
        /// Protocol asked for.
        protocol: Protocol,
    },
}

fn check(product: Product, protocol: Protocol, inverter: Inverter) -> Result<(), AddrError> {
    if !product.protocols().contains(&protocol) {
        return Err(AddrError::NoProtocol {
            product: product.name(),
            protocol,
        });
    }
    if inverter.get() > product.max_inverters() {
        return Err(AddrError::NoSuchInverter {
            product: product.name(),
            inverter: inverter.get(),
            max: product.max_inverters(),
        });
    }
    Ok(())
}

/// The sub-index of CoE and POWERLINK SDOs (BU 0620 §2.4.6 sub-index table).
pub fn sdo_subindex(set: Option<ParamSet>, element: Option<ArrayElement>) -> u8 {
    match (set, element) {
        (None, None) => 0,
        (Some(s), None) => s.get(),
        (None, Some(e)) => e.get(),
        (Some(s), Some(e)) => (e.get() - 1).saturating_mul(4).saturating_add(s.get()),
    }
}

/// The CIP instance (BU 0620 §2.3.5: set in bits 0–1, element above).
pub fn cip_instance(set: Option<ParamSet>, element: Option<ArrayElement>) -> u16 {
    let s = set.map_or(0, |s| u16::from(s.get() - 1));
    match element {
        None => s,
        Some(e) if set.is_some() => (u16::from(e.get()) - 1) * 4 + s,
        Some(e) => u16::from(e.get()) - 1,
    }
}

/// The set and element a CIP instance addresses, given the parameter's structure — the inverse
/// of [`cip_instance`]. `None` when the instance names no set/element of that parameter.
pub fn cip_decode_instance(
    instance: u32,
    set_dependent: bool,
    array: Option<u8>,
) -> Option<(Option<ParamSet>, Option<ArrayElement>)> {
    let (set, element) = match (set_dependent, array) {
        (false, None) => (None, None),
        (true, None) => (Some(instance), None),
        (false, Some(_)) => (None, Some(instance)),
        (true, Some(_)) => (Some(instance % 4), Some(instance / 4)),
    };
    if !set_dependent && array.is_none() && instance != 0 {
        return None;
    }
    let set = match set {
        Some(s) => Some(ParamSet::new(i64::from(s) + 1).ok()?),
        None => None,
    };
    let element = match (element, array) {
        (Some(e), Some(n)) if e < u32::from(n) => Some(ArrayElement::new(i64::from(e) + 1).ok()?),
        (Some(_), _) => return None,
        (None, _) => None,
    };
    Some((set, element))
}

/// A CoE or POWERLINK object address.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct SdoAddress {
    /// Object index.
    pub index: u16,
    /// Sub-index.
    pub subindex: u8,
}

/// EtherCAT CoE object of a parameter (SK 550P).
pub fn coe(product: Product, a: ParamAddress) -> Result<SdoAddress, AddrError> {
    check(product, Protocol::Ethercat, a.inverter)?;
    let device = COE_DEVICE_STEP.get() * u16::from(a.inverter.get() - 1);
    Ok(SdoAddress {
        index: COE_INDEX.get() + device + a.number.get(),
        subindex: sdo_subindex(a.set, a.element),
    })
}

/// POWERLINK SDO of an inverter parameter: the SK 550P's device-id table (600h steps) or the
/// modules' (interface 2000h, FU n at 2000h + 800h·n), [`super::epl::device_id`]. An inverter
/// the product carries but the table lists no id for (FU5..FU8 of the SK TU3-POL) is
/// [`AddrError::NoDeviceId`], not the table's rule continued: 4800h, 5000h, … would fall on the
/// process-data objects 5000h–5003h.
pub fn powerlink(product: Product, a: ParamAddress) -> Result<SdoAddress, AddrError> {
    check(product, Protocol::Powerlink, a.inverter)?;
    let device =
        super::epl::device_id(product, a.inverter).ok_or_else(|| AddrError::NoDeviceId {
            product: product.name(),
            inverter: a.inverter.get(),
            last: super::epl::device_id_inverters(product),
        })?;
    Ok(SdoAddress {
        index: device + a.number.get(),
        subindex: sdo_subindex(a.set, a.element),
    })
}

/// A CIP path to a parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct CipAddress {
    /// Class: 101..108 for FI 1..8 (100 for a module's own parameters).
    pub class: u16,
    /// Instance from set and element.
    pub instance: u16,
    /// Attribute = parameter number.
    pub attribute: u16,
}

/// EtherNet/IP path of an inverter parameter.
pub fn cip(product: Product, a: ParamAddress) -> Result<CipAddress, AddrError> {
    check(product, Protocol::Ethernetip, a.inverter)?;
    Ok(CipAddress {
        class: CIP_CLASS_BASE.get() + u16::from(a.inverter.get()),
        instance: cip_instance(a.set, a.element),
        attribute: a.number.get(),
    })
}

/// PNU of a parameter order in a data record: P + 1000 (BU 0620 §2.5.6.2 "1000 must be added";
/// BU 0590 §4.2.2.1, e.g. P508 → 1508).
pub fn profinet_pnu(_product: Product, number: ParamNumber) -> u16 {
    number.get() + super::pkw::PNU_OFFSET.get()
}

/// A PROFINET parameter order's address.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct ProfinetAddress {
    /// Data record: 101..108 for FI 1..8 (100 = bus interface).
    pub record: u16,
    /// PNU with the +1000 offset.
    pub pnu: u16,
    /// IND word.
    pub ind: u16,
}

/// PROFINET data record and PKW fields of an inverter parameter.
pub fn profinet(product: Product, a: ParamAddress) -> Result<ProfinetAddress, AddrError> {
    check(product, Protocol::Profinet, a.inverter)?;
    Ok(ProfinetAddress {
        record: PNIO_RECORD_BASE.get() + u16::from(a.inverter.get()),
        pnu: profinet_pnu(product, a.number),
        ind: Ind::for_address(a.set, a.element).raw(),
    })
}

/// System-bus CAN IDs of an inverter and its absolute encoder.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct CanIds {
    /// P515 [-01] of FI n: 32, 34, 36, …
    pub inverter: u8,
    /// The encoder's address: inverter + 1.
    pub encoder: u8,
}

/// CAN IDs on the NORD system bus (BU 0620 §3.1: "P515[1] = 32", further inverters 34, 36, …;
/// "Absolute encoder address = CAN ID of the frequency inverter + 1").
pub fn can(inverter: Inverter) -> CanIds {
    let id = super::can::SystemBusAddress::inverter(inverter);
    CanIds {
        inverter: id.get(),
        encoder: super::can::SystemBusAddress::encoder(inverter).get(),
    }
}

/// The CoE index of P0 of FI 1 (BU 0620 §2.2.7: "2000h + parameter number").
pub static COE_INDEX: Constant<u16> = Constant::new(
    "coe-index",
    0x2000,
    "CoE index of P0",
    "BU 0620 §2.2.7 CoE object index",
);

/// From one inverter's CoE objects to the next's (BU 0620 §2.2.7: FI n at 2000h + 800h·(n−1)).
pub static COE_DEVICE_STEP: Constant<u16> = Constant::new(
    "coe-device-step",
    0x800,
    "CoE index step per inverter",
    "BU 0620 §2.2.7 CoE object index",
);

/// The CIP class of FI n is this + n (BU 0620 §2.3.5, BU 2100 §6.3: 100 + FI).
pub static CIP_CLASS_BASE: Constant<u16> = Constant::new(
    "cip-class-base",
    100,
    "CIP class base",
    "BU 0620 §2.3.5 CIP parameter classes",
);

/// The PROFINET data record of FI n is this + n (BU 0620 §2.5.6.2, BU 0590 §4.2.2).
pub static PNIO_RECORD_BASE: Constant<u16> = Constant::new(
    "pnio-record-base",
    100,
    "PROFINET data record base",
    "BU 0620 §2.5.6.2 data records",
);

/// Every protocol address of one parameter, for `harness addr`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Addresses {
    /// Product whose tables apply.
    pub product: &'static str,
    /// The parameter as the manuals write it.
    pub parameter: String,
    /// CoE object, where the product speaks EtherCAT.
    pub ethercat: Option<SdoAddress>,
    /// POWERLINK SDO.
    pub powerlink: Option<SdoAddress>,
    /// Why a product that speaks POWERLINK has no SDO for the parameter (FU5..FU8 of the
    /// SK TU3-POL, [`AddrError::NoDeviceId`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub powerlink_none: Option<String>,
    /// CIP path.
    pub ethernetip: Option<CipAddress>,
    /// PROFINET record and PKW.
    pub profinet: Option<ProfinetAddress>,
    /// System-bus CAN IDs.
    pub systembus: CanIds,
}

/// All addresses of a parameter (protocols the product does not speak are `None`).
pub fn all(product: Product, a: ParamAddress) -> Result<Addresses, AddrError> {
    if a.inverter.get() > product.max_inverters() {
        return Err(AddrError::NoSuchInverter {
            product: product.name(),
            inverter: a.inverter.get(),
            max: product.max_inverters(),
        });
    }
    let mut parameter = format!("{} {}", a.number, a.inverter);
    if let Some(s) = a.set {
        parameter += &format!(" set {}", s.get());
    }
    if let Some(e) = a.element {
        parameter += &format!(" [-{:02}]", e.get());
    }
    Ok(Addresses {
        product: product.name(),
        parameter,
        ethercat: coe(product, a).ok(),
        powerlink: powerlink(product, a).ok(),
        powerlink_none: match powerlink(product, a) {
            Err(e @ AddrError::NoDeviceId { .. }) => Some(e.to_string()),
            _ => None,
        },
        ethernetip: cip(product, a).ok(),
        profinet: profinet(product, a).ok(),
        systembus: can(a.inverter),
    })
}

impl fmt::Display for Addresses {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "{} on {}", self.parameter, self.product)?;
        if let Some(c) = self.ethercat {
            writeln!(
                f,
                "  EtherCAT CoE      index {:04X}h ({}) sub-index {}",
                c.index, c.index, c.subindex
            )?;
        }
        if let Some(p) = self.powerlink {
            writeln!(
                f,
                "  POWERLINK SDO     index {:04X}h ({}) sub-index {}",
                p.index, p.index, p.subindex
            )?;
        }
        if let Some(why) = &self.powerlink_none {
            writeln!(f, "  POWERLINK SDO     none: {why}")?;
        }
        if let Some(e) = self.ethernetip {
            writeln!(
                f,
                "  EtherNet/IP CIP   class {} instance {} attribute {}",
                e.class, e.instance, e.attribute
            )?;
        }
        if let Some(p) = self.profinet {
            writeln!(
                f,
                "  PROFINET          data record {} PNU {} ({:04X}h) IND {:04X}h",
                p.record, p.pnu, p.pnu, p.ind
            )?;
        }
        writeln!(
            f,
            "  System bus        CAN ID {} (absolute encoder {})",
            self.systembus.inverter, self.systembus.encoder
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    fn a(fi: i64, p: i64, set: Option<i64>, el: Option<i64>) -> ParamAddress {
        ParamAddress {
            inverter: Inverter::new(fi).unwrap(),
            number: ParamNumber::new(p).unwrap(),
            set: set.map(|s| ParamSet::new(s).unwrap()),
            element: el.map(|e| ArrayElement::new(e).unwrap()),
        }
    }

    #[test]
    fn coe_example_p102_fi3() {
        // BU 0620 §2.2.7 p. 20: 2000h + 1000h + 66h = 3066h.
        assert_eq!(
            coe(Product::Sk550p, a(3, 102, None, None)).unwrap().index,
            0x3066
        );
        assert_eq!(
            coe(Product::Sk550p, a(8, 999, None, None)).unwrap().index,
            0x5800 + 999
        );
    }

    #[test]
    fn powerlink_examples_differ_by_manual() {
        // BU 0620 §2.4.6 p. 36: P102 on FI 5 = 3800h + 66h = 3866h.
        assert_eq!(
            powerlink(Product::Sk550p, a(5, 102, None, None))
                .unwrap()
                .index,
            0x3866
        );
        // BU 2200: P102 on FU1 = 2800h + 66h = 2866h.
        assert_eq!(
            powerlink(Product::Tu3Pol, a(1, 102, None, None))
                .unwrap()
                .index,
            0x2866
        );
        // §6.4's last row: FU4 at 4000h. The SK TU3-POL carries FU5..FU8 (§6.3.5), the table
        // gives them no device id; the SK TU4-POL has no FU5 at all.
        assert_eq!(
            powerlink(Product::Tu3Pol, a(4, 102, None, None))
                .unwrap()
                .index,
            0x4066
        );
        let e = powerlink(Product::Tu3Pol, a(5, 102, None, None)).unwrap_err();
        assert_eq!(
            e,
            AddrError::NoDeviceId {
                product: "tu3-pol",
                inverter: 5,
                last: 4
            }
        );
        assert!(
            e.to_string()
                .starts_with("BU 2200 §6.4 lists no SDO device id for FU5"),
            "{e}"
        );
        assert!(matches!(
            powerlink(Product::Tu4Pol, a(5, 102, None, None)),
            Err(AddrError::NoSuchInverter { max: 4, .. })
        ));
        let all = all(Product::Tu3Pol, a(8, 102, None, None)).unwrap();
        assert_eq!(all.powerlink, None);
        assert!(
            all.to_string()
                .contains("POWERLINK SDO     none: BU 2200 §6.4 lists no SDO device id for FU8"),
            "{all}"
        );
    }

    #[test]
    fn cip_instances_decode_back() {
        for set_dependent in [false, true] {
            for array in [None, Some(9)] {
                let sets: Vec<Option<ParamSet>> = if set_dependent {
                    (1..=4).map(|s| ParamSet::new(s).ok()).collect()
                } else {
                    vec![None]
                };
                let elements: Vec<Option<ArrayElement>> = match array {
                    Some(n) => (1..=i64::from(n))
                        .map(|e| ArrayElement::new(e).ok())
                        .collect(),
                    None => vec![None],
                };
                for &s in &sets {
                    for &e in &elements {
                        let i = cip_instance(s, e);
                        assert_eq!(
                            cip_decode_instance(u32::from(i), set_dependent, array),
                            Some((s, e))
                        );
                    }
                }
            }
        }
        // P103 has four sets: instance 4 is none of them; P102-like plain parameters only 0.
        assert_eq!(cip_decode_instance(4, true, None), None);
        assert_eq!(cip_decode_instance(1, false, None), None);
        assert_eq!(cip_decode_instance(36, true, Some(9)), None);
        assert_eq!(cip_decode_instance(9, false, Some(9)), None);
    }

    #[rstest]
    // BU 0620 §2.3.5 p. 27 examples (the manual's FI 2 rows print class 103 and instances 12/14;
    // the formula gives 102 and 8/10: see suites/bu0620/addr-cip.yaml).
    #[case(a(1, 103, Some(1), None), (101, 0, 103))]
    #[case(a(4, 103, Some(3), None), (104, 2, 103))]
    #[case(a(3, 465, None, Some(1)), (103, 0, 465))]
    #[case(a(3, 465, None, Some(2)), (103, 1, 465))]
    #[case(a(2, 400, Some(3), Some(1)), (102, 2, 400))]
    #[case(a(2, 400, Some(1), Some(3)), (102, 8, 400))]
    #[case(a(2, 400, Some(3), Some(3)), (102, 10, 400))]
    fn cip_examples(#[case] addr: ParamAddress, #[case] want: (u16, u16, u16)) {
        let c = cip(Product::Sk550p, addr).unwrap();
        assert_eq!((c.class, c.instance, c.attribute), want);
    }

    #[rstest]
    #[case(None, None, 0)]
    #[case(Some(3), None, 3)]
    #[case(None, Some(2), 2)]
    #[case(Some(4), Some(2), 8)]
    fn sdo_subindices(#[case] set: Option<i64>, #[case] el: Option<i64>, #[case] want: u8) {
        let x = a(1, 1, set, el);
        assert_eq!(sdo_subindex(x.set, x.element), want);
    }

    #[test]
    fn profinet_and_can() {
        let p = profinet(Product::Sk550p, a(1, 717, None, None)).unwrap();
        assert_eq!((p.record, p.pnu), (101, 0x6B5));
        assert_eq!(
            can(Inverter::new(3).unwrap()),
            CanIds {
                inverter: 36,
                encoder: 37
            }
        );
    }

    #[test]
    fn refusals() {
        assert!(matches!(
            coe(Product::Tu3Eip, a(1, 1, None, None)),
            Err(AddrError::NoProtocol { .. })
        ));
        assert!(matches!(
            cip(Product::Tu4Eip, a(5, 1, None, None)),
            Err(AddrError::NoSuchInverter { max: 4, .. })
        ));
        let all = all(Product::Sk550p, a(5, 102, Some(3), None))
            .unwrap()
            .to_string();
        assert!(
            all.contains("index 4066h") && all.contains("3866h"),
            "{all}"
        );
    }
}
