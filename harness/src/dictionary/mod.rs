//! The NORD parameters as CANopen objects, for the device descriptions the CANopen-style buses
//! write (the POWERLINK XDD, DS 311; the system bus's EDS, CiA 306): one model of an object,
//! its sub-objects, types, access, defaults and limits, filled from the parameter catalogue
//! (`proto::nord::params`) the simulated devices answer from. A parameter with sets or elements
//! is an ARRAY whose sub-index 0 is the count (`proto::nord::ecat::parameter_subindex`).
//!
//! The two writers built on it live here too ([`xdd`], [`eds`]), not in their buses' folders:
//! the reference model reads the XDD (BU 2200 §5.2.1: the SK TU3-POL's file carries the
//! inverters' parameters), and the model sits below every bus.

pub(crate) mod eds;
pub(crate) mod xdd;

use std::collections::BTreeSet;

use proto::nord::ecat::{
    parameter_count, parameter_data_type, parameter_subindex, DataType, ObjectCode, ParamSub,
};
use proto::nord::params::{self, Access, Owner, ParamDef};
use proto::nord::{Family, Inverter, ParamNumber, Product};

/// Why a device description (`harness describe <format>`) cannot be written, for every format.
#[derive(Debug, thiserror::Error)]
pub(crate) enum DescribeError {
    /// A generic profile: any maker's device has no NORD description.
    #[error("profile `{0}` stands for any maker's device, not a NORD product")]
    AnyMaker(String),
    /// The product has no interface of the bus the format describes.
    #[error("{} has no {bus} interface ({}): there is no {format} for it", product.name(), product.manual())]
    NoInterface {
        /// The product.
        product: Product,
        /// The bus, as people write it.
        bus: &'static str,
        /// The format (`EDS`, `XDD`).
        format: &'static str,
    },
    /// More inverters, or a higher inverter number, than the product has.
    #[error("{} has {} behind it, not {asked}", product.name(), inverter_range(*product))]
    Inverters {
        /// The product.
        product: Product,
        /// The count or number asked for.
        asked: u8,
    },
    /// The definitions the file is written from contradict each other: a bug of the harness.
    #[error("{0} (a bug)")]
    Inconsistent(String),
    /// The text could not be written (it is written to memory: only on a bug).
    #[error("cannot write the {format}: {detail}")]
    Write {
        /// The format.
        format: &'static str,
        /// What the writer said.
        detail: String,
    },
}

/// The inverter counts a product can have behind it, as a message says them.
fn inverter_range(product: Product) -> String {
    match product.max_inverters() {
        1 => "1 inverter".into(),
        max => format!("1…{max} inverters"),
    }
}

impl DescribeError {
    /// The error unless `inverters` is a count the product can have behind it.
    pub(crate) fn check_inverters(product: Product, inverters: u8) -> Result<(), DescribeError> {
        if (1..=product.max_inverters()).contains(&inverters) {
            Ok(())
        } else {
            Err(DescribeError::Inverters {
                product,
                asked: inverters,
            })
        }
    }
}

/// One object or sub-object as a device description writes it (a DS 311 `Object` or
/// `SubObject`, a CiA 306 EDS section).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ObjectDoc {
    /// Index (objects) or sub-index (sub-objects).
    pub(crate) at: u16,
    pub(crate) name: String,
    /// 7 VAR, 8 ARRAY, 9 RECORD.
    pub(crate) object_type: u8,
    /// CANopen data type code (DS 311 and CiA 306 share them); on an ARRAY the elements' type, on a RECORD none.
    pub(crate) data_type: Option<u16>,
    /// `const`, `ro`, `rw` (VARs only).
    pub(crate) access: Option<&'static str>,
    /// `no`, `RPDO`, `TPDO` (VARs only).
    pub(crate) pdo: Option<&'static str>,
    pub(crate) default: Option<String>,
    pub(crate) limits: Option<(i32, i32)>,
    pub(crate) subs: Vec<ObjectDoc>,
}

