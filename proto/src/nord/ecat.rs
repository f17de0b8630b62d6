//! The SK 550P's integrated EtherCAT interface as the manual defines it (BU 0620 §2.2, §3.6,
//! §4.2.1): identity, SyncManager and FMMU layout, process data objects and their mapping, the
//! CoE object dictionary of §2.2.7.1 and the NORD parameter objects of §2.2.7.
//!
//! Pure data, no wire format: the simulator's slave (`sim::ecat`), its SII EEPROM image and the
//! ESI XML writer are all built from this one definition, so they cannot disagree.
//!
//! What the manual does not give is an assumption, said so where it is made:
//! - product code [`PRODUCT_CODE`] and revision [`REVISION`] (§3.6.1 names the objects, not
//!   their values), device type [`DEVICE_TYPE`], the version strings;
//! - the SyncManager start addresses and mailbox sizes (the ESI file of §3.4 carries them, the
//!   manual does not);
//! - the objects the PDOs map: the control word, setpoints, status word and actual values of
//!   FI n are entries 1..6 of 7000h + 10h·(n−1) (outputs) and 6000h + 10h·(n−1) (inputs), the
//!   ETG.5001 modular-device convention; §2.2.7.1 lists the mapping objects only.
//!
//! Errata of the manual kept here (the code follows the standard):
//! - §2.2.3 figure 3 prints EtherType 0x88AB; EtherCAT is 0x88A4 (IEEE registry, ETG.1000.4).
//! - §2.2.6 says "up to 3 setpoints" and "up to 3 actual values"; §2.2.6.1 (the telegram table)
//!   and P873/P874 (§4.3) carry 5 each in 12 bytes per inverter, which this definition follows.
//! - §2.2.7.1 prints sub-index "0-4" for the mapping objects 1600h/1A00h, which hold 6 entries
//!   (control/status word + 5 values, 12 bytes); and sub-index "5" for 1C12h/1C13h, which hold
//!   one assigned PDO per inverter (sub-index 0 = the count, 1..8).
//! - §2.2.7.2 prints 06020002h for "write access to read-only object" and 06060047h for the
//!   internal incompatibility; CiA 301 defines 06010002h and 06040047h (see
//!   [`super::errors::ETHERCAT_ABORTS`]).

use super::params::{ParamDef, Width};
use super::types::{ArrayElement, Inverter, ParamSet};

/// Vendor ID of Getriebebau NORD GmbH & Co. KG (BU 0620 §2.2.7.1, object 1018h:01; §3.6.1).
pub const VENDOR_ID: u32 = 0x0000_0538;
/// Product code (1018h:02). The manual gives no value; 0550h ("SK 550P") is an assumption.
pub const PRODUCT_CODE: u32 = 0x0000_0550;
/// Revision number (1018h:03, "software version and revision number (2 × 16 bit)"): major 1,
/// minor 0. An assumption: the manual gives no value.
pub const REVISION: u32 = 0x0001_0000;
/// Serial number (1018h:04): "Not supported" (§2.2.7.1), so 0.
pub const SERIAL_NUMBER: u32 = 0;
/// Device type (1000h). NORD's control and status words follow no CiA device profile, so
/// "no standard device profile" (CiA 301 §7.5.2.1: 0). An assumption: the manual gives none.
pub const DEVICE_TYPE: u32 = 0;
/// Device name (1008h) and the ESI/SII device name.
pub const DEVICE_NAME: &str = "NORDAC PRO SK 550P";
/// Hardware version (1009h). An assumption.
pub const HARDWARE_VERSION: &str = "1.0";
/// Software version (100Ah). An assumption, matching [`REVISION`].
pub const SOFTWARE_VERSION: &str = "V1.0 R0";
/// The device group of the ESI file and the SII general category.
pub const GROUP: &str = "NORD Frequency Inverter";
/// The order number ("type") of the ESI file.
pub const ORDER_NUMBER: &str = "SK 550P";
/// Vendor name of the ESI file.
pub const VENDOR_NAME: &str = "Getriebebau NORD GmbH & Co. KG";

