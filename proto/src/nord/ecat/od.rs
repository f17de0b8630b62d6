//! The CoE object dictionary of BU 0620 §2.2.7.1 as data: data types, objects and entries, the
//! fixed PDOs per inverter and their mapping.

use super::super::types::Inverter;
use super::device::{
    sync_managers, DEVICE_NAME, DEVICE_TYPE, HARDWARE_VERSION, MAX_INVERTERS, PRODUCT_CODE,
    REVISION, SERIAL_NUMBER, SOFTWARE_VERSION, VENDOR_ID,
};

/// A CoE basic data type (ETG.1000.6 table 64, CiA 301 table 44).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub enum DataType {
    /// UNSIGNED8 (ESI `USINT`).
    U8,
    /// UNSIGNED16 (`UINT`).
    U16,
    /// UNSIGNED32 (`UDINT`).
    U32,
    /// INTEGER16 (`INT`).
    I16,
    /// INTEGER32 (`DINT`).
    I32,
    /// UNSIGNED64 (`ULINT`; POWERLINK PDO mapping entries).
    U64,
    /// VISIBLE_STRING of the given length (`STRING(n)`).
    String(u16),
}

impl DataType {
    /// The CoE data type index (0005h UNSIGNED8 …).
    pub fn code(self) -> u16 {
        match self {
            DataType::I16 => 0x0003,
            DataType::I32 => 0x0004,
            DataType::U8 => 0x0005,
            DataType::U16 => 0x0006,
            DataType::U32 => 0x0007,
            DataType::U64 => 0x001B,
            DataType::String(_) => 0x0009,
        }
    }

    /// Size in bits.
    pub fn bits(self) -> u16 {
        match self {
            DataType::U8 => 8,
            DataType::U16 | DataType::I16 => 16,
            DataType::U32 | DataType::I32 => 32,
            DataType::U64 => 64,
            DataType::String(n) => n.saturating_mul(8),
        }
    }

    /// Size in bytes.
    pub fn bytes(self) -> usize {
        usize::from(self.bits() / 8)
    }

    /// The ESI (ETG.2000) type name.
    pub fn esi_name(self) -> String {
        match self {
            DataType::U8 => "USINT".into(),
            DataType::U16 => "UINT".into(),
            DataType::U32 => "UDINT".into(),
            DataType::I16 => "INT".into(),
            DataType::I32 => "DINT".into(),
            DataType::U64 => "ULINT".into(),
            DataType::String(n) => format!("STRING({n})"),
        }
    }
}

/// CoE object code (ETG.1000.6 §5.6.3.6: VAR 7, ARRAY 8, RECORD 9).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum ObjectCode {
    /// A single value at sub-index 0.
    Var,
    /// Sub-index 0 the count, sub-indices 1.. of one type.
    Array,
    /// Sub-index 0 the count, sub-indices 1.. of their own types.
    Record,
}

impl ObjectCode {
    /// The numeric object code.
    pub fn code(self) -> u8 {
        match self {
            ObjectCode::Var => 7,
            ObjectCode::Array => 8,
            ObjectCode::Record => 9,
        }
    }
}

/// SDO access of an entry (§2.2.7.1 "Read/Write").
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum EntryAccess {
    /// Read only.
    Ro,
    /// Read and write.
    Rw,
}

/// Whether and how an entry can be mapped into a PDO.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum PdoMapping {
    /// Not mappable.
    None,
    /// Mapped into an RxPDO (outputs).
    Rx,
    /// Mapped into a TxPDO (inputs).
    Tx,
}

/// Where an entry's value comes from.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub enum Value {
    /// A constant number of the entry's type.
    Number(u64),
    /// A constant string.
    Text(&'static str),
    /// Word `word` (0 = control word, 1..5 = setpoints) of FI `inverter`'s outputs, as last
    /// received by process data.
    Output {
        /// FI 1..8.
        inverter: u8,
        /// 0..=5.
        word: u8,
    },
    /// Word `word` (0 = status word, 1..5 = actual values) of FI `inverter`'s inputs.
    Input {
        /// FI 1..8.
        inverter: u8,
        /// 0..=5.
        word: u8,
    },
}

/// One sub-index of an object.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct Entry {
    /// Sub-index.
    pub sub: u8,
    /// Name.
    pub name: String,
    /// Type.
    pub data_type: DataType,
    /// SDO access.
    pub access: EntryAccess,
    /// PDO mapping.
    pub pdo: PdoMapping,
    /// Value source.
    pub value: Value,
}

/// One object of the dictionary.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct Object {
    /// Index.
    pub index: u16,
    /// Name.
    pub name: String,
    /// VAR, ARRAY or RECORD.
    pub code: ObjectCode,
    /// Its sub-indices (for ARRAY and RECORD, sub-index 0 first: the highest sub-index).
    pub entries: Vec<Entry>,
}

