//! The products the manuals describe, and the protocols they speak.
//!
//! Where two products differ, code takes a [`Product`] rather than guessing.

use serde::{Deserialize, Serialize};

/// A field-bus protocol of the manuals.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Protocol {
    /// EtherCAT with CAN application protocol over EtherCAT (CoE). BU 0620 §2.2.
    Ethercat,
    /// EtherNet/IP (CIP). BU 0620 §2.3, BU 2100.
    Ethernetip,
    /// Ethernet POWERLINK. BU 0620 §2.4, BU 2200.
    Powerlink,
    /// PROFINET IO. BU 0620 §2.5, BU 0590.
    Profinet,
    /// NORD system bus (CANopen on CAN). BU 0620 §2.1.
    Systembus,
}

impl Protocol {
    /// All protocols, in the order the manuals list them.
    pub const ALL: [Protocol; 5] = [
        Protocol::Ethercat,
        Protocol::Ethernetip,
        Protocol::Powerlink,
        Protocol::Profinet,
        Protocol::Systembus,
    ];
}

/// The values of P899 "Changing the bus protocol" and P870 "Present bus protocol" of the
/// SK 550P (BU 0620 §3.3, §4.1 p. 76, §4.3 p. 84): value, P899's meaning, P870's meaning.
pub const BUS_PROTOCOL_VALUES: [(u8, &str, &str); 5] = [
    (0, "No action", "No bus system active"),
    (1, "PROFINET IO", "PROFINET IO"),
    (2, "EtherCAT", "EtherCAT"),
    (3, "Ethernet/IP", "Ethernet/IP"),
    (4, "Powerlink", "Powerlink"),
];

/// Product family: the parameter numbering scheme follows it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Family {
    /// SK 550P with the integrated Industrial Ethernet interface: bus parameters P850–P899
    /// (BU 0620).
    Integrated,
    /// Plug-in bus modules SK TU3/TU4/CU4: bus parameters P150–P189 (BU 2100, BU 0590, BU 2200).
    Module,
}

/// A bus-interface product the manuals describe.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Product {
    /// NORDAC PRO SK 550P, integrated interface (BU 0620); protocol chosen with P899.
    Sk550p,
    /// SK TU3-EIP technology unit for SK 5xxE (BU 2100).
    Tu3Eip,
    /// SK TU4-EIP(-C) technology unit for SK 2xxE (BU 2100).
    Tu4Eip,
    /// SK CU4-EIP(-C) customer unit, installed in SK 2xxE / SK 1x0E (BU 2100).
    Cu4Eip,
    /// SK TU3-PNT technology unit for SK 5xxE (BU 0590).
    Tu3Pnt,
    /// SK TU3-POL technology unit (BU 2200).
    Tu3Pol,
    /// SK TU4-POL(-C) technology unit (BU 2200).
    Tu4Pol,
    /// SK CU4-POL(-C) customer unit (BU 2200).
    Cu4Pol,
}

impl Product {
    /// Every product, in a stable order.
    pub const ALL: [Product; 8] = [
        Product::Sk550p,
        Product::Tu3Eip,
        Product::Tu4Eip,
        Product::Cu4Eip,
        Product::Tu3Pnt,
        Product::Tu3Pol,
        Product::Tu4Pol,
        Product::Cu4Pol,
    ];

    /// The product's short name as used by profiles and the CLI (`sk550p`, `tu3-eip`, …).
    pub fn name(self) -> &'static str {
        match self {
            Product::Sk550p => "sk550p",
            Product::Tu3Eip => "tu3-eip",
            Product::Tu4Eip => "tu4-eip",
            Product::Cu4Eip => "cu4-eip",
            Product::Tu3Pnt => "tu3-pnt",
            Product::Tu3Pol => "tu3-pol",
            Product::Tu4Pol => "tu4-pol",
            Product::Cu4Pol => "cu4-pol",
        }
    }

    /// Parses a short name (`sk550p`, `tu3-eip`, …).
    pub fn from_name(name: &str) -> Option<Product> {
        Product::ALL.into_iter().find(|p| p.name() == name)
    }

    /// The manual that describes the product.
    pub fn manual(self) -> &'static str {
        match self {
            Product::Sk550p => "BU 0620",
            Product::Tu3Eip | Product::Tu4Eip | Product::Cu4Eip => "BU 2100",
            Product::Tu3Pnt => "BU 0590",
            Product::Tu3Pol | Product::Tu4Pol | Product::Cu4Pol => "BU 2200",
        }
    }

    /// Integrated interface or plug-in module.
    pub fn family(self) -> Family {
        match self {
            Product::Sk550p => Family::Integrated,
            _ => Family::Module,
        }
    }

    /// The protocols the product speaks. The SK 550P speaks all four Industrial Ethernet
    /// protocols (selected with P899, BU 0620 §3.3); every product reaches further inverters over
    /// the NORD system bus.
    pub fn protocols(self) -> &'static [Protocol] {
        match self {
            Product::Sk550p => &[
                Protocol::Ethercat,
                Protocol::Ethernetip,
                Protocol::Powerlink,
                Protocol::Profinet,
                Protocol::Systembus,
            ],
            Product::Tu3Eip | Product::Tu4Eip | Product::Cu4Eip => {
                &[Protocol::Ethernetip, Protocol::Systembus]
            }
            Product::Tu3Pnt => &[Protocol::Profinet, Protocol::Systembus],
            Product::Tu3Pol | Product::Tu4Pol | Product::Cu4Pol => {
                &[Protocol::Powerlink, Protocol::Systembus]
            }
        }
    }

    /// How many inverters the interface carries: FI 1 plus those on the system bus, each with
    /// its process data (control/status word, setpoints/actual values).
    ///
    /// BU 0620 §2.1.1: up to 8 on the SK 550P's system bus. BU 2100 §6: classes 105–108 (FI 5..8)
    /// "only bus interface SK TU3-EIP", so TU4/CU4-EIP reach 4. BU 2200: the SK TU3-POL carries
    /// FU1..FU8 — §4.1 p. 20 (8 inverters SK 500–535E / SK 54xE on one system bus), §6.3.5 (its
    /// PDO table lists FU5..FU8), §7.1.3 P176/P177 (arrays [-26]…[-49] "an/von FU5…FU8",
    /// footnote "Nur Busschnittstelle SK TU3-POL"); SK TU4/CU4-POL FU1..FU4 (§6.3.5's 50-byte
    /// table, §4.1's SK 1x0E/2xxE column). Parameter access over POWERLINK reaches fewer: BU 2200
    /// §6.4 lists SDO device ids for FU1..FU4 only ([`crate::nord::epl::device_id_inverters`]).
    /// BU 0590 §4.2.2.1: data record 101 is "the frequency inverter" — one.
    pub fn max_inverters(self) -> u8 {
        match self {
            Product::Sk550p | Product::Tu3Eip | Product::Tu3Pol => 8,
            Product::Tu4Eip | Product::Cu4Eip | Product::Tu4Pol | Product::Cu4Pol => 4,
            Product::Tu3Pnt => 1,
        }
    }
}