/// Inverters the interface reaches: FI 1 plus up to 7 on the system bus (§2.2.7).
pub const MAX_INVERTERS: u8 = 8;
/// Process data words per inverter and direction (§2.2.6.1): control word + setpoints 1..5,
/// status word + actual values 1..5.
pub const WORDS_PER_INVERTER: u8 = 6;
/// Process data bytes per inverter and direction (§2.2.6.1: "12 bytes").
pub const BYTES_PER_INVERTER: u16 = 12;

/// "Second Address" for Hot Connect (§4.2.1 P850 under EtherCAT: 0…4096, factory 0, adopted at
/// POWER ON; §3.6.2). The parameter catalogue's P850 is EtherNet/IP's "IP address" (§4.2.2):
/// the SK 550P's P850 means one or the other with the protocol of P899.
pub const SECOND_ADDRESS_MAX: u16 = 4096;
/// The ESC register the master reads the Hot Connect ID from (§3.6.2: "ADO 0x134", the AL
/// status code register, ETG.1020 explicit device identification).
pub const HOT_CONNECT_ADO: u16 = 0x0134;

/// What a SyncManager is used for (ETG.1000.4 §6.7, ETG.2010 SII category SyncM "type").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
pub enum SmRole {
    /// Mailbox written by the master (receive mailbox of the slave).
    MailboxOut,
    /// Mailbox read by the master (send mailbox of the slave).
    MailboxIn,
    /// Process data outputs (written by the master, 3-buffer mode).
    Outputs,
    /// Process data inputs (read by the master, 3-buffer mode).
    Inputs,
}

impl SmRole {
    /// The communication type of object 1C00h and of the SII SyncM category: 1 mailbox out,
    /// 2 mailbox in, 3 outputs, 4 inputs (ETG.1000.6 §5.6.7.4.9, ETG.2010 table 7).
    pub fn com_type(self) -> u8 {
        match self {
            SmRole::MailboxOut => 1,
            SmRole::MailboxIn => 2,
            SmRole::Outputs => 3,
            SmRole::Inputs => 4,
        }
    }
}

/// One SyncManager's configuration as the master must write it (ESC registers 0800h + 8·n).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct SyncManager {
    /// SyncManager number 0..3.
    pub index: u8,
    /// Its use.
    pub role: SmRole,
    /// Physical start address in the ESC's process RAM.
    pub start: u16,
    /// Length in bytes (0 for process data without inverters).
    pub len: u16,
    /// Control byte (register 0804h + 8·n): bits 0–1 mode (10b mailbox, 00b 3-buffer), bits
    /// 2–3 direction (01b written by the master), bit 5 AL event, bit 6 watchdog trigger.
    pub control: u8,
    /// Enabled by default (ESI `Enable`).
    pub enable: bool,
}

/// Receive mailbox (SM0): start 1000h, 128 bytes, control 26h (mailbox, written by the master,
/// AL event). Address and size are assumptions (the manual gives none).
pub const SM_MAILBOX_OUT: SyncManager = SyncManager {
    index: 0,
    role: SmRole::MailboxOut,
    start: 0x1000,
    len: 128,
    control: 0x26,
    enable: true,
};
/// Send mailbox (SM1): start 1080h, 128 bytes, control 22h (mailbox, read by the master, AL
/// event).
pub const SM_MAILBOX_IN: SyncManager = SyncManager {
    index: 1,
    role: SmRole::MailboxIn,
    start: 0x1080,
    len: 128,
    control: 0x22,
    enable: true,
};
/// Start of the outputs (SM2); 3-buffer mode takes 3 × the length, at most 3 × 96 bytes.
pub const OUTPUTS_START: u16 = 0x1100;
/// Control byte of SM2: 3-buffer, written by the master, AL event, watchdog trigger (64h).
pub const OUTPUTS_CONTROL: u8 = 0x64;
/// Start of the inputs (SM3), after the outputs' three buffers.
pub const INPUTS_START: u16 = 0x1400;
/// Control byte of SM3: 3-buffer, read by the master, AL event (20h).
pub const INPUTS_CONTROL: u8 = 0x20;
/// The bootstrap mailbox (SII words 14h–17h): the same area as the standard mailbox.
pub const BOOTSTRAP_MAILBOX: (SyncManager, SyncManager) = (SM_MAILBOX_OUT, SM_MAILBOX_IN);

