//! The parameter catalogue: the parameters the manuals name, with their metadata.
//!
//! Inverter parameters come from the manuals' examples and tables (BU 0620 §4.5 "Frequency
//! inverter parameter settings", §6.1.2.4, §2.5.6.4); the inverter's own manual (BU 0600) is not
//! among the specification documents, so where a range or default is not printed in the five
//! manuals the entry's `source` says which value was assumed. Bus-interface parameters of the
//! SK 550P come from BU 0620 §4.2–§4.4 (the protocol-independent ones and the IP parameters).

use super::mutant::{Row, Table};
use super::product::{Family, Product};
use super::types::ParamNumber;

/// Transfer width in the parameter channel (BU 0620 §2.5.6.3 "Parameter value PWE").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Width {
    /// 16 bits (order labels 2/7/12/14).
    Word,
    /// 32 bits (order labels 3/8/11/13): positions.
    Dword,
}

/// Whether and how a parameter may be written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Access {
    /// Setting parameter.
    ReadWrite,
    /// Information (display) parameter.
    ReadOnly,
    /// Only 0 may be written (resets a counter).
    ResetOnly,
}

/// Which unit owns the parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Owner {
    /// The bus interface (SK 550P: P850–P899, data record 100).
    Interface,
    /// Every inverter.
    Inverter,
}

/// One parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct ParamDef {
    /// P-number.
    pub number: u16,
    /// Name as the manual prints it.
    pub name: &'static str,
    /// Who owns it.
    pub owner: Owner,
    /// Product family that has it (`None`: every product).
    pub family: Option<Family>,
    /// Products that have it, where the manual narrows it down ("Bus interface: SK TU4-EIP");
    /// empty: every product of the family.
    #[serde(skip)]
    pub products: &'static [Product],
    /// Transfer width.
    pub width: Width,
    /// Smallest value (raw, after resolution).
    pub min: i32,
    /// Largest value (raw).
    pub max: i32,
    /// Factory setting (raw), for every element.
    pub default: i32,
    /// Decimal places of the displayed value (0.01 s → 2; BU 0620 §2.5.6.3 99.99 s → 9999).
    pub decimals: u8,
    /// Array elements, if an array.
    pub array: Option<u8>,
    /// Factory settings per array element where the manual gives them (else `default`).
    #[serde(skip)]
    pub element_defaults: &'static [i32],
    /// Depends on the parameter set (P1…P4).
    pub set_dependent: bool,
    /// Writability.
    pub access: Access,
    /// A text parameter of ASCII codes: besides 0, which ends or clears the text, it takes only
    /// `text_from..=max` (BU 2100 §7.1.2 P169 "45...122 ASCII", factory {0}); 0 for every
    /// other parameter.
    pub text_from: i32,
    /// Where the manuals state it, and what was assumed.
    pub source: &'static str,
    /// The fields no manual of the five states (the `source` says where they come from: an
    /// inverter manual outside the specification, or a choice). `harness mutants` changes only
    /// the stated fields: a wrong assumed value is no error of the manuals' data.
    #[serde(skip)]
    pub assumed: &'static [Field],
}

/// A field of a catalogue entry, as a mutant changes it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Field {
    /// `default` and `element_defaults`.
    Default,
    /// `min` and `max`.
    Range,
    /// `decimals`.
    Decimals,
    /// `array`.
    Array,
    /// `access`.
    Access,
    /// `set_dependent`.
    Sets,
}

const fn inv(
    number: u16,
    name: &'static str,
    min: i32,
    max: i32,
    default: i32,
    decimals: u8,
    source: &'static str,
) -> ParamDef {
    ParamDef {
        number,
        name,
        owner: Owner::Inverter,
        family: None,
        products: &[],
        width: Width::Word,
        min,
        max,
        default,
        decimals,
        array: None,
        element_defaults: &[],
        set_dependent: false,
        access: Access::ReadWrite,
        text_from: 0,
        source,
        assumed: &[],
    }
}

/// An entry whose `fields` no manual of the five states.
const fn assumed(p: ParamDef, fields: &'static [Field]) -> ParamDef {
    ParamDef {
        assumed: fields,
        ..p
    }
}

const fn sets(p: ParamDef) -> ParamDef {
    ParamDef {
        set_dependent: true,
        ..p
    }
}

/// An array whose elements have their own factory settings.
const fn elements(p: ParamDef, defaults: &'static [i32]) -> ParamDef {
    ParamDef {
        array: Some(defaults.len() as u8),
        element_defaults: defaults,
        ..p
    }
}

const fn array(p: ParamDef, n: u8) -> ParamDef {
    ParamDef {
        array: Some(n),
        ..p
    }
}

const fn dword(p: ParamDef) -> ParamDef {
    ParamDef {
        width: Width::Dword,
        ..p
    }
}

/// An ASCII text parameter of the characters `from..=max` and the 0 that ends the text.
const fn text(p: ParamDef, from: i32) -> ParamDef {
    ParamDef {
        text_from: from,
        ..p
    }
}

const fn ro(p: ParamDef) -> ParamDef {
    ParamDef {
        access: Access::ReadOnly,
        ..p
    }
}

const fn iface(p: ParamDef) -> ParamDef {
    ParamDef {
        owner: Owner::Interface,
        family: Some(Family::Integrated),
        ..p
    }
}

/// An inverter parameter as the manual of the listed products prints it (the inverter they sit
/// on differs from the SK 550P).
const fn only(p: ParamDef, products: &'static [Product]) -> ParamDef {
    ParamDef { products, ..p }
}

/// An inverter parameter only the SK 550P's inverters have (BU 0620 §4.5: the XU5 extension).
const fn integrated(p: ParamDef) -> ParamDef {
    ParamDef {
        family: Some(Family::Integrated),
        ..p
    }
}

/// A bus-module parameter of the listed products (BU 2100 §7.1 "Bus interface" rows).
const fn module(p: ParamDef, products: &'static [Product]) -> ParamDef {
    ParamDef {
        owner: Owner::Interface,
        family: Some(Family::Module),
        products,
        ..p
    }
}

const EIP_ALL: &[Product] = &[Product::Tu3Eip, Product::Tu4Eip, Product::Cu4Eip];
const POL_ALL: &[Product] = &[Product::Tu3Pol, Product::Tu4Pol, Product::Cu4Pol];
const PNT: &[Product] = &[Product::Tu3Pnt];
const POL_TU4_CU4: &[Product] = &[Product::Tu4Pol, Product::Cu4Pol];
const TU4_CU4: &[Product] = &[
    Product::Tu4Eip,
    Product::Cu4Eip,
    Product::Tu4Pol,
    Product::Cu4Pol,
];
const EIP_POL_ALL: &[Product] = &[
    Product::Tu3Eip,
    Product::Tu4Eip,
    Product::Cu4Eip,
    Product::Tu3Pol,
    Product::Tu4Pol,
    Product::Cu4Pol,
];