impl ObjectDoc {
    pub(crate) fn var(
        at: u16,
        name: impl Into<String>,
        data_type: u16,
        access: &'static str,
    ) -> ObjectDoc {
        ObjectDoc {
            at,
            name: name.into(),
            object_type: 7,
            data_type: Some(data_type),
            access: Some(access),
            pdo: Some("no"),
            default: None,
            limits: None,
            subs: Vec::new(),
        }
    }

    pub(crate) fn default(self, v: impl Into<String>) -> ObjectDoc {
        ObjectDoc {
            default: Some(v.into()),
            ..self
        }
    }

    pub(crate) fn compound(
        at: u16,
        name: &str,
        code: ObjectCode,
        subs: Vec<ObjectDoc>,
    ) -> ObjectDoc {
        let data_type = match code {
            ObjectCode::Array => subs.iter().find(|s| s.at != 0).and_then(|s| s.data_type),
            _ => None,
        };
        ObjectDoc {
            at,
            name: name.into(),
            object_type: code.code(),
            data_type,
            access: None,
            pdo: None,
            default: None,
            limits: None,
            subs,
        }
    }
}

/// The parameters a unit of `product` has (as its parameter store looks them up), by number.
pub(crate) fn defs(product: Product, owner: Owner) -> Vec<&'static ParamDef> {
    let numbers: BTreeSet<u16> = params::CATALOGUE.iter().map(|d| d.number).collect();
    numbers
        .into_iter()
        .filter_map(|n| ParamNumber::new(i64::from(n)).ok())
        .filter_map(|n| params::lookup(product, owner, n))
        .collect()
}

/// Parameter `d` at `base` + its number: a VAR, or an ARRAY of its sets and elements.
pub(crate) fn parameter(base: u16, prefix: &str, d: &ParamDef) -> ObjectDoc {
    let index = base + d.number;
    let name = format!("{prefix}P{:03} {}", d.number, d.name);
    let ty = parameter_data_type(d).code();
    let rw = match d.access {
        Access::ReadOnly => "ro",
        Access::ReadWrite | Access::ResetOnly => "rw",
    };
    let var = |at: u16, name: String, default: i32| ObjectDoc {
        limits: Some((d.min, d.max)),
        ..ObjectDoc::var(at, name, ty, rw).default(default.to_string())
    };
    let Some(count) = parameter_count(d.set_dependent, d.array) else {
        return var(index, name, d.default);
    };
    let mut subs = vec![
        ObjectDoc::var(0, "NumberOfEntries", DataType::U8.code(), "ro").default(count.to_string()),
    ];
    for s in 1..=count {
        let Some(ParamSub::Value(set, element)) = parameter_subindex(s, d.set_dependent, d.array)
        else {
            continue;
        };
        let default = element.map_or(d.default, |e| params::element_default(d, e.get()));
        let label = match (set, element) {
            (Some(p), Some(e)) => format!("[-{:02}] set {}", e.get(), p.get()),
            (Some(p), None) => format!("Set {}", p.get()),
            (None, Some(e)) => format!("[-{:02}]", e.get()),
            (None, None) => format!("Sub-index {s}"),
        };
        subs.push(var(u16::from(s), label, default));
    }
    ObjectDoc::compound(index, &name, ObjectCode::Array, subs)
}

/// The parameters inverter `fi` of `product` answers: its own, and on the SK 550P, whose
/// interface is built into FI 1, the interface's there too.
pub(crate) fn inverter_parameters(product: Product, fi: Inverter) -> Vec<&'static ParamDef> {
    let mut ds = defs(product, Owner::Inverter);
    if fi.get() == 1 && product.family() == Family::Integrated {
        let iface = defs(product, Owner::Interface);
        ds.retain(|d| !iface.iter().any(|i| i.number == d.number));
        ds.extend(iface);
        ds.sort_by_key(|d| d.number);
    }
    ds
}