/// The four SyncManagers of a device with `inverters` inverters (1..=8, clamped).
pub fn sync_managers(inverters: u8) -> [SyncManager; 4] {
    let len = process_data_len(inverters);
    [
        SM_MAILBOX_OUT,
        SM_MAILBOX_IN,
        SyncManager {
            index: 2,
            role: SmRole::Outputs,
            start: OUTPUTS_START,
            len,
            control: OUTPUTS_CONTROL,
            enable: len > 0,
        },
        SyncManager {
            index: 3,
            role: SmRole::Inputs,
            start: INPUTS_START,
            len,
            control: INPUTS_CONTROL,
            enable: len > 0,
        },
    ]
}

/// Bytes of process data each way for `inverters` inverters (12 each, §2.2.6.1).
pub fn process_data_len(inverters: u8) -> u16 {
    u16::from(inverters.clamp(1, MAX_INVERTERS)) * BYTES_PER_INVERTER
}

/// What an FMMU is used for (ETG.2010 SII category FMMU: 1 outputs, 2 inputs, 3 SyncM status).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum FmmuUse {
    /// Maps the outputs (SM2).
    Outputs,
    /// Maps the inputs (SM3).
    Inputs,
    /// Maps the send mailbox's status (SM1 status bit "mailbox full") for logical polling.
    MailboxState,
}

impl FmmuUse {
    /// The SII code.
    pub fn code(self) -> u8 {
        match self {
            FmmuUse::Outputs => 1,
            FmmuUse::Inputs => 2,
            FmmuUse::MailboxState => 3,
        }
    }
}

/// The FMMUs the interface offers and their use (ESI `Fmmu`, SII FMMU category).
pub const FMMUS: [FmmuUse; 3] = [FmmuUse::Outputs, FmmuUse::Inputs, FmmuUse::MailboxState];

/// The mailbox protocols supported: CoE only (§2.2.7: "a single SDO channel"). SII word 1Ch
/// bit 2 (ETG.2010 table 2).
pub const MAILBOX_PROTOCOLS: u16 = 0x0004;

/// The CoE services offered (ESI `CoE` attributes, SII general category "CoE details").
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct CoeDetails {
    /// SDO upload/download.
    pub sdo: bool,
    /// SDO information service.
    pub sdo_info: bool,
    /// PDO assignment writable (1C12h/1C13h).
    pub pdo_assign: bool,
    /// PDO mapping writable (1600h/1A00h).
    pub pdo_config: bool,
    /// Complete access to an object's sub-indices at once.
    pub complete_access: bool,
}

/// The SK 550P's CoE: SDO with complete access; the mapping and assignment are fixed
/// ("The structure of EtherCAT process data is fixed", §2.2.6; every PDO object is RO,
/// §2.2.7.1). No SDO information service (the manual names none).
pub const COE: CoeDetails = CoeDetails {
    sdo: true,
    sdo_info: false,
    pdo_assign: false,
    pdo_config: false,
    complete_access: true,
};