/// Every catalogued parameter.
pub static CATALOGUE: Table<ParamDef> = Table::new("params", "BU 0620 §4", &[
    assumed(sets(inv(102, "Acceleration time", 0, 32000, 200, 2, "BU 0620 §2.5.6.4 (P102 set 2 = 2.5 s = 250); range 0–320.00 s and default 2.00 s assumed from BU 0600")), &[Field::Range, Field::Default]),
    assumed(sets(inv(103, "Deceleration time", 0, 32000, 200, 2, "BU 0620 §2.5.6.3 (99.99 s run-up → 9999); range/default assumed from BU 0600; the run-up time of §2.5.6.3 is P102's (acceleration): no decimals printed for P103 (assumed)")), &[Field::Range, Field::Default, Field::Decimals]),
    assumed(sets(inv(105, "Maximum frequency", 1, 4000, 500, 1, "BU 0620 §6.1.3 (P105 = 50 Hz); range 0.1–400.0 Hz assumed from BU 0600; not printed in the manuals (assumed): range")), &[Field::Range]),
    assumed(sets(inv(112, "Torque current limit", 25, 400, 400, 0, "BU 0620 §6.1.2.4 (100 % of currents); range 25–400 % assumed; not printed in the manuals (assumed): default, range, decimals, access, set dependence")), &[Field::Default, Field::Range, Field::Decimals, Field::Access, Field::Sets]),
    assumed(sets(array(inv(400, "Function setpoint inputs", 0, 80, 0, 0, "BU 0620 §2.3.5 (array depending on parameter sets); range assumed; not printed in the manuals (assumed): default, range, decimals, array size, access"), 9)), &[Field::Default, Field::Range, Field::Decimals, Field::Array, Field::Access]),
    assumed(array(inv(465, "Fixed frequency array", -4000, 4000, 0, 1, "BU 0620 §2.3.5 (array, not set-dependent); range assumed; not printed in the manuals (assumed): default, range, decimals, array size, access"), 31), &[Field::Default, Field::Range, Field::Decimals, Field::Array, Field::Access]),
    // The SK 5xxE under the SK TU3-PNT (BU 0590 §5.2, SK 540E and above), ahead of the SK 550P's
    // entries of the same numbers: the lookup takes the first that applies.
    only(elements(inv(510, "Source setpoints", 0, 10, 0, 0, "BU 0590 §5.2.1 (p. 38): [-01] main, [-02] auxiliary setpoint source, 0…10, factory all 0 (0 = auto, 8 = Ethernet TU)"), &[0, 0]), PNT),
    only(inv(513, "Telegram time-out", -1, 1000, 0, 1, "BU 0590 §5.2.1 (p. 38): -0.1 (no error) / 0.0 (off) / 0.1…100.0 s, factory 0.0; one value"), PNT),
    only(sets(elements(inv(543, "Bus actual value", 0, 57, 0, 0, "BU 0590 §5.2.1 (p. 39), SK 540E and above: [-01]..[-05], 0…57, factory 1, 4, 9, 0, 0; \"S P\" in the columns Supervisor and Parameter set: parameter-set dependent"), &[1, 4, 9, 0, 0])), PNT),
    only(sets(elements(inv(546, "Function bus setpoint", 0, 57, 0, 0, "BU 0590 §5.2.1 (p. 40), SK 540E and above: [-01]..[-05], 0…57, factory [-01] = 1, all others 0; \"S P\" in the columns Supervisor and Parameter set: parameter-set dependent"), &[1, 0, 0, 0, 0])), PNT),
    assumed(only(ro(array(inv(740, "PZD bus in", 0, 0xFFFF, 0, 0, "BU 0590 §5.2.2 (p. 42), SK 540E and above: [-01] control word, [-02]..[-06] setpoints 1..5, [-07] bus I/O in bits, [-08]..[-12] parameter data in (AK, PNU, IND, PWE 1/2), [-13]..[-23] broadcast and PLC; set dependence not printed: §5.2.2 has no parameter-set column"), 23)), PNT), &[Field::Sets]),
    assumed(only(ro(array(inv(741, "PZD bus out", 0, 0xFFFF, 0, 0, "BU 0590 §5.2.2 (p. 43), SK 540E and above: [-01] status word, [-02]..[-06] actual values 1..5, [-07] bus I/O out bits, [-08]..[-12] parameter data out, [-13]..[-23] master function and PLC; set dependence not printed: §5.2.2 has no parameter-set column; not printed in the manuals (assumed): default"), 23)), PNT), &[Field::Default, Field::Sets]),
    assumed(only(inv(607, "Speed ratio", 1, 65535, 1, 0, "BU 0590 §4.1.5 (p. 23): the gear ratio factor P607 & P608 extends the low word's position range at a lower resolution; positions count output rotations = motor rotations × P607 / P608 (POSICON, BU 0510, not among the manuals: range 1…65535 and factory 1 assumed, one value); not printed in the manuals (assumed): default, range, decimals, set dependence"), PNT), &[Field::Default, Field::Range, Field::Decimals, Field::Sets]),
    assumed(only(inv(608, "Reduction ratio", 1, 65535, 1, 0, "BU 0590 §4.1.5 (p. 23): the denominator of the gear ratio factor P607 / P608 (range 1…65535 and factory 1 assumed); not printed in the manuals (assumed): default, range, decimals, set dependence"), PNT), &[Field::Default, Field::Range, Field::Decimals, Field::Sets]),
    assumed(only(ro(array(inv(701, "Last error", 0, 9999, 0, 1, "BU 0590 §6.2 (p. 44): the error 'is permanently stored in the FI error statistics'; BU 0620 §4.5 / BU 2100 §7.2 name P701 'Last error'; [-01]..[-05] newest first assumed from BU 0500; not printed in the manuals (assumed): default, range, decimals, array size, access, set dependence"), 5)), PNT), &[Field::Default, Field::Range, Field::Decimals, Field::Array, Field::Access, Field::Sets]),
    assumed(only(ro(inv(745, "Module version", 0, 9999, 0, 1, "BU 0590 §5.2.2 (p. 43): 0.0…999.9, the technology unit's software version; not printed in the manuals (assumed): default, set dependence")), PNT), &[Field::Default, Field::Sets]),
    assumed(only(ro(inv(746, "Module status", 0, 0xFFFF, 0, 0, "BU 0590 §5.2.2 (p. 43): 0000…FFFFh, readiness, error and communication of the technology unit; not printed in the manuals (assumed): default, set dependence")), PNT), &[Field::Default, Field::Sets]),
    // The SK 54xE behind the EtherNet/IP and POWERLINK modules (BU 2100 §7.2 p. 54/55, BU 2200
    // §7.2 p. 59/60: "information parameters relevant for the bus interface").
    assumed(only(inv(512, "USS address", 0, 30, 0, 0, "BU 2100 §4.3 (p. 22): the SK TU3-EIP gateway needs P512 USS address = 0 (factory setting) on every inverter; range 0…30 assumed from BU 0500; not printed in the manuals (assumed): range, decimals, set dependence"), &[Product::Tu3Eip, Product::Tu3Pol]), &[Field::Range, Field::Decimals, Field::Sets]),
    assumed(only(ro(inv(744, "Configuration", 0, 0xFFFF, 0, 0, "BU 2100 §7.2 (p. 55) \"Configuration\", BU 2200 §7.2 (p. 60) \"Ausbaustufe\": for SK TU3, SK CU4 and SK TU4; no value printed (the inverter's manual), 0 assumed; not printed in the manuals (assumed): default, range, decimals, set dependence")), EIP_POL_ALL), &[Field::Default, Field::Range, Field::Decimals, Field::Sets]),
    assumed(only(ro(inv(745, "Module version", 0, 9999, 0, 1, "BU 2100 §7.2 (p. 55), BU 2200 §7.2 (p. 60): \"—\" in the SK CU4 column (the tab-separated row of BU 2100: SK TU3 empty, SK CU4 \"—\"; BU 2200 prints the same module); no value printed: the module's software version as P171 [-01] shows it assumed (BU 0590 §5.2.2: the version of the technology unit); not printed in the manuals (assumed): default, range, decimals, set dependence")), &[Product::Tu3Eip, Product::Tu4Eip, Product::Tu3Pol, Product::Tu4Pol]), &[Field::Default, Field::Range, Field::Decimals, Field::Sets]),
    assumed(only(ro(inv(746, "Module status", 0, 0xFFFF, 0, 0, "BU 2100 §7.2 (p. 55), BU 2200 §7.2 (p. 60): bit 0 initialised, 1 cyclic communication, 4…6 error, 8…15 bus interface ID (EtherNet/IP 23, POWERLINK 24): proto::nord::can::p746_status; not printed in the manuals (assumed): default, range, decimals, set dependence")), EIP_POL_ALL), &[Field::Default, Field::Range, Field::Decimals, Field::Sets]),
    assumed(array(inv(120, "Option monitoring", 0, 2, 1, 0, "BU 0620 §3.9 step 7 (p. 74): [-01] 1 (Auto) or 2 (monitoring active immediately) for the system bus; 0 = off, factory 1 and 4 elements assumed from BU 0600; not printed in the manuals (assumed): default, range, array size, set dependence"), 4), &[Field::Default, Field::Range, Field::Array, Field::Sets]),
    assumed(inv(506, "Auto. Acknowledge Error", 0, 7, 0, 0, "BU 0620 §5.2 (p. 93): activating P506 acknowledges errors automatically; 0 = off (factory) and range 0…7 assumed from BU 0600, any other value acknowledges (BU 0600's count of acknowledgements per mains-on is not modelled); not printed in the manuals (assumed): default, range, decimals, set dependence"), &[Field::Default, Field::Range, Field::Decimals, Field::Sets]),
    inv(509, "Control word source", 0, 10, 0, 0, "BU 0620 §4.5: 8 = Ethernet (FI 1), 6 = CANopen (further FIs)"),
    assumed(array(inv(510, "Setpoint source", 0, 10, 0, 0, "BU 0620 §4.5: 8 = Ethernet, 6 = CANopen; §3.9 step 5 (p. 74): elements [-01] and [-02], 0 = Auto; not printed in the manuals (assumed): range, set dependence"), 2), &[Field::Range, Field::Sets]),
    assumed(array(inv(513, "Telegram timeout time", -1, 3200, 0, 1, "BU 0620 §4.5: [-03] CANopen, [-04] Ethernet, factory Off (0); not printed in the manuals (assumed): range, decimals"), 4), &[Field::Range, Field::Decimals]),
    assumed(inv(514, "CAN baud rate", 0, 7, 5, 0, "BU 0620 §4.5: 5 = 250 kBaud; not printed in the manuals (assumed): range, set dependence"), &[Field::Range, Field::Sets]),
    assumed(array(inv(515, "CAN address", 0, 255, 32, 0, "BU 0620 §4.5: [-01] system bus address 32 (further FIs 34, 36, …); not printed in the manuals (assumed): range, array size, set dependence"), 3), &[Field::Range, Field::Array, Field::Sets]),
    assumed(elements(inv(543, "Actual bus value", 0, 60, 0, 0, "BU 0620 §6.1.2.4/§6.1.3: [-01]..[-05], [-01] = 1 actual frequency; not printed in the manuals (assumed): range"), &[1, 0, 0, 0, 0]), &[Field::Range]),
    assumed(elements(inv(546, "Function bus setpoint", 0, 60, 0, 0, "BU 0620 §6.1.2.4/§6.1.3: [-01]..[-05], [-01] = 1 setpoint frequency; not printed in the manuals (assumed): range"), &[1, 0, 0, 0, 0]), &[Field::Range]),
    assumed(inv(560, "Save in EEPROM", 0, 1, 1, 0, "BU 0620 §2.5.6 (RAM-only saving via P560; set dependence not printed); 1 = save assumed default; not printed in the manuals (assumed): default, decimals"), &[Field::Default, Field::Decimals, Field::Sets]),
    assumed(ro(array(inv(700, "Present operating status", 0, 0xFFFF, 0, 0, "BU 0620 §5.3: [-01] present error (10.3 shown as 103), [-04] its DS402 code (7583h); not printed in the manuals (assumed): range; decimals differ per element (one in [-01], none in the code of [-04]), which one figure cannot state"), 4)), &[Field::Range, Field::Decimals]),
    assumed(dword(inv(615, "Maximum position", -5_000_000, 5_000_000, 0, 2, "BU 0620 §4 (p. 75): POSICON position values are communicated as double words; §6.1.2.4: positions range -50000.00…50000.00 rotations. The number P615 \"Maximum position\" and its factory 0 are assumed from the POSICON manual BU 0510; not printed in the manuals (assumed): default")), &[Field::Default]),
    assumed(ro(array(inv(701, "Last error", 0, 0xFFFF, 0, 1, "BU 0620 §4.5 (p. 91), §5.3: the last error (as P700 shows it, 10.3 → 103: one decimal); [-01] the latest, five elements assumed from BU 0600; not printed in the manuals (assumed): default, range, array size, set dependence"), 5)), &[Field::Default, Field::Range, Field::Array, Field::Sets]),
    assumed(ro(array(inv(707, "Software version", 0, 99999, 12, 1, "BU 0620 §7.1 (p. 119): the software version is shown in P707; [-01] version, [-02] revision, [-03] special version as the modules' P171; the value V 1.2 R0 is assumed (BU 0620 prints none for the inverter); not printed in the manuals (assumed): default, range, decimals, array size, set dependence"), 3)), &[Field::Default, Field::Range, Field::Decimals, Field::Array, Field::Sets]),
    assumed(ro(inv(717, "Current speed", -32768, 32767, 0, 0, "BU 0620 §2.5.6.4: read example, 1020 (03FCh); not printed in the manuals (assumed): default, range, decimals, set dependence")), &[Field::Default, Field::Range, Field::Decimals, Field::Sets]),
    assumed(ro(array(inv(740, "PZD bus in", 0, 0xFFFF, 0, 0, "BU 0620 §4.5: control word and setpoints as received; not printed in the manuals (assumed): range"), 6)), &[Field::Range]),
    assumed(ro(array(inv(741, "PZD bus out", 0, 0xFFFF, 0, 0, "BU 0620 §4.5: status word and actual values as sent; not printed in the manuals (assumed): default, range, array size, set dependence"), 6)), &[Field::Default, Field::Range, Field::Array, Field::Sets]),
    assumed(integrated(ro(array(inv(744, "Configuration", 0, 0xFFFF, 0, 0, "BU 0620 §4.5 (p. 91): [-02] XU5 type: 0 no extension present, 1 reserved, 2 Industrial Ethernet present (the SK 550P's FI 1); [-01] not printed; set dependence not printed; not printed in the manuals (assumed): range"), 2))), &[Field::Range, Field::Sets]),
    assumed(integrated(ro(array(inv(745, "Module version", 0, 99999, 0, 0, "BU 0620 §4.5 (p. 91): [-07] XU5 version, [-08] revision, [-09] special version, [-10] stack 1, [-11] stack 2; [-01]..[-06] not printed; FI 1 shows the interface software V 1.1 R1 of §1.1.2 as 11 and 1; not printed in the manuals (assumed): default, range, decimals"), 11))), &[Field::Default, Field::Range, Field::Decimals]),
    assumed(integrated(ro(array(inv(746, "Module status", 0, 0xFFFF, 0, 0, "BU 0620 §4.5 (p. 91): [-03] XU5 status: 0 not ready, 1 ready; [-01]/[-02] not printed; not printed in the manuals (assumed): default, range"), 3))), &[Field::Default, Field::Range]),
    assumed(ro(array(inv(748, "CANopen status", 0, 0xFFFF, 0, 0, "BU 0620 §4.5 (p. 91): [-01] displays the system bus status; BU 2100 §7.2 (p. 55) and BU 2200 §7.2: the inverters' system bus status (its values are in BU 0200, not among the manuals); not printed in the manuals (assumed): default, range, decimals, set dependence"), 1)), &[Field::Default, Field::Range, Field::Decimals, Field::Sets]),
    iface(elements(inv(850, "IP address", 0, 255, 0, 0, "BU 0620 §4.2.2: [-01]..[-04], factory 192.168.1.100"), IP_DEFAULT)),
    iface(elements(inv(851, "IP sub-net mask", 0, 255, 0, 0, "BU 0620 §4.2.2: factory 255.255.255.0"), MASK_DEFAULT)),
    iface(array(inv(852, "IP Gateway", 0, 255, 0, 0, "BU 0620 §4.2.2: factory 0.0.0.0"), 4)),
    assumed(iface(inv(853, "Right TCP Ethernet", 0, 3, 0, 0, "BU 0620 §4.2.2: 0…3, factory 0; not printed in the manuals (assumed): set dependence")), &[Field::Sets]),
    assumed(iface(inv(856, "Addressing Mode", 0, 2, 1, 0, "BU 0620 §4.2.2: 0 fixed (P850–P852), 1 BOOTP, 2 DHCP; factory 1; read in at restart; not printed in the manuals (assumed): set dependence")), &[Field::Sets]),
    assumed(iface(inv(854, "Device name", 0, 122, 0, 0, "BU 0620 §4.2.3 (POWERLINK, p. 80), §4.2.4 (PROFINET IO, p. 83): 0…122 (ASCII), factory 0 (no name); one character per value, the manual prints no array; not printed in the manuals (assumed): set dependence")), &[Field::Sets]),
    assumed(iface(inv(857, "FI sets bus error", 0, 1, 1, 0, "BU 0620 §5.4.1 (p. 95): \"P163/P857 FI sets bus error\" factory 1 (a FI error stops the PLC), may be set to 0 (\"False\"); §4.2.3 prints no entry, range 0…1 as P163 of BU 2200 §7.1.2; not printed in the manuals (assumed): range, decimals, set dependence")), &[Field::Range, Field::Decimals, Field::Sets]),
    assumed(iface(inv(858, "POWERLINK cycle", 400, 2000, 1000, 0, "BU 0620 §4.2.3 (p. 81): 400…2000 µs, factory 1000; not printed in the manuals (assumed): set dependence")), &[Field::Sets]),
    assumed(iface(ro(array(inv(877, "Present IP gateway", 0, 255, 0, 0, "BU 0620 §4.4.2 (p. 87), §4.4.3 (p. 88): [-01]..[-04], the gateway set in P852; set dependence not printed"), 4))), &[Field::Sets]),
    assumed(iface(ro(array(inv(875, "Present IP address", 0, 255, 0, 0, "BU 0620 §4.4.1: [-01]..[-04]; not printed in the manuals (assumed): default"), 4))), &[Field::Default]),
    assumed(iface(ro(array(inv(876, "Present IP sub-net mask", 0, 255, 0, 0, "BU 0620 §4.4.1: [-01]..[-04]; not printed in the manuals (assumed): default"), 4))), &[Field::Default]),
    assumed(iface(ro(array(inv(878, "MAC Address", 0, 255, 0, 0, "BU 0620 §4.4.1: [-01]..[-03] manufacturer id F0.5F.5A, [-04]..[-06] free; not printed in the manuals (assumed): default"), 6))), &[Field::Default]),
    assumed(iface(ro(inv(870, "Present bus protocol", 0, 4, 0, 0, "BU 0620 §4.3: display 0…4; not printed in the manuals (assumed): default, set dependence"))), &[Field::Default, Field::Sets]),
    assumed(iface(ro(inv(872, "Bus status", 0, 0xFFFF, 0, 0, "BU 0620 §4.3: bit 0 module ready … bits 8–15 FI 1..8 online; not printed in the manuals (assumed): default, set dependence"))), &[Field::Default, Field::Sets]),
    assumed(iface(ro(array(inv(873, "Process data bus In", 0, 0xFFFF, 0, 0, "BU 0620 §4.3: [-01] control word, [-02]..[-06] setpoints to FI 1; six elements per FI up to [-48] for FI 8; not printed in the manuals (assumed): default"), 48))), &[Field::Default]),
    assumed(iface(ro(array(inv(874, "Process data bus Out", 0, 0xFFFF, 0, 0, "BU 0620 §4.3: [-01] status word, [-02]..[-06] actual values of FI 1; six elements per FI up to [-48] for FI 8; not printed in the manuals (assumed): default"), 48))), &[Field::Default]),
    assumed(iface(ro(array(inv(879, "PPO Type", 0, 255, 3, 0, "BU 0620 §4.4.3 (PROFINET): [-01]..[-08] FI 1..8; 3 = empty slot, 6 PPO3, 7 PPO4, 8 PPO6, 9 PPO1, 10 PPO2. Under EtherNet/IP (§4.4.1) P879 is \"Active Assembly\": [-01] setpoints, [-02] actual values; not printed in the manuals (assumed): default"), 8))), &[Field::Default]),
    assumed(iface(inv(899, "Changing the bus protocol", 0, 4, 0, 0, "BU 0620 §4.2: 0…4, factory 0; not printed in the manuals (assumed): set dependence")), &[Field::Sets]),
    assumed(module(inv(150, "Set relay", 0, 4, 0, 0, "BU 2100 §7.1.1: 0…4, factory 0, SK TU4-EIP only; BU 2200 §7.1.1 (p. 48): the same on the SK TU4-POL only; parameter-set dependence not printed (one value for all sets assumed)"), &[Product::Tu4Eip, Product::Tu4Pol]), &[Field::Sets]),
    // P151 differs per product (docs/product-differences.md): BU 2100 has -1 "Monitoring Off"
    // and 0 "Control word monitoring Off, bus-communication monitoring active"; BU 2200 has
    // 0…32767 with 0 "Überwachung Aus" and no -1 (can::p151_monitoring).
    assumed(module(inv(151, "Timeout for external bus", -1, 32767, 0, 0, "BU 2100 §7.1.1 (p. 45): ms, factory 0; setting values -1 = Monitoring Off, 0 = Control word monitoring Off, bus-communication monitoring active (the printed range 0…32767 omits -1: erratum, own-text); parameter-set dependence not printed (one value for all sets assumed)"), &[Product::Tu4Eip, Product::Cu4Eip]), &[Field::Sets]),
    assumed(module(inv(151, "TimeOut externer Bus", 0, 32767, 0, 0, "BU 2200 §7.1.1 (p. 48): 0…32767 ms, factory 0; Einstellwerte 0 = Überwachung Aus (no -1); parameter-set dependence not printed (one value for all sets assumed)"), POL_TU4_CU4), &[Field::Sets]),
    assumed(module(inv(152, "Factory setting", 0, 3, 0, 0, "BU 2100 §7.1.1, BU 2200 §7: 0…3, returns to 0 after loading; parameter-set dependence not printed (one value for all sets assumed)"), EIP_POL_ALL), &[Field::Sets]),
    assumed(module(elements(inv(153, "Min. system bus cycle", 0, 250, 0, 0, "BU 2100 §7.1.1, BU 2200 §7: ms, [-01] TxSDO {10}, [-02] TxPDO {5}; parameter-set dependence not printed (one value for all sets assumed)"), &[10, 5]), TU4_CU4), &[Field::Sets]),
    assumed(module(array(inv(154, "TB-IO access", 0, 5, 0, 0, "BU 2100 §7.1.1, BU 2200 §7.1.1 (p. 49): [-01] inputs, [-02] outputs, {0}; SK TU4/CU4 only; parameter-set dependence not printed (one value for all sets assumed)"), 2), TU4_CU4), &[Field::Sets]),
    assumed(module(elements(inv(160, "IP address", 0, 255, 0, 0, "BU 2100 §7.1.2: factory 192.168.1.100; parameter-set dependence not printed (one value for all sets assumed)"), IP_DEFAULT), EIP_ALL), &[Field::Sets]),
    assumed(module(elements(inv(161, "IP subnet mask", 0, 255, 0, 0, "BU 2100 §7.1.2: factory 255.255.255.0; parameter-set dependence not printed (one value for all sets assumed)"), MASK_DEFAULT), EIP_ALL), &[Field::Sets]),
    assumed(module(array(inv(164, "IP Gateway", 0, 255, 0, 0, "BU 2100 §7.1.2: factory 0.0.0.0; parameter-set dependence not printed (one value for all sets assumed)"), 4), EIP_ALL), &[Field::Sets]),
    assumed(module(inv(165, "Addressing mode", 0, 2, 1, 0, "BU 2100 §7.1.2: 0…2, factory 1; parameter-set dependence not printed (one value for all sets assumed)"), EIP_ALL), &[Field::Sets]),
    assumed(module(inv(160, "Node Id/IP Adresse 4", 0, 239, 0, 0, "BU 2200 §7: 0…239 (no factory setting printed; 0 assumed, DIP switches take precedence); parameter-set dependence not printed (one value for all sets assumed)"), POL_ALL), &[Field::Default, Field::Sets]),
    assumed(module(inv(163, "FU setzt Busfehler", 0, 1, 1, 0, "BU 2200 §7: 0…1, factory 1; parameter-set dependence not printed (one value for all sets assumed)"), POL_ALL), &[Field::Sets]),
    assumed(module(elements(inv(164, "IP Gateway", 0, 255, 0, 0, "BU 2200 §7: factory 192.168.100.254; parameter-set dependence not printed (one value for all sets assumed)"), &[192, 168, 100, 254]), POL_ALL), &[Field::Sets]),
    assumed(module(inv(165, "POWERLINK Zyklus", 400, 4000, 1000, 0, "BU 2200 §7: 400…4000 µs, factory 1000; parameter-set dependence not printed (one value for all sets assumed)"), POL_ALL), &[Field::Sets]),
    assumed(module(inv(166, "PZD transmission format", 0, 1, 0, 0, "BU 2100 §7.1.2: 0 = 32 bit header + status, 1 = modeless (instances 110/111 only); factory 0; parameter-set dependence not printed (one value for all sets assumed)"), EIP_ALL), &[Field::Sets]),
    assumed(module(ro(array(inv(180, "Active assembly", 0, 255, 0, 0, "BU 2100 §7.1.4: [-01] consumer, [-02] producer assembly; no factory setting printed (0 assumed); parameter-set dependence not printed (one value for all sets assumed)"), 2)), EIP_ALL), &[Field::Default, Field::Sets]),
    assumed(module(ro(array(inv(181, "MAC address", 0, 255, 0, 0, "BU 2100 §7.1.4, BU 2200 §7.1.4 (p. 57): [-01]..[-03] manufacturer id F0.5F.5A, [-04]..[-06] free; no factory setting printed (0 assumed); parameter-set dependence not printed (one value for all sets assumed)"), 6)), EIP_POL_ALL), &[Field::Default, Field::Sets]),
    assumed(module(ro(array(inv(185, "Present IP address", 0, 255, 0, 0, "BU 2100 §7.1.4, BU 2200 §7.1.4 (p. 58): [-01]..[-04]; no factory setting printed (0 assumed); parameter-set dependence not printed (one value for all sets assumed)"), 4)), EIP_POL_ALL), &[Field::Default, Field::Sets]),
    assumed(module(ro(array(inv(186, "Present IP subnet mask", 0, 255, 0, 0, "BU 2100 §7.1.4, BU 2200 §7.1.4 (p. 58): [-01]..[-04]; no factory setting printed (0 assumed); parameter-set dependence not printed (one value for all sets assumed)"), 4)), EIP_POL_ALL), &[Field::Default, Field::Sets]),
    assumed(module(ro(array(inv(170, "Actual error", 0, 9999, 0, 0, "BU 2100 §7.1.3: [-01] actual, [-02] last error of the bus interface; parameter-set dependence not printed (one value for all sets assumed)"), 2)), EIP_ALL), &[Field::Sets]),
    assumed(module(ro(inv(172, "Configuration level", 0, 3, 0, 0, "BU 2100 §7.1.3: 0 CU4, 1 TU4, 2 TU3, 3 TU3 with DIP switch; no factory setting printed (0 assumed); parameter-set dependence not printed (one value for all sets assumed)")), EIP_ALL), &[Field::Default, Field::Sets]),
    assumed(module(ro(array(inv(173, "Module status", 0, 0xFFFF, 0, 0, "BU 2100 §7.1.3 (p. 51): [-01] bit 0 ready, 1 cyclic communication, 2 timeout EtherNet/IP, 3 timeout P151/P513, bits 8–15 FI 1..4 in bit pairs; [-02] FI 1..8 in bit pairs (SK TU3-EIP: two arrays); no factory setting printed (0 assumed); parameter-set dependence not printed (one value for all sets assumed)"), 2)), &[Product::Tu3Eip]), &[Field::Default, Field::Sets]),
    assumed(module(ro(inv(173, "Module status", 0, 0xFFFF, 0, 0, "BU 2100 §7.1.3 (p. 51) footnote 1: on the SK xU4-EIP no arrays, the bits of column [-01]; no factory setting printed (0 assumed); parameter-set dependence not printed (one value for all sets assumed)")), &[Product::Tu4Eip, Product::Cu4Eip]), &[Field::Default, Field::Sets]),
    assumed(module(ro(array(inv(171, "Software version", 0, 99999, 0, 1, "BU 2100 §7.1.3 (p. 50): 0.0…9999.9, [-01] version, [-02] revision, [-03] special version (0 = standard); §1.1.2: V 1.3 R1 (SK TU3), R5 (SK TU4), R4 (SK CU4); parameter-set dependence not printed (one value for all sets assumed)"), 3)), EIP_ALL), &[Field::Sets]),
    assumed(module(ro(inv(174, "Digital input status", 0, 255, 0, 0, "BU 2100 §7.1.3 (p. 52): bit n = DIN n+1 of the bus interface (DIN3..DIN8 SK TU4-EIP only); parameter-set dependence not printed (one value for all sets assumed)")), &[Product::Tu4Eip, Product::Cu4Eip]), &[Field::Sets]),
    assumed(module(ro(inv(175, "Relay status", 0, 3, 0, 0, "BU 2100 §7.1.3 (p. 52): bit 0 DO1, bit 1 DO2; no factory setting printed (0 assumed); parameter-set dependence not printed (one value for all sets assumed)")), &[Product::Tu4Eip]), &[Field::Default, Field::Sets]),
    assumed(module(ro(array(inv(176, "Process data Bus In", -32768, 32767, 0, 0, "BU 2100 §7.1.3 (p. 52): [-01] bus module outputs (xU4), [-02 + 6(n-1)] control word and setpoints 1..5 of FI n, up to [-49]; no factory setting printed (0 assumed); parameter-set dependence not printed (one value for all sets assumed)"), 49)), EIP_ALL), &[Field::Default, Field::Sets]),
    assumed(module(ro(array(inv(177, "Process data Bus Out", -32768, 32767, 0, 0, "BU 2100 §7.1.3 (p. 52): [-01] bus module inputs (xU4), [-02 + 6(n-1)] status word and actual values 1..5 of FI n, up to [-49]; no factory setting printed (0 assumed); parameter-set dependence not printed (one value for all sets assumed)"), 49)), EIP_ALL), &[Field::Default, Field::Sets]),
    assumed(module(ro(inv(178, "Internal temperature", -128, 127, 0, 0, "BU 2100 §7.1.3 (p. 52): -128…127 °C, SK CU4-EIP only; above +97 °C error 10.1; no factory setting printed (0 assumed); parameter-set dependence not printed (one value for all sets assumed)")), &[Product::Cu4Eip]), &[Field::Default, Field::Sets]),
    assumed(module(text(array(inv(169, "Password", 0, 122, 0, 0, "BU 2100 §7.1.2 (p. 49): up to 20 characters of ASCII 45…122, factory {0} (outside the printed range: 0 = no password / end of text); parameter-set dependence not printed (one value for all sets assumed)"), 20), 45), EIP_ALL), &[Field::Sets]),
    assumed(module(inv(152, "Factory setting", 0, 1, 0, 0, "BU 0590 §5.1.1: 0…1, factory 0; parameter-set dependence not printed (one value for all sets assumed)"), PNT), &[Field::Sets]),
    assumed(module(inv(162, "Device name", 0, 122, 0, 0, "BU 0590 §5.1.2 (p. 35): ASCII characters 45…122, up to 240 of them; a 0 ends and saves the name (so 0 is allowed, which the printed range 45…122 omits); no factory setting printed, 0 (no name) assumed; parameter-set dependence not printed (one value for all sets assumed)"), PNT), &[Field::Default, Field::Sets]),
    assumed(module(ro(array(inv(170, "Present error", 0, 5420, 0, 0, "BU 0590 §5.1.3 (p. 35): 0…5420, [-01] actual module error, [-02] last (printed \"actual\" twice); 1020 = bus time-out via P151/P513; no factory setting printed (0 assumed); parameter-set dependence not printed (one value for all sets assumed)"), 2)), PNT), &[Field::Default, Field::Sets]),
    assumed(module(ro(array(inv(171, "Software version", 0, 99999, 0, 1, "BU 0590 §5.1.3 (p. 35): 0.0…9999.9, [-01] version, [-02] revision, [-03] special version (0 = standard); parameter-set dependence not printed (one value for all sets assumed)"), 3)), PNT), &[Field::Sets]),
    assumed(module(ro(inv(172, "Configuration level", 0, 2, 0, 0, "BU 0590 §5.1.3 (p. 36): 0 SK CU4, 1 SK TU4, 2 SK TU3-PNT; no factory setting printed (0 assumed); parameter-set dependence not printed (one value for all sets assumed)")), PNT), &[Field::Default, Field::Sets]),
    assumed(module(ro(inv(173, "Module status", 0, 0xFFFF, 0, 0, "BU 0590 §5.1.3 (p. 36): bit 0 initialisation, 1 AR installed, 3 timeout P151/P513, 5 Ethernet connection, bits 9–8 FI status (00 offline, 01 not supported, 10 online); no factory setting printed (0 assumed); parameter-set dependence not printed (one value for all sets assumed)")), PNT), &[Field::Default, Field::Sets]),
    assumed(module(ro(array(inv(176, "PZD bus IN", -32768, 32767, 0, 0, "BU 0590 §5.1.3 (p. 36): [-01]..[-27], [-01] bus module outputs, [-02] control word, [-03]/[-04] setpoints 1/2 for FI 1; no factory setting printed (0 assumed); parameter-set dependence not printed (one value for all sets assumed)"), 27)), PNT), &[Field::Default, Field::Sets]),
    assumed(module(ro(array(inv(177, "PZD bus OUT", -32768, 32767, 0, 0, "BU 0590 §5.1.3 (p. 36): [-01]..[-27], [-01] bus module inputs, [-02] status word, [-03]/[-04] actual values 1/2 from FI 1; no factory setting printed (0 assumed); parameter-set dependence not printed (one value for all sets assumed)"), 27)), PNT), &[Field::Default, Field::Sets]),
    assumed(module(ro(array(inv(180, "PPO type", 0, 7, 0, 0, "BU 0590 §5.1.4 (p. 37): module id per slot [-01]..[-07], [-03] = slot 3 (FI): 0 empty, 1 reserved, 2 DIG-IO, 3 PPO3, 4 PPO4, 5 PPO6, 6 PPO1, 7 PPO2; no factory setting printed (0 assumed); parameter-set dependence not printed (one value for all sets assumed)"), 7)), PNT), &[Field::Default, Field::Sets]),
    assumed(module(ro(array(inv(181, "MAC address", 0, 255, 0, 0, "BU 0590 §5.1.4 (p. 37): [-01]..[-03] PROFINET identification, [-04]..[-06] NORD range 6000…6FFF; example 00:0E:CF:03:60:00; no factory setting printed (0 assumed); parameter-set dependence not printed (one value for all sets assumed)"), 6)), PNT), &[Field::Default, Field::Sets]),
    assumed(module(inv(162, "Geräte Name", 0, 122, 0, 0, "BU 2200 §7.1.2 (p. 51): 0…122 (ASCII), factory 0; without a name the node registers as \"Powerlink <nnn>-0xED\"; parameter-set dependence not printed (one value for all sets assumed)"), POL_ALL), &[Field::Sets]),
    assumed(module(ro(array(inv(170, "Aktueller Fehler", 0, 9999, 0, 0, "BU 2200 §7.1.3 (p. 53): [-01] present, [-02] last error of the bus interface; parameter-set dependence not printed (one value for all sets assumed)"), 2)), POL_ALL), &[Field::Sets]),
    assumed(module(ro(array(inv(171, "Software-Version", 0, 99999, 0, 1, "BU 2200 §7.1.3 (p. 53): 0.0…9999.9, [-01] version, [-02] revision, [-03] special version; parameter-set dependence not printed (one value for all sets assumed)"), 3)), POL_ALL), &[Field::Sets]),
    assumed(module(ro(inv(172, "Ausbaustufe", 0, 3, 0, 0, "BU 2200 §7.1.3 (p. 53): 0 CU4, 1 TU4, 2 TU3, 3 TU3 with DIP switch (the printed range \"0…\" is cut off); no factory setting printed (0 assumed); parameter-set dependence not printed (one value for all sets assumed)")), POL_ALL), &[Field::Default, Field::Sets]),
    assumed(module(ro(array(inv(173, "Baugruppen Zustand", 0, 0xFFFF, 0, 0, "BU 2200 §7.1.3 (p. 54): [-01] bit 0 ready, 1 cyclic communication, 2 timeout Ethernet bus, 3 timeout P151/P513, bits 8–15 status of FI 1..4; [-02] status of FI 1..8 in bit pairs (10 = online); no factory setting printed (0 assumed); parameter-set dependence not printed (one value for all sets assumed)"), 2)), POL_ALL), &[Field::Default, Field::Sets]),
    assumed(module(ro(inv(174, "Zustand Digitaleing.", 0, 255, 0, 0, "BU 2200 §7.1.3 (p. 54): bit n = input n+1 of the bus interface; no factory setting printed (0 assumed); parameter-set dependence not printed (one value for all sets assumed)")), POL_TU4_CU4), &[Field::Default, Field::Sets]),
    assumed(module(ro(inv(175, "Zustand Relais", 0, 3, 0, 0, "BU 2200 §7.1.3 (p. 55): bit 0 DO1, bit 1 DO2; no factory setting printed (0 assumed); parameter-set dependence not printed (one value for all sets assumed)")), &[Product::Tu4Pol]), &[Field::Default, Field::Sets]),
    assumed(module(ro(array(inv(176, "Prozeßdaten Bus In", -32768, 32767, 0, 0, "BU 2200 §7.1.3 (p. 55): [-01] module outputs, [-02 + 6(n-1)] control word and the next five setpoints 1..5 to FI n; no factory setting printed (0 assumed); parameter-set dependence not printed (one value for all sets assumed)"), 49)), POL_ALL), &[Field::Default, Field::Sets]),
    assumed(module(ro(array(inv(177, "Prozessdaten Bus Out", -32768, 32767, 0, 0, "BU 2200 §7.1.3 (p. 55): [-01] module inputs, [-02 + 6(n-1)] status word and the next five actual values 1..5 of FI n; no factory setting printed (0 assumed); parameter-set dependence not printed (one value for all sets assumed)"), 49)), POL_ALL), &[Field::Default, Field::Sets]),
    assumed(module(ro(inv(178, "Innenraumtemperatur", -128, 127, 0, 0, "BU 2200 §7.1.3 (p. 56): -128…127 °C; above +97 °C an error is reported; no factory setting printed (0 assumed); parameter-set dependence not printed (one value for all sets assumed)")), &[Product::Cu4Pol]), &[Field::Default, Field::Sets]),
    assumed(module(ro(inv(182, "NMT State", 0, 0xFF, 0, 0, "BU 2200 §7.1.4 (p. 57): POWERLINK NMT state codes (proto::nord::nmt::P182_CODES); no factory setting printed (0 assumed); parameter-set dependence not printed (one value for all sets assumed)")), POL_ALL), &[Field::Default, Field::Sets]),
    assumed(module(ro(inv(183, "NMT Error", -32768, 32767, 0, 0, "BU 2200 §7.1.4 (p. 58): errors of the Controlled Node (DS-301 codes); no factory setting printed (0 assumed); parameter-set dependence not printed (one value for all sets assumed)")), POL_ALL), &[Field::Default, Field::Sets]),
    assumed(module(ro(array(dword(inv(184, "NMT Statechangecount", 0, i32::MAX, 0, 0, "BU 2200 §7.1.4 (p. 58): error counters 0…2^31 (the extraction prints \"0…231\"; 2^31 - 1 is the largest 32-bit value), [-01] loss of SoC … [-06] CRC error; cleared at restart; parameter-set dependence not printed (one value for all sets assumed)")), 6)), POL_ALL), &[Field::Sets]),
    assumed(module(elements(inv(160, "IP address", 0, 255, 0, 0, "BU 0590 §5.1.2: factory 192.168.20.200; parameter-set dependence not printed (one value for all sets assumed)"), &[192, 168, 20, 200]), PNT), &[Field::Sets]),
    assumed(module(elements(inv(161, "IP sub-net mask", 0, 255, 0, 0, "BU 0590 §5.1.2: factory 255.255.255.0; parameter-set dependence not printed (one value for all sets assumed)"), MASK_DEFAULT), PNT), &[Field::Sets]),
    assumed(module(array(inv(163, "Test alarm", 0, 255, 0, 0, "BU 0590 §5.1.2: [-01]..[-07] slots, all {0}; parameter-set dependence not printed (one value for all sets assumed)"), 7), PNT), &[Field::Sets]),
]);