impl Object {
    /// The entry at `sub`, if it exists.
    pub fn entry(&self, sub: u8) -> Option<&Entry> {
        self.entries.iter().find(|e| e.sub == sub)
    }
}

pub(crate) fn entry(sub: u8, name: impl Into<String>, data_type: DataType, value: Value) -> Entry {
    Entry {
        sub,
        name: name.into(),
        data_type,
        access: EntryAccess::Ro,
        pdo: PdoMapping::None,
        value,
    }
}

pub(crate) fn var(index: u16, name: &str, data_type: DataType, value: Value) -> Object {
    Object {
        index,
        name: name.into(),
        code: ObjectCode::Var,
        entries: vec![entry(0, name, data_type, value)],
    }
}

/// An ARRAY or RECORD whose sub-index 0 counts `entries`.
pub(crate) fn compound(index: u16, name: String, code: ObjectCode, entries: Vec<Entry>) -> Object {
    let count = entries.iter().map(|e| e.sub).max().unwrap_or(0);
    let mut all = vec![entry(
        0,
        "Largest sub-index",
        DataType::U8,
        Value::Number(u64::from(count)),
    )];
    all.extend(entries);
    Object {
        index,
        name,
        code,
        entries: all,
    }
}

/// Index of FI `inverter`'s output object (control word, setpoints 1..5): 7000h + 10h·(FI−1).
pub fn outputs_index(inverter: Inverter) -> u16 {
    0x7000 + 0x10 * u16::from(inverter.get() - 1)
}

/// Index of FI `inverter`'s input object (status word, actual values 1..5): 6000h + 10h·(FI−1).
pub fn inputs_index(inverter: Inverter) -> u16 {
    0x6000 + 0x10 * u16::from(inverter.get() - 1)
}

/// Index of FI `inverter`'s RxPDO: 1600h + FI−1 (§2.2.7.1 "xx00 = FI 1, …, xx07 = FI 8").
pub fn rx_pdo_index(inverter: Inverter) -> u16 {
    0x1600 + u16::from(inverter.get() - 1)
}

/// Index of FI `inverter`'s TxPDO: 1A00h + FI−1.
pub fn tx_pdo_index(inverter: Inverter) -> u16 {
    0x1A00 + u16::from(inverter.get() - 1)
}

/// The data type of process data word `word` (0 the control/status word, UNSIGNED16; 1..5
/// setpoints/actual values, INTEGER16: signed percentages of P105, §6.1.2.4).
pub fn word_type(word: u8) -> DataType {
    if word == 0 {
        DataType::U16
    } else {
        DataType::I16
    }
}

/// One mapped entry of a PDO.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct PdoEntry {
    /// The mapped object.
    pub index: u16,
    /// Its sub-index.
    pub sub: u8,
    /// Bits.
    pub bits: u8,
    /// Name.
    pub name: String,
    /// Type.
    pub data_type: DataType,
}

impl PdoEntry {
    /// The mapping object's value: index · 10000h + sub-index · 100h + bit length (ETG.1000.6
    /// §5.6.7.4.7).
    pub fn mapping(&self) -> u32 {
        u32::from(self.index) << 16 | u32::from(self.sub) << 8 | u32::from(self.bits)
    }
}

/// One PDO of one inverter.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct Pdo {
    /// 1600h.. (RxPDO) or 1A00h.. (TxPDO).
    pub index: u16,
    /// Name.
    pub name: String,
    /// The SyncManager it is assigned to (2 outputs, 3 inputs).
    pub sm: u8,
    /// The inverter it carries.
    pub inverter: Inverter,
    /// Fixed mapping (§2.2.6 "The structure of EtherCAT process data is fixed").
    pub fixed: bool,
    /// Control/status word, then the five values.
    pub entries: Vec<PdoEntry>,
}

const OUT_NAMES: [&str; 6] = [
    "Control word",
    "Setpoint 1",
    "Setpoint 2",
    "Setpoint 3",
    "Setpoint 4",
    "Setpoint 5",
];
const IN_NAMES: [&str; 6] = [
    "Status word",
    "Actual value 1",
    "Actual value 2",
    "Actual value 3",
    "Actual value 4",
    "Actual value 5",
];

fn pdo(inverter: Inverter, rx: bool) -> Pdo {
    let (index, object, names, sm, kind) = if rx {
        (
            rx_pdo_index(inverter),
            outputs_index(inverter),
            OUT_NAMES,
            2,
            "RxPDO",
        )
    } else {
        (
            tx_pdo_index(inverter),
            inputs_index(inverter),
            IN_NAMES,
            3,
            "TxPDO",
        )
    };
    Pdo {
        index,
        name: format!("{kind} FI {}", inverter.get()),
        sm,
        inverter,
        fixed: true,
        entries: (0u8..)
            .zip(names)
            .map(|(w, n)| PdoEntry {
                index: object,
                sub: w + 1,
                bits: 16,
                name: n.into(),
                data_type: word_type(w),
            })
            .collect(),
    }
}