/// SII EEPROM size in bytes (2 KiB = 16 Kbit, as ESCs commonly carry). An assumption.
pub const EEPROM_BYTES: u32 = 2048;
/// PDI control (SII word 0, ESC register 0140h): 80h, an on-chip bus to the application
/// controller (the netX of P872 bit 4). An assumption.
pub const PDI_CONTROL: u16 = 0x0080;
/// PDI configuration (SII word 1, register 0150h). An assumption.
pub const PDI_CONFIG: u16 = 0x0000;

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
            DataType::String(_) => 0x0009,
        }
    }

    /// Size in bits.
    pub fn bits(self) -> u16 {
        match self {
            DataType::U8 => 8,
            DataType::U16 | DataType::I16 => 16,
            DataType::U32 | DataType::I32 => 32,
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
    Number(u32),
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

fn entry(sub: u8, name: impl Into<String>, data_type: DataType, value: Value) -> Entry {
    Entry {
        sub,
        name: name.into(),
        data_type,
        access: EntryAccess::Ro,
        pdo: PdoMapping::None,
        value,
    }
}

fn var(index: u16, name: &str, data_type: DataType, value: Value) -> Object {
    Object {
        index,
        name: name.into(),
        code: ObjectCode::Var,
        entries: vec![entry(0, name, data_type, value)],
    }
}

/// An ARRAY or RECORD whose sub-index 0 counts `entries`.
fn compound(index: u16, name: String, code: ObjectCode, entries: Vec<Entry>) -> Object {
    let count = entries.iter().map(|e| e.sub).max().unwrap_or(0);
    let mut all = vec![entry(
        0,
        "Largest sub-index",
        DataType::U8,
        Value::Number(u32::from(count)),
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
    let u32v = |v: u32| Value::Number(v);
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

/// First index of the NORD parameter objects (§2.2.7 "Start offset").
pub const PARAMETER_BASE: u16 = 0x2000;
/// Index step from one inverter to the next (§2.2.7 "Device offset").
pub const PARAMETER_DEVICE_OFFSET: u16 = 0x800;

/// The inverter and raw parameter number (0..7FFh; the manual's numbers are 0..999) an index
/// in 2000h..5FFFh addresses (§2.2.7 formula inverted; `proto::nord::addr::coe` forms it).
pub fn parameter_object(index: u16) -> Option<(Inverter, u16)> {
    let offset = index.checked_sub(PARAMETER_BASE)?;
    let fi = offset / PARAMETER_DEVICE_OFFSET + 1;
    let inverter = Inverter::new(i64::from(fi)).ok()?;
    Some((inverter, offset % PARAMETER_DEVICE_OFFSET))
}

/// What a sub-index of a parameter object addresses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParamSub {
    /// Sub-index 0 of a parameter with a sub-index: "the maximum size of the array" (§2.2.7).
    Count(u8),
    /// A value: its set and element (per `proto::nord::addr::sdo_subindex`).
    Value(Option<ParamSet>, Option<ArrayElement>),
}

/// The number of sub-indices of a parameter (sets × elements), `None` for a plain parameter
/// (whose value is at sub-index 0).
pub fn parameter_count(set_dependent: bool, array: Option<u8>) -> Option<u8> {
    match (set_dependent, array) {
        (false, None) => None,
        (true, None) => Some(4),
        (false, Some(n)) => Some(n),
        (true, Some(n)) => Some(n.saturating_mul(4)),
    }
}

/// Decodes a parameter object's sub-index (the inverse of `addr::sdo_subindex`); `None` when
/// the sub-index does not exist for that parameter (abort 06090011h).
pub fn parameter_subindex(sub: u8, set_dependent: bool, array: Option<u8>) -> Option<ParamSub> {
    let Some(count) = parameter_count(set_dependent, array) else {
        return (sub == 0).then_some(ParamSub::Value(None, None));
    };
    if sub == 0 {
        return Some(ParamSub::Count(count));
    }
    if sub > count {
        return None;
    }
    let n = i64::from(sub);
    Some(match (set_dependent, array) {
        (true, Some(_)) => ParamSub::Value(
            ParamSet::new((n - 1) % 4 + 1).ok(),
            ArrayElement::new((n - 1) / 4 + 1).ok(),
        ),
        (true, None) => ParamSub::Value(ParamSet::new(n).ok(), None),
        _ => ParamSub::Value(None, ArrayElement::new(n).ok()),
    })
}

/// The CoE type of a parameter's value: INTEGER16 for words (signed, so that a value below the
/// range is "too small" rather than a large unsigned one), UNSIGNED16 for words whose range
/// exceeds 7FFFh (bit fields such as P872), INTEGER32 for positions (§4: "position values are
/// communicated as double words").
pub fn parameter_data_type(def: &ParamDef) -> DataType {
    match def.width {
        Width::Dword => DataType::I32,
        Width::Word if def.max > i32::from(i16::MAX) => DataType::U16,
        Width::Word => DataType::I16,
    }
}

#[cfg(test)]
mod tests {
    use super::super::addr::sdo_subindex;
    use super::*;

    fn fi(n: i64) -> Inverter {
        Inverter::new(n).unwrap()
    }

    #[test]
    fn identity_of_1018h() {
        let od = object_dictionary(1);
        let id = od.iter().find(|o| o.index == 0x1018).unwrap();
        assert_eq!(id.entry(0).unwrap().value, Value::Number(4));
        assert_eq!(id.entry(1).unwrap().value, Value::Number(0x538));
        assert!(id.entry(5).is_none());
    }

    #[test]
    fn pdo_mapping_of_fi_3() {
        // 12 bytes per FI (§2.2.6.1): control word + setpoints 1..5 from 7020h:01..06.
        let rx = &rx_pdos(3)[2];
        assert_eq!((rx.index, rx.sm), (0x1602, 2));
        assert_eq!(rx.entries[0].mapping(), 0x7020_0110);
        assert_eq!(rx.entries[5].mapping(), 0x7020_0610);
        let bits: u16 = rx.entries.iter().map(|e| u16::from(e.bits)).sum();
        assert_eq!(bits / 8, BYTES_PER_INVERTER);
        assert_eq!(tx_pdos(8)[7].entries[0].mapping(), 0x6070_0110);
    }

    #[test]
    fn assignment_and_sm_layout() {
        let od = object_dictionary(4);
        let a = od.iter().find(|o| o.index == 0x1C12).unwrap();
        assert_eq!(a.entry(0).unwrap().value, Value::Number(4));
        assert_eq!(a.entry(4).unwrap().value, Value::Number(0x1603));
        let t = od.iter().find(|o| o.index == 0x1C00).unwrap();
        let types: Vec<_> = t.entries.iter().map(|e| e.value.clone()).collect();
        assert_eq!(types, [4, 1, 2, 3, 4].map(Value::Number));
        let sms = sync_managers(8);
        assert_eq!(sms[2].len, 96);
        // Three buffers of SM2 end before SM3 starts.
        assert!(OUTPUTS_START + 3 * sms[2].len <= INPUTS_START);
        const { assert!(SM_MAILBOX_IN.start + SM_MAILBOX_IN.len <= OUTPUTS_START) };
        let mut idx: Vec<u16> = od.iter().map(|o| o.index).collect();
        idx.dedup();
        assert_eq!(idx.len(), od.len(), "indices unique");
    }

    #[test]
    fn parameter_objects_invert_the_formula() {
        // §2.2.7: FI 3, P102 → 3066h.
        assert_eq!(parameter_object(0x3066), Some((fi(3), 102)));
        assert_eq!(parameter_object(0x5FFF), Some((fi(8), 0x7FF)));
        assert_eq!(parameter_object(0x1FFF), None);
        assert_eq!(parameter_object(0x6000), None);
    }

    #[test]
    fn sub_indices_invert_sdo_subindex() {
        for (sets, array) in [
            (false, None),
            (true, None),
            (false, Some(5)),
            (true, Some(3)),
        ] {
            let count = parameter_count(sets, array).unwrap_or(0);
            for sub in 1..=count {
                let Some(ParamSub::Value(s, e)) = parameter_subindex(sub, sets, array) else {
                    panic!("{sub}");
                };
                assert_eq!(sdo_subindex(s, e), sub);
            }
            assert_eq!(parameter_subindex(count + 1, sets, array), None);
        }
        assert_eq!(parameter_subindex(0, true, None), Some(ParamSub::Count(4)));
        assert_eq!(
            parameter_subindex(0, false, None),
            Some(ParamSub::Value(None, None))
        );
    }
}