/// IP address factory setting 192.168.1.100 (BU 0620 §4.2.2, BU 2100 §7.1.2).
const IP_DEFAULT: &[i32] = &[192, 168, 1, 100];
/// Sub-net mask factory setting 255.255.255.0.
const MASK_DEFAULT: &[i32] = &[255, 255, 255, 0];

/// Factory setting of one array element (1-based): the element's own where the manual gives
/// one, else the parameter's.
pub fn element_default(def: &ParamDef, element: u8) -> i32 {
    usize::from(element)
        .checked_sub(1)
        .and_then(|i| def.element_defaults.get(i))
        .copied()
        .unwrap_or(def.default)
}

/// Values inside min..=max that a parameter still refuses: the SK TU3-PNT's device name P162
/// takes the ASCII characters 45…122 and the 0 that ends the name (BU 0590 §5.1.2, p. 35), not
/// 1…44.
pub fn value_allowed(def: &ParamDef, product: Product, value: i32) -> bool {
    let name_gap = product == Product::Tu3Pnt && def.owner == Owner::Interface && def.number == 162;
    !(name_gap && (1..45).contains(&value))
}

impl ParamDef {
    /// Whether a value is in the setting range (a text parameter's: 0 or a character).
    pub fn accepts(&self, value: i32) -> bool {
        (self.min..=self.max).contains(&value)
            && (self.text_from == 0 || value == 0 || value >= self.text_from)
    }