fn inverters_up_to(inverters: u8) -> impl Iterator<Item = Inverter> {
    (1..=inverters.clamp(1, MAX_INVERTERS)).filter_map(|n| Inverter::new(i64::from(n)).ok())
}

/// The RxPDOs (outputs) of FI 1..=`inverters`, assigned to SM2 in this order (1C12h).
pub fn rx_pdos(inverters: u8) -> Vec<Pdo> {
    inverters_up_to(inverters).map(|i| pdo(i, true)).collect()
}

/// The TxPDOs (inputs) of FI 1..=`inverters`, assigned to SM3 in this order (1C13h).
pub fn tx_pdos(inverters: u8) -> Vec<Pdo> {
    inverters_up_to(inverters).map(|i| pdo(i, false)).collect()
}

/// The object dictionary of §2.2.7.1 for a device with `inverters` inverters, sorted by index
/// (the NORD parameter objects 2000h–5FFFh are not listed: see [`parameter_object`]).
pub fn object_dictionary(inverters: u8) -> Vec<Object> {
    let u32v = |v: u32| Value::Number(u64::from(v));
    let text = |s: &'static str| (DataType::String(s.len() as u16), Value::Text(s));
    let (t, v) = text(DEVICE_NAME);
    let mut od = vec![
        var(0x1000, "Device type", DataType::U32, u32v(DEVICE_TYPE)),
        var(0x1008, "Device name", t, v),
    ];
    let (t, v) = text(HARDWARE_VERSION);
    od.push(var(0x1009, "Hardware version", t, v));
    let (t, v) = text(SOFTWARE_VERSION);
    od.push(var(0x100A, "Software version", t, v));
    od.push(compound(
        0x1018,
        "Identity object".into(),
        ObjectCode::Record,
        vec![
            entry(1, "Vendor ID", DataType::U32, u32v(VENDOR_ID)),
            entry(2, "Product code", DataType::U32, u32v(PRODUCT_CODE)),
            entry(3, "Revision number", DataType::U32, u32v(REVISION)),
            entry(4, "Serial number", DataType::U32, u32v(SERIAL_NUMBER)),
        ],
    ));
    for p in rx_pdos(inverters).into_iter().chain(tx_pdos(inverters)) {
        let entries = (1..)
            .zip(&p.entries)
            .map(|(s, e)| {
                entry(
                    s,
                    format!("SubIndex {s:03}"),
                    DataType::U32,
                    u32v(e.mapping()),
                )
            })
            .collect();
        od.push(compound(p.index, p.name, ObjectCode::Record, entries));
    }
    let sms = sync_managers(inverters);
    od.push(compound(
        0x1C00,
        "Sync manager type".into(),
        ObjectCode::Array,
        (1..)
            .zip(sms)
            .map(|(s, sm)| {
                let name = format!("SubIndex {s:03}");
                entry(s, name, DataType::U8, u32v(u32::from(sm.role.com_type())))
            })
            .collect(),
    ));
    for (index, name) in [
        (0x1C10, "Sync manager 0 PDO assignment"),
        (0x1C11, "Sync manager 1 PDO assignment"),
    ] {
        od.push(compound(index, name.into(), ObjectCode::Array, Vec::new()));
    }
    for (index, name, pdos) in [
        (0x1C12, "Sync manager 2 PDO assignment", rx_pdos(inverters)),
        (0x1C13, "Sync manager 3 PDO assignment", tx_pdos(inverters)),
    ] {
        let entries = (1..)
            .zip(&pdos)
            .map(|(s, p)| {
                let name = format!("SubIndex {s:03}");
                entry(s, name, DataType::U16, u32v(u32::from(p.index)))
            })
            .collect();
        od.push(compound(index, name.into(), ObjectCode::Array, entries));
    }
    for fi in inverters_up_to(inverters) {
        for (index, names, input) in [
            (inputs_index(fi), IN_NAMES, true),
            (outputs_index(fi), OUT_NAMES, false),
        ] {
            let n = fi.get();
            let entries = (0u8..)
                .zip(names)
                .map(|(w, name)| {
                    let value = if input {
                        Value::Input {
                            inverter: n,
                            word: w,
                        }
                    } else {
                        Value::Output {
                            inverter: n,
                            word: w,
                        }
                    };
                    Entry {
                        pdo: if input {
                            PdoMapping::Tx
                        } else {
                            PdoMapping::Rx
                        },
                        ..entry(w + 1, name, word_type(w), value)
                    }
                })
                .collect();
            let name = format!("{} FI {n}", if input { "Inputs" } else { "Outputs" });
            od.push(compound(index, name, ObjectCode::Record, entries));
        }
    }
    od.sort_by_key(|o| o.index);
    od
}