    /// Whether `product` has the parameter.
    pub fn applies_to(&self, product: Product) -> bool {
        self.family.is_none_or(|f| f == product.family())
            && (self.products.is_empty() || self.products.contains(&product))
    }
}

impl Row for ParamDef {
    /// A default one off (the first element's, for an array whose elements have their own), a
    /// range narrowed by one at either end, one decimal more, one array element fewer, the
    /// writability and the set dependence swapped: each where the manuals state the field.
    fn changes(&self) -> Vec<(&'static str, String, ParamDef)> {
        let p = format!("P{} ({})", self.number, owner_name(self.owner));
        let mut out = Vec::new();
        let mut add = |field: Field, key: &'static str, what: String, def: ParamDef| {
            if !self.assumed.contains(&field) {
                out.push((key, format!("{p} {what}"), def));
            }
        };
        let bumped = |v: i32| if v < self.max { v + 1 } else { v - 1 };
        match self.element_defaults.split_first() {
            Some((&first, rest)) => {
                let mut defaults = vec![bumped(first)];
                defaults.extend_from_slice(rest);
                let what = format!("[-01] default {first} → {}", defaults[0]);
                let element_defaults = Vec::leak(defaults);
                add(
                    Field::Default,
                    "default",
                    what,
                    ParamDef {
                        element_defaults,
                        ..*self
                    },
                );
            }
            None => {
                let default = bumped(self.default);
                let what = format!("default {} → {default}", self.default);
                add(
                    Field::Default,
                    "default",
                    what,
                    ParamDef { default, ..*self },
                );
            }
        }
        if self.min < self.max {
            let (min, max) = (self.min + 1, self.max - 1);
            let what = format!("minimum {} → {min}", self.min);
            add(Field::Range, "min", what, ParamDef { min, ..*self });
            let what = format!("maximum {} → {max}", self.max);
            add(Field::Range, "max", what, ParamDef { max, ..*self });
        }
        let decimals = self.decimals + 1;
        let what = format!("decimals {} → {decimals}", self.decimals);
        add(
            Field::Decimals,
            "decimals",
            what,
            ParamDef { decimals, ..*self },
        );
        if let Some(n) = self.array.filter(|n| *n > 1) {
            let what = format!("array of {n} → {}", n - 1);
            add(
                Field::Array,
                "array",
                what,
                ParamDef {
                    array: Some(n - 1),
                    ..*self
                },
            );
        }
        let access = match self.access {
            Access::ReadWrite => Access::ReadOnly,
            Access::ReadOnly | Access::ResetOnly => Access::ReadWrite,
        };
        let what = format!("{:?} → {access:?}", self.access);
        add(Field::Access, "access", what, ParamDef { access, ..*self });
        let set_dependent = !self.set_dependent;
        let what = format!(
            "{} → {}",
            set_name(self.set_dependent),
            set_name(set_dependent)
        );
        add(
            Field::Sets,
            "sets",
            what,
            ParamDef {
                set_dependent,
                ..*self
            },
        );
        out
    }

    fn source(&self) -> Option<&'static str> {
        Some(self.source)
    }

    fn parameter(&self) -> Option<u16> {
        Some(self.number)
    }
}

fn owner_name(owner: Owner) -> &'static str {
    match owner {
        Owner::Interface => "bus interface",
        Owner::Inverter => "inverter",
    }
}

fn set_name(dependent: bool) -> &'static str {
    if dependent {
        "per parameter set"
    } else {
        "one for all sets"
    }
}

/// The parameter `number` of a unit of `product`.
pub fn lookup(product: Product, owner: Owner, number: ParamNumber) -> Option<&'static ParamDef> {
    let unit = Product::ALL.iter().position(|p| *p == product)? * 2
        + usize::from(owner == Owner::Inverter);
    table()[unit]
        .get(usize::from(number.get()))
        .copied()
        .flatten()
}

/// Every unit's parameters by number: for each product (in [`Product::ALL`] order) its
/// interface's and its inverters' table of P0…P999, built once from the catalogue, as the
/// simulator looks parameters up on every bus cycle.
fn table() -> &'static [Vec<Option<&'static ParamDef>>] {
    static TABLE: std::sync::OnceLock<Vec<Vec<Option<&'static ParamDef>>>> =
        std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        let mut index: Vec<Vec<usize>> = vec![Vec::new(); 1000];
        for (i, d) in CATALOGUE.iter().enumerate() {
            if let Some(entries) = index.get_mut(usize::from(d.number)) {
                entries.push(i);
            }
        }
        let mut units = Vec::new();
        for product in Product::ALL {
            for owner in [Owner::Interface, Owner::Inverter] {
                units.push(
                    index
                        .iter()
                        .map(|entries| {
                            entries
                                .iter()
                                .map(|&i| &CATALOGUE[i])
                                .find(|d| d.owner == owner && d.applies_to(product))
                        })
                        .collect(),
                );
            }
        }
        units
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(n: i64) -> ParamNumber {
        ParamNumber::new(n).unwrap()
    }

    #[test]
    fn p102_has_resolution_0_01_and_four_sets() {
        let d = lookup(Product::Sk550p, Owner::Inverter, p(102)).unwrap();
        assert_eq!(
            (d.decimals, d.set_dependent, d.width),
            (2, true, Width::Word)
        );
        // BU 0620 §2.5.6.3: 99.99 s is transferred as 9999: inside the range.
        assert!((d.min..=d.max).contains(&9999));
    }

    #[test]
    fn interface_parameters_belong_to_the_sk550p() {
        assert!(lookup(Product::Sk550p, Owner::Interface, p(872)).is_some());
        assert!(lookup(Product::Tu3Pnt, Owner::Interface, p(872)).is_none());
        assert_eq!(
            element_default(
                lookup(Product::Sk550p, Owner::Interface, p(850)).unwrap(),
                4
            ),
            100
        );
    }

    #[test]
    fn module_parameters_per_product() {
        assert!(lookup(Product::Tu4Eip, Owner::Interface, p(150)).is_some());
        assert!(lookup(Product::Tu3Eip, Owner::Interface, p(150)).is_none());
        assert!(lookup(Product::Tu3Eip, Owner::Interface, p(160)).is_some());
        assert!(lookup(Product::Sk550p, Owner::Interface, p(160)).is_none());
    }

    #[rstest::rstest]
    // BU 0620 §4.2.3/§4.2.4 (p. 80–83), §5.4.1 (p. 95), §4.4.2 (p. 87): (P, min, max, default).
    #[case(Product::Sk550p, 854, 0, 122, 0)]
    #[case(Product::Sk550p, 857, 0, 1, 1)]
    #[case(Product::Sk550p, 858, 400, 2000, 1000)]
    #[case(Product::Sk550p, 877, 0, 255, 0)]
    // BU 0590 §5.1.2–§5.1.4 (p. 35–37).
    #[case(Product::Tu3Pnt, 162, 0, 122, 0)]
    // BU 2100 §7.1.2–§7.1.3 (p. 49–52).
    #[case(Product::Tu4Eip, 169, 0, 122, 0)]
    #[case(Product::Cu4Eip, 178, -128, 127, 0)]
    #[case(Product::Tu4Eip, 175, 0, 3, 0)]
    #[case(Product::Tu3Pnt, 170, 0, 5420, 0)]
    #[case(Product::Tu3Pnt, 172, 0, 2, 0)]
    #[case(Product::Tu3Pnt, 180, 0, 7, 0)]
    // BU 2200 §7.1.2–§7.1.4 (p. 51–58).
    #[case(Product::Tu3Pol, 162, 0, 122, 0)]
    #[case(Product::Tu3Pol, 170, 0, 9999, 0)]
    #[case(Product::Cu4Pol, 178, -128, 127, 0)]
    #[case(Product::Tu4Pol, 182, 0, 0xFF, 0)]
    #[case(Product::Tu4Pol, 183, -32768, 32767, 0)]
    fn bus_parameters(
        #[case] product: Product,
        #[case] number: i64,
        #[case] min: i32,
        #[case] max: i32,
        #[case] default: i32,
    ) {
        let d = lookup(product, Owner::Interface, p(number)).unwrap();
        assert_eq!((d.min, d.max, d.default), (min, max, default));
    }

    #[test]
    fn inverter_parameters_of_chapters_4_to_7() {
        // BU 0620 §3.9 step 7, §4.5, §5.2, §7.1.
        let fi = |n| lookup(Product::Sk550p, Owner::Inverter, p(n)).unwrap();
        assert_eq!((fi(120).array, fi(120).min, fi(120).max), (Some(4), 0, 2));
        assert_eq!(fi(506).access, Access::ReadWrite);
        assert_eq!(
            (fi(701).access, fi(707).access),
            (Access::ReadOnly, Access::ReadOnly)
        );
        assert_eq!(
            (fi(744).array, fi(745).array, fi(746).array),
            (Some(2), Some(11), Some(3))
        );
        // The XU5 extension parameters are the SK 550P's only; the modules' inverters have one
        // value each (BU 2100 §7.2 p. 55), P745 not behind the SK CU4.
        assert_eq!(
            lookup(Product::Tu3Eip, Owner::Inverter, p(744)).map(|d| d.array),
            Some(None)
        );
        assert!(lookup(Product::Cu4Eip, Owner::Inverter, p(745)).is_none());
        assert!(lookup(Product::Tu4Pol, Owner::Inverter, p(746)).is_some());
        // §4: position values (POSICON) are double words.
        assert_eq!((fi(615).width, fi(102).width), (Width::Dword, Width::Word));
    }

    #[test]
    fn information_parameters_of_the_modules() {
        let gateway = lookup(Product::Sk550p, Owner::Interface, p(877)).unwrap();
        assert_eq!((gateway.access, gateway.array), (Access::ReadOnly, Some(4)));
        let counters = lookup(Product::Tu3Pol, Owner::Interface, p(184)).unwrap();
        assert_eq!((counters.width, counters.array), (Width::Dword, Some(6)));
        assert_eq!(
            lookup(Product::Tu3Pol, Owner::Interface, p(176)).and_then(|d| d.array),
            Some(49)
        );
        // Per product: P174 on SK TU4/CU4-POL, P175 on SK TU4-POL, P178 on SK CU4-POL only.
        assert!(lookup(Product::Tu3Pol, Owner::Interface, p(174)).is_none());
        assert!(lookup(Product::Cu4Pol, Owner::Interface, p(175)).is_none());
        assert!(lookup(Product::Tu4Pol, Owner::Interface, p(178)).is_none());
        // The modules' MAC address P181 and present address P185 on POWERLINK too.
        assert!(lookup(Product::Cu4Pol, Owner::Interface, p(181)).is_some());
        assert!(lookup(Product::Tu3Pol, Owner::Interface, p(185)).is_some());
        assert!(lookup(Product::Tu3Pnt, Owner::Interface, p(185)).is_none());
    }

    #[test]
    fn ethernet_ip_module_information_parameters() {
        // BU 2100 §7.1.3 (p. 51) P173: two arrays on the SK TU3-EIP, none on the SK xU4-EIP.
        let p173 = |product| lookup(product, Owner::Interface, p(173)).unwrap().array;
        assert_eq!(p173(Product::Tu3Eip), Some(2));
        assert_eq!((p173(Product::Tu4Eip), p173(Product::Cu4Eip)), (None, None));
        // P174 on the SK CU4/TU4-EIP, P175 on the SK TU4-EIP, P178 on the SK CU4-EIP only.
        assert!(lookup(Product::Tu3Eip, Owner::Interface, p(174)).is_none());
        assert!(lookup(Product::Cu4Eip, Owner::Interface, p(175)).is_none());
        assert!(lookup(Product::Tu4Eip, Owner::Interface, p(178)).is_none());
        assert_eq!(
            lookup(Product::Tu3Eip, Owner::Interface, p(177)).and_then(|d| d.array),
            Some(49)
        );
    }

    #[test]
    fn text_parameters_take_0_and_their_ascii_range() {
        // BU 2100 §7.1.2 P169 "45...122 ASCII", factory {0}.
        let d = lookup(Product::Tu3Eip, Owner::Interface, p(169)).unwrap();
        let taken: Vec<i32> = [0, 1, 44, 45, 122, 123]
            .into_iter()
            .filter(|v| d.accepts(*v))
            .collect();
        assert_eq!((taken, d.text_from), (vec![0, 45, 122], 45));
    }

    #[test]
    fn tu3_pnt_device_name_refuses_1_to_44() {
        // BU 0590 §5.1.2 (p. 35) P162: ASCII characters 45…122, and the 0 that ends the name.
        let d = lookup(Product::Tu3Pnt, Owner::Interface, p(162)).unwrap();
        let taken: Vec<i32> = [0, 1, 44, 45, 122]
            .into_iter()
            .filter(|v| value_allowed(d, Product::Tu3Pnt, *v))
            .collect();
        assert_eq!(taken, [0, 45, 122]);
        // No other parameter has the gap: BU 2200's P162 prints 0…122, and P102 takes 1…44
        // where its range does.
        let pol = lookup(Product::Tu3Pol, Owner::Interface, p(162)).unwrap();
        assert!(value_allowed(pol, Product::Tu3Pol, 10));
        let other = lookup(Product::Sk550p, Owner::Inverter, p(102)).unwrap();
        assert!(value_allowed(other, Product::Sk550p, 10));
    }

    #[test]
    fn every_parameter_mutant_changes_its_row() {
        // `harness mutants` (`super::super::mutant`): each mutant changes one datum the manual
        // states. A change that leaves the row as printed could survive every case, and the
        // range is narrowed (a value the manual allows refused), never widened.
        use crate::nord::mutant::Row;
        for d in CATALOGUE.iter() {
            for (field, what, new) in d.changes() {
                assert_ne!(new, *d, "P{} {field}: {what}", d.number);
                match field {
                    "min" => assert_eq!(new.min, d.min + 1, "P{}: {what}", d.number),
                    "max" => assert_eq!(new.max, d.max - 1, "P{}: {what}", d.number),
                    _ => {}
                }
            }
        }
    }

    #[test]
    fn lookup_finds_every_entry_of_the_catalogue() {
        for d in CATALOGUE.iter() {
            let n = ParamNumber::new(i64::from(d.number)).unwrap();
            for product in Product::ALL.into_iter().filter(|p| d.applies_to(*p)) {
                let found = lookup(product, d.owner, n).unwrap();
                // The first entry that applies, as a scan of the catalogue finds it.
                let first = CATALOGUE
                    .iter()
                    .find(|e| e.number == d.number && e.owner == d.owner && e.applies_to(product));
                assert_eq!(found, first.unwrap(), "P{}", d.number);
            }
        }
    }

    #[test]
    fn catalogue_is_consistent() {
        for d in CATALOGUE.iter() {
            assert!(d.accepts(d.default), "P{} default outside range", d.number);
            assert!(d.number <= 999 && !d.source.is_empty());
            for product in Product::ALL {
                let same: Vec<_> = CATALOGUE
                    .iter()
                    .filter(|o| o.number == d.number && o.owner == d.owner && o.applies_to(product))
                    .collect();
                // Two only where the first names the product (it overrides the general entry
                // for the inverter that product sits on, as BU 0590's SK 5xxE).
                let overridden = same.len() == 2 && same[0].products.contains(&product);
                assert!(
                    same.len() <= 1 || overridden || !d.applies_to(product),
                    "P{} twice",
                    d.number
                );
            }
        }
    }
}
