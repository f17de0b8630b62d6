//! `harness describe gsdml`: the PROFINET General Station Description (GSDML, schema V2.35) of
//! the SK 550P's integrated interface (BU 0620 §2.5) and the SK TU3-PNT (BU 0590), written
//! from `proto::nord::pnio` — the definition the simulated IO device (`sim::pnio`) takes its
//! identity, slots, modules, records and alarms from — so an engineering tool set up from this
//! file plans the device the simulator is (BU 0620 §2.5.5: "The slots and sub-slots … are
//! read by the IO controller from the device description file"; §3.4; BU 0590 §3.3).
//!
//! The file holds
//! - `DeviceIdentity`: [`def::VENDOR_ID`] and [`def::device_id`] (placeholders, see
//!   `proto::nord::pnio`), the vendor name;
//! - one `DeviceAccessPointItem` in slot 0 (`PhysicalSlots` 0…[`def::slot_count`] − 1): the
//!   DAP submodule, the interface (8000h) and both ports (8001h, 8002h, 100 Mbit/s full duplex,
//!   BU 0620 §2.5.1, BU 0590 §1.2); `UseableModules` with the slots each module fits
//!   ([`def::fits`]): on the SK 550P the PPO modules in the slots of FI 1…`inverters` (3…2 +
//!   `inverters`), on the SK TU3-PNT the DIG-IO module in slot 2 and the PPO modules in slot 3;
//! - `ModuleList`: every module of [`def::modules`] with its ident number, one submodule in
//!   subslot 1 whose `IOData` is the PPO as BU 0620 §2.5.5.1 / BU 0590 §4.1.1 lay it out (the
//!   four PKW words where the type has them, then control/status word and setpoints/actual
//!   values, each Unsigned16) or the DIG-IO words (BU 0590 P176/P177 [-01]);
//! - the parameter-channel records as `ParameterRecordDataItem`s where the device takes them
//!   ([`def::record_target`]): SK 550P records 100 and 101…100 + `inverters` on the FI
//!   modules; SK TU3-PNT record 47 on the DAP, 100 on the DIG-IO module, 101 on the FI module;
//! - `ChannelDiagList`: the alarm numbers of BU 0620 §5.4.2 / BU 0590 §6.1 — every inverter
//!   error of the allocation table (P700 + 100h, [`def::fi_error_alarm`]), the lost inverter
//!   (1256, SK 550P) and the SK TU3-PNT's module error (P170 1020 + 100h);
//! - `ExternalTextList` with every text the file refers to.
//!
//! Assumptions (neither manual gives them), said once:
//! - A GSDML `ParameterRecordDataItem` is written by the controller at start-up. The records
//!   of the parameter channel are request/response records the application uses later, so
//!   each is declared with a constant of zeros: a PKW order with AK 0 ("no order"), which the
//!   device answers with "no response" and which changes nothing.
//! - Send clock 1 ms (`SendClock` 32 × 31.25 µs, the simulator's input CR); RT class 1; the
//!   conformance class B both manuals state (BU 0620 §2.5.1, BU 0590 §1.2: "B, C"; class C's
//!   IRT is not described); `SupportedProtocols` SNMP and LLDP, which class B requires.
//! - `MaxInputLength`/`MaxOutputLength`: the RT frame's 1440 bytes of data
//!   ([`proto::pnio::rt::MAX_C_SDU`]), the most the simulator accepts in one IO CR.
//! - The SK TU3-PNT's inverter (SK 5xxE, BU 0500, not among the manuals) is given the error
//!   texts of BU 0620 §5.4.1.2, the table the harness has.
//! - The file name: the SK TU3-PNT's manual names a V2.2 file (BU 0590 §3.3,
//!   [`def::gsdml_file_name`]); this file is V2.35 and says so in a comment.

use std::collections::{BTreeMap, HashSet};
use std::io::Cursor;

use crate::dictionary::DescribeError;
use proto::nord::errors::{COMM_ERRORS, POWERLINK_ERRORS};
use proto::nord::pnio::{self as def, Module, ModuleKind, RecordTarget, SlotRole};
use proto::nord::{Inverter, Product};
use quick_xml::events::{BytesDecl, BytesText, Event};
use quick_xml::Writer;

type W = Writer<Cursor<Vec<u8>>>;

/// GSDML schema version the file follows.
const SCHEMA: &str = "V2.35";
/// The namespace of every GSDML.
const NAMESPACE: &str = "http://www.profibus.com/GSDML/2003/11/DeviceProfile";
/// Send clock factor (× 31.25 µs): 1 ms.
const SEND_CLOCK: u16 = 32;
/// MAU type 16: 100BASE-TX full duplex (IEC 61158-6-10).
const MAU_100BASETX_FD: u8 = 16;

/// The GSDML of `product` with `inverters` inverters behind its interface.
pub(crate) fn gsdml(product: Product, inverters: u8) -> Result<String, DescribeError> {
    let (Some(device_id), Some(station)) = (def::device_id(product), def::station_type(product))
    else {
        return Err(DescribeError::NoInterface {
            product,
            bus: "PROFINET IO",
            format: "GSDML",
        });
    };
    DescribeError::check_inverters(product, inverters)?;
    let model = Model::new(product, inverters, device_id, station)?;
    model.write().map_err(|e| DescribeError::Write {
        format: "GSDML",
        detail: e.to_string(),
    })
}

/// The texts the file refers to, in first-use order (`ExternalTextList`).
#[derive(Default)]
struct Texts {
    list: Vec<(String, String)>,
    seen: HashSet<String>,
}

impl Texts {
    /// Registers `value` under `id` (the first value wins) and gives the id back.
    fn id(&mut self, id: impl Into<String>, value: impl Into<String>) -> String {
        let id = id.into();
        if self.seen.insert(id.clone()) {
            self.list.push((id.clone(), value.into()));
        }
        id
    }
}

/// A `ParameterRecordDataItem`.
#[derive(Debug, Clone, PartialEq)]
struct Record {
    index: u16,
    len: usize,
    text: String,
}

/// A `ModuleItem` with its one submodule.
struct ModuleDesc {
    module: Module,
    id: String,
    name: String,
    info: String,
    /// `DataItem` text ids, from the controller.
    outputs: Vec<String>,
    /// `DataItem` text ids, to the controller.
    inputs: Vec<String>,
    records: Vec<Record>,
    /// Slots it may be plugged into (empty: listed, not usable with these inverters).
    allowed: Vec<u16>,
}

/// A diagnosis item: alarm number and its text id.
type Diag = (u16, String);

/// Everything the file says, gathered before it is written.
struct Model {
    product: Product,
    device_id: u16,
    station: &'static str,
    dap_records: Vec<Record>,
    modules: Vec<ModuleDesc>,
    diags: Vec<Diag>,
    texts: Texts,
}

impl Model {
    fn new(
        product: Product,
        inverters: u8,
        device_id: u16,
        station: &'static str,
    ) -> Result<Model, DescribeError> {
        let mut texts = Texts::default();
        texts.id(
            "IDT_INFO_Device",
            format!(
                "{station}: PROFINET IO device of NORD DRIVESYSTEMS ({})",
                match product {
                    Product::Sk550p => "integrated interface, FI 1 … FI 8 on the system bus",
                    _ => "bus module for one SK 5xxE frequency inverter",
                }
            ),
        );
        texts.id("IDT_NAME_DAP", station);
        texts.id("IDT_INFO_DAP", format!("{station}, PROFINET IO, 2 ports"));
        texts.id("IDT_NAME_IF", "X1");
        for (n, _) in def::PORT_SUBSLOTS.iter().enumerate() {
            texts.id(format!("IDT_NAME_P{}", n + 1), format!("X1 P{}", n + 1));
        }
        let dap_records = records(product, SlotRole::Dap, inverters, &mut texts)?;
        let mut modules = Vec::new();
        for m in def::modules(product) {
            modules.push(module_desc(product, inverters, m, &mut texts)?);
        }
        let diags = diagnosis(product, &mut texts);
        Ok(Model {
            product,
            device_id,
            station,
            dap_records,
            modules,
            diags,
            texts,
        })
    }
}

/// `0x00000006`: a GSDML ident number.
fn ident(v: u32) -> String {
    format!("0x{v:08X}")
}

/// Runs of consecutive numbers as GSDML writes a value list: `3..10`, `2 5..7`.
fn runs(values: impl IntoIterator<Item = u16>) -> String {
    let mut out: Vec<(u16, u16)> = Vec::new();
    for v in values {
        match out.last_mut() {
            Some((_, hi)) if hi.checked_add(1) == Some(v) => *hi = v,
            _ => out.push((v, v)),
        }
    }
    out.iter()
        .map(|(lo, hi)| {
            if lo == hi {
                lo.to_string()
            } else {
                format!("{lo}..{hi}")
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// Whether the slot is in use with `inverters` inverters (an FI slot beyond them is not).
fn slot_in_use(product: Product, slot: u16, inverters: u8) -> Option<SlotRole> {
    match def::slot_role(product, slot)? {
        SlotRole::Inverter(fi) if fi.get() > inverters => None,
        role => Some(role),
    }
}

fn module_desc(
    product: Product,
    inverters: u8,
    m: Module,
    texts: &mut Texts,
) -> Result<ModuleDesc, DescribeError> {
    let name = m.name();
    let key = name.replace('-', "_");
    let info = match m.kind {
        ModuleKind::Ppo(t) if t.has_pkw() => format!(
            "{name}: parameter channel (PKW) and {} process data words to and from the frequency inverter, {} bytes each way",
            t.pzd_words(),
            m.output_len
        ),
        ModuleKind::Ppo(t) => format!(
            "{name}: {} process data words to and from the frequency inverter, {} bytes each way",
            t.pzd_words(),
            m.output_len
        ),
        ModuleKind::DigIo => format!(
            "{name}: process data for the SK TU3-PNT itself, {} bytes each way",
            m.output_len
        ),
    };
    let outputs = io_items(&m, true, texts);
    let inputs = io_items(&m, false, texts);
    for (items, len, way) in [
        (&outputs, m.output_len, "output"),
        (&inputs, m.input_len, "input"),
    ] {
        if 2 * items.len() != len {
            return Err(DescribeError::Inconsistent(format!(
                "{name}: {} data words do not make the module's {len} {way} bytes",
                items.len()
            )));
        }
    }
    let allowed: Vec<u16> = (0..def::slot_count(product))
        .filter(|&s| slot_in_use(product, s, inverters).is_some())
        .filter(|&s| def::fits(product, s, m.kind))
        .collect();
    // The records of the first slot the module fits (every slot of a kind takes the same).
    let fitting = (0..def::slot_count(product))
        .find(|&s| def::fits(product, s, m.kind))
        .and_then(|s| def::slot_role(product, s));
    let records = match fitting {
        Some(role) => records(product, role, inverters, texts)?,
        None => Vec::new(),
    };
    Ok(ModuleDesc {
        id: format!("IDM_{key}"),
        name: texts.id(format!("IDT_NAME_{key}"), name.clone()),
        info: texts.id(format!("IDT_INFO_{key}"), info),
        module: m,
        outputs,
        inputs,
        records,
        allowed,
    })
}

/// The words of a module in one direction (BU 0620 §2.5.5.1, BU 0590 §4.1.1 and P176/P177).
fn io_items(m: &Module, output: bool, texts: &mut Texts) -> Vec<String> {
    let mut items = Vec::new();
    match m.kind {
        ModuleKind::Ppo(t) => {
            if t.has_pkw() {
                items.push(texts.id("IDT_PKE", "PKE: order label AK and parameter number PNU"));
                items.push(texts.id("IDT_IND", "IND: parameter index"));
                items.push(texts.id("IDT_PWE_HI", "PWE HI: parameter value, high word"));
                items.push(texts.id("IDT_PWE_LO", "PWE LO: parameter value, low word"));
            }
            items.push(if output {
                texts.id("IDT_CTW", "Control word")
            } else {
                texts.id("IDT_STW", "Status word")
            });
            for n in 1..t.pzd_words() {
                items.push(if output {
                    texts.id(format!("IDT_SW{n}"), format!("Setpoint {n}"))
                } else {
                    texts.id(format!("IDT_IW{n}"), format!("Actual value {n}"))
                });
            }
        }
        ModuleKind::DigIo => {
            let len = if output { m.output_len } else { m.input_len };
            for n in 1..=len / 2 {
                let suffix = if len > 2 {
                    format!(" {n}")
                } else {
                    String::new()
                };
                items.push(if output {
                    texts.id(
                        format!("IDT_TU_OUT{n}"),
                        format!("Bus module outputs{suffix}"),
                    )
                } else {
                    texts.id(
                        format!("IDT_TU_IN{n}"),
                        format!("Bus module inputs{suffix}"),
                    )
                });
            }
        }
    }
    items
}

/// `P850…P899`, `P000…P849 P900…P999`: the parameters a record's target holds.
fn parameter_ranges(product: Product, target: RecordTarget) -> String {
    let numbers = (0..=999).filter(|&n| def::holds_parameter(product, target, n));
    runs(numbers)
        .split(' ')
        .map(|r| match r.split_once("..") {
            Some((lo, hi)) => format!("P{lo:0>3}…P{hi:0>3}"),
            None => format!("P{r:0>3}"),
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The parameter-channel records a submodule in a slot of `role` takes (BU 0620 §2.5.6.2;
/// BU 0590 §4.2.2), each checked against [`def::record_target`] for such a slot.
fn records(
    product: Product,
    role: SlotRole,
    inverters: u8,
    texts: &mut Texts,
) -> Result<Vec<Record>, DescribeError> {
    let fi = |n: u8| {
        Inverter::new(i64::from(n)).map_err(|e| DescribeError::Inconsistent(format!("FI {n}: {e}")))
    };
    let targets: Vec<RecordTarget> = match (product, role) {
        (Product::Sk550p, SlotRole::Inverter(_)) => {
            let mut t = vec![RecordTarget::Interface];
            for n in 1..=inverters {
                t.push(RecordTarget::Inverter(fi(n)?));
            }
            t
        }
        (Product::Tu3Pnt, SlotRole::Dap) => vec![RecordTarget::ByAxis],
        (Product::Tu3Pnt, SlotRole::BusModule) => vec![RecordTarget::Interface],
        (Product::Tu3Pnt, SlotRole::Inverter(n)) => vec![RecordTarget::Inverter(n)],
        _ => Vec::new(),
    };
    let slot = (0..def::slot_count(product))
        .find(|&s| def::slot_role(product, s) == Some(role))
        .ok_or_else(|| {
            DescribeError::Inconsistent(format!("{} has no slot for {role:?}", product.name()))
        })?;
    let mut out = Vec::new();
    for target in targets {
        let index = def::record_index(target);
        def::record_target(product, slot, def::IO_SUBSLOT, index).map_err(|e| {
            DescribeError::Inconsistent(format!("record {index} in slot {slot}: {e}"))
        })?;
        let (len, what) = match target {
            RecordTarget::ByAxis => (
                def::AXIS_RECORD_LEN,
                "Parameter order by axis (0 = SK TU3-PNT, 1 = frequency inverter)".to_string(),
            ),
            RecordTarget::Interface => (
                def::PKW_RECORD_LEN,
                format!(
                    "Parameter order to the bus interface ({})",
                    parameter_ranges(product, target)
                ),
            ),
            RecordTarget::Inverter(n) => (
                def::PKW_RECORD_LEN,
                format!(
                    "Parameter order to FI {} ({})",
                    n.get(),
                    parameter_ranges(product, target)
                ),
            ),
        };
        def::check_record_len(index, len)
            .map_err(|e| DescribeError::Inconsistent(e.to_string()))?;
        let text = texts.id(
            format!("IDT_RECORD_{index}"),
            format!("Record {index}: {what}"),
        );
        out.push(Record { index, len, text });
    }
    Ok(out)
}

/// `E10.3`: a P700 value (tenths) as the manuals write it.
fn error_name(p700: u16) -> String {
    format!("E{}.{}", p700 / 10, p700 % 10)
}

/// The channel diagnosis items: inverter errors (P700 + 100h) with the texts of BU 0620
/// §5.3 (where one row names the error) or §5.4.1.2, the lost inverter, the module error.
fn diagnosis(product: Product, texts: &mut Texts) -> Vec<Diag> {
    let mut errors: BTreeMap<u16, String> = BTreeMap::new();
    // Rows that print no meaning (7332h, 7334h, 8612h, 8711h) give no diagnosis text.
    for row in POWERLINK_ERRORS.iter().filter(|r| !r.text.is_empty()) {
        for &(lo, hi) in row.p700 {
            for p700 in (lo..=hi).filter(|&v| v > 0) {
                errors.entry(p700).or_insert_with(|| row.text.to_string());
            }
        }
    }
    for (p700, text) in errors.iter_mut() {
        let rows: Vec<_> = COMM_ERRORS.iter().filter(|e| e.p700 == *p700).collect();
        if let [one] = rows.as_slice() {
            *text = one.text.to_string();
        }
    }
    let mut diags: Vec<(u16, String)> = errors
        .into_iter()
        .map(|(p700, text)| {
            let alarm = def::fi_error_alarm(p700);
            let value = format!(
                "{} {text} (inverter error P700 = {p700} + 100h = {alarm})",
                error_name(p700)
            );
            (alarm, value)
        })
        .collect();
    if product == Product::Sk550p {
        let alarm = def::lost_inverter_alarm();
        diags.push((
            alarm,
            format!("Connection to a frequency inverter on the NORD system bus lost (error 1000 + 100h = {alarm})"),
        ));
    }
    if let Some(p170) = def::timeout_module_error(product) {
        if let Some(alarm) = def::module_error_alarm(product, p170) {
            diags.push((
                alarm,
                format!("SK TU3-PNT module error P170 = {p170}: bus time-out via P513 ({p170} + 100h = {alarm})"),
            ));
        }
    }
    diags.sort_by_key(|(a, _)| *a);
    diags.dedup_by_key(|(a, _)| *a);
    diags
        .into_iter()
        .map(|(alarm, value)| (alarm, texts.id(format!("IDT_DIAG_{alarm}"), value)))
        .collect()
}

/// One element with text.
fn text(w: &mut W, name: &str, value: &str) -> std::io::Result<()> {
    w.create_element(name)
        .write_text_content(BytesText::new(value))?;
    Ok(())
}

/// `<Name TextId=…/>` and the like.
fn text_ref(w: &mut W, name: &str, id: &str) -> std::io::Result<()> {
    w.create_element(name)
        .with_attribute(("TextId", id))
        .write_empty()?;
    Ok(())
}

/// `<VendorName Value=…/>` and the like.
fn value(w: &mut W, name: &str, v: &str) -> std::io::Result<()> {
    w.create_element(name)
        .with_attribute(("Value", v))
        .write_empty()?;
    Ok(())
}

fn record_list(w: &mut W, records: &[Record]) -> std::io::Result<()> {
    if records.is_empty() {
        return Ok(());
    }
    w.create_element("RecordDataList")
        .write_inner_content(|w| {
            for r in records {
                let zeros = vec!["0x00"; r.len].join(",");
                w.create_element("ParameterRecordDataItem")
                    .with_attributes([
                        ("Index", r.index.to_string().as_str()),
                        ("Length", r.len.to_string().as_str()),
                    ])
                    .write_inner_content(|w| {
                        text_ref(w, "Name", &r.text)?;
                        w.create_element("Const")
                            .with_attributes([("Data", zeros.as_str()), ("ByteOffset", "0")])
                            .write_empty()?;
                        Ok(())
                    })?;
            }
            Ok(())
        })?;
    Ok(())
}

impl Model {
    fn write(&self) -> std::io::Result<String> {
        let mut w = Writer::new_with_indent(Cursor::new(Vec::new()), b' ', 2);
        w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))?;
        let note = format!(
            " {} PROFINET IO device description (GSDML {SCHEMA}) written by the NORD harness from proto::nord::pnio{} ",
            self.station,
            def::gsdml_file_name(self.product)
                .map(|f| format!("; the manual's own file is {f}"))
                .unwrap_or_default()
        );
        w.write_event(Event::Comment(BytesText::from_escaped(
            note.replace("--", "- -"),
        )))?;
        let location = format!("{NAMESPACE} GSDML-DeviceProfile-{SCHEMA}.xsd");
        w.create_element("ISO15745Profile")
            .with_attributes([
                ("xmlns", NAMESPACE),
                ("xmlns:xsi", "http://www.w3.org/2001/XMLSchema-instance"),
                ("xsi:schemaLocation", location.as_str()),
            ])
            .write_inner_content(|w| {
                self.header(w)?;
                w.create_element("ProfileBody").write_inner_content(|w| {
                    w.create_element("DeviceIdentity")
                        .with_attributes([
                            ("VendorID", format!("0x{:04X}", def::VENDOR_ID).as_str()),
                            ("DeviceID", format!("0x{:04X}", self.device_id).as_str()),
                        ])
                        .write_inner_content(|w| {
                            text_ref(w, "InfoText", "IDT_INFO_Device")?;
                            value(w, "VendorName", proto::nord::ecat::VENDOR_NAME)
                        })?;
                    w.create_element("DeviceFunction")
                        .write_inner_content(|w| {
                            let family = match self.product {
                                Product::Sk550p => "NORDAC PRO",
                                _ => "SK 5xxE",
                            };
                            w.create_element("Family")
                                .with_attributes([
                                    ("MainFamily", "Drives"),
                                    ("ProductFamily", family),
                                ])
                                .write_empty()?;
                            Ok(())
                        })?;
                    w.create_element("ApplicationProcess")
                        .write_inner_content(|w| self.application_process(w))?;
                    Ok(())
                })?;
                Ok(())
            })?;
        let bytes = w.into_inner().into_inner();
        Ok(String::from_utf8_lossy(&bytes).into_owned() + "\n")
    }

    /// The ISO 15745 header every GSDML carries.
    fn header(&self, w: &mut W) -> std::io::Result<()> {
        w.create_element("ProfileHeader").write_inner_content(|w| {
            text(w, "ProfileIdentification", "PROFINET Device Profile")?;
            text(w, "ProfileRevision", "1.00")?;
            text(w, "ProfileName", "Device Profile for PROFINET Devices")?;
            text(
                w,
                "ProfileSource",
                "PROFIBUS Nutzerorganisation e. V. (PNO)",
            )?;
            text(w, "ProfileClassID", "Device")?;
            w.create_element("ISO15745Reference")
                .write_inner_content(|w| {
                    text(w, "ISO15745Part", "4")?;
                    text(w, "ISO15745Edition", "1")?;
                    text(w, "ProfileTechnology", "GSDML")
                })?;
            Ok(())
        })?;
        Ok(())
    }

    fn application_process(&self, w: &mut W) -> std::io::Result<()> {
        w.create_element("DeviceAccessPointList")
            .write_inner_content(|w| self.dap(w))?;
        w.create_element("ModuleList")
            .write_inner_content(|w| self.modules.iter().try_for_each(|m| module_item(w, m)))?;
        w.create_element("ChannelDiagList")
            .write_inner_content(|w| {
                for (alarm, id) in &self.diags {
                    w.create_element("ChannelDiagItem")
                        .with_attribute(("ErrorType", alarm.to_string().as_str()))
                        .write_inner_content(|w| text_ref(w, "Name", id))?;
                }
                Ok(())
            })?;
        w.create_element("ExternalTextList")
            .write_inner_content(|w| {
                w.create_element("PrimaryLanguage")
                    .write_inner_content(|w| {
                        for (id, v) in &self.texts.list {
                            w.create_element("Text")
                                .with_attributes([("TextId", id.as_str()), ("Value", v.as_str())])
                                .write_empty()?;
                        }
                        Ok(())
                    })?;
                Ok(())
            })?;
        Ok(())
    }

    fn dap(&self, w: &mut W) -> std::io::Result<()> {
        let slots = format!("0..{}", def::slot_count(self.product).saturating_sub(1));
        let dns: String = self
            .station
            .to_ascii_lowercase()
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
            .collect();
        let dns = format!("nord-{}", dns.replace("nordac-pro-", ""));
        let send_clock = SEND_CLOCK.to_string();
        let max_len = proto::pnio::rt::MAX_C_SDU.to_string();
        w.create_element("DeviceAccessPointItem")
            .with_attributes([
                ("ID", "IDD_1"),
                ("PNIO_Version", "V2.3"),
                ("PhysicalSlots", slots.as_str()),
                ("ModuleIdentNumber", ident(def::DAP_MODULE_IDENT).as_str()),
                ("MinDeviceInterval", send_clock.as_str()),
                ("DNS_CompatibleName", dns.as_str()),
                ("FixedInSlots", def::DAP_SLOT.to_string().as_str()),
                ("ObjectUUID_LocalIndex", "1"),
                ("DeviceAccessSupported", "true"),
                ("NameOfStationNotTransferable", "false"),
            ])
            .write_inner_content(|w| {
                w.create_element("ModuleInfo").write_inner_content(|w| {
                    text_ref(w, "Name", "IDT_NAME_DAP")?;
                    text_ref(w, "InfoText", "IDT_INFO_DAP")?;
                    value(w, "VendorName", proto::nord::ecat::VENDOR_NAME)
                })?;
                w.create_element("CertificationInfo")
                    .with_attributes([
                        ("ConformanceClass", "B"),
                        ("ApplicationClass", ""),
                        ("NetloadClass", "I"),
                    ])
                    .write_empty()?;
                w.create_element("IOConfigData")
                    .with_attributes([
                        ("MaxInputLength", max_len.as_str()),
                        ("MaxOutputLength", max_len.as_str()),
                    ])
                    .write_empty()?;
                w.create_element("UseableModules")
                    .write_inner_content(|w| {
                        for m in self.modules.iter().filter(|m| !m.allowed.is_empty()) {
                            w.create_element("ModuleItemRef")
                                .with_attributes([
                                    ("ModuleItemTarget", m.id.as_str()),
                                    ("AllowedInSlots", runs(m.allowed.iter().copied()).as_str()),
                                ])
                                .write_empty()?;
                        }
                        Ok(())
                    })?;
                w.create_element("VirtualSubmoduleList")
                    .write_inner_content(|w| {
                        w.create_element("VirtualSubmoduleItem")
                            .with_attributes([
                                ("ID", "IDS_DAP"),
                                (
                                    "SubmoduleIdentNumber",
                                    ident(def::DAP_SUBMODULE_IDENT).as_str(),
                                ),
                                ("FixedInSubslots", def::DAP_SUBSLOT.to_string().as_str()),
                                ("MayIssueProcessAlarm", "false"),
                            ])
                            .write_inner_content(|w| {
                                w.create_element("IOData").write_empty()?;
                                record_list(w, &self.dap_records)?;
                                w.create_element("ModuleInfo").write_inner_content(|w| {
                                    text_ref(w, "Name", "IDT_NAME_DAP")?;
                                    text_ref(w, "InfoText", "IDT_INFO_DAP")
                                })?;
                                Ok(())
                            })?;
                        Ok(())
                    })?;
                w.create_element("SystemDefinedSubmoduleList")
                    .write_inner_content(|w| {
                        w.create_element("InterfaceSubmoduleItem")
                            .with_attributes([
                                ("ID", "IDS_I"),
                                ("SubslotNumber", def::INTERFACE_SUBSLOT.to_string().as_str()),
                                (
                                    "SubmoduleIdentNumber",
                                    ident(def::INTERFACE_SUBMODULE_IDENT).as_str(),
                                ),
                                ("TextId", "IDT_NAME_IF"),
                                ("SupportedRT_Classes", "RT_CLASS_1"),
                                ("SupportedProtocols", "SNMP;LLDP"),
                            ])
                            .write_inner_content(|w| {
                                w.create_element("ApplicationRelations")
                                    .write_inner_content(|w| {
                                        w.create_element("TimingProperties")
                                            .with_attributes([
                                                ("SendClock", send_clock.as_str()),
                                                ("ReductionRatio", "1 2 4 8 16 32 64 128 256 512"),
                                            ])
                                            .write_empty()?;
                                        Ok(())
                                    })?;
                                Ok(())
                            })?;
                        for (n, (subslot, id)) in def::PORT_SUBSLOTS
                            .iter()
                            .zip(def::PORT_SUBMODULE_IDENTS)
                            .enumerate()
                        {
                            w.create_element("PortSubmoduleItem")
                                .with_attributes([
                                    ("ID", format!("IDS_P{}", n + 1).as_str()),
                                    ("SubslotNumber", subslot.to_string().as_str()),
                                    ("SubmoduleIdentNumber", ident(id).as_str()),
                                    ("TextId", format!("IDT_NAME_P{}", n + 1).as_str()),
                                ])
                                .write_inner_content(|w| {
                                    w.create_element("MAUTypeList").write_inner_content(|w| {
                                        w.create_element("MAUTypeItem")
                                            .with_attribute((
                                                "Value",
                                                MAU_100BASETX_FD.to_string().as_str(),
                                            ))
                                            .write_empty()?;
                                        Ok(())
                                    })?;
                                    Ok(())
                                })?;
                        }
                        Ok(())
                    })?;
                Ok(())
            })?;
        Ok(())
    }
}

/// One `ModuleItem` with its submodule in subslot 1.
fn module_item(w: &mut W, m: &ModuleDesc) -> std::io::Result<()> {
    let items = |w: &mut W, ids: &[String]| -> std::io::Result<()> {
        for id in ids {
            w.create_element("DataItem")
                .with_attributes([("DataType", "Unsigned16"), ("TextId", id.as_str())])
                .write_empty()?;
        }
        Ok(())
    };
    w.create_element("ModuleItem")
        .with_attributes([
            ("ID", m.id.as_str()),
            ("ModuleIdentNumber", ident(m.module.ident).as_str()),
        ])
        .write_inner_content(|w| {
            w.create_element("ModuleInfo").write_inner_content(|w| {
                text_ref(w, "Name", &m.name)?;
                text_ref(w, "InfoText", &m.info)
            })?;
            w.create_element("VirtualSubmoduleList")
                .write_inner_content(|w| {
                    w.create_element("VirtualSubmoduleItem")
                        .with_attributes([
                            ("ID", m.id.replacen("IDM_", "IDS_", 1).as_str()),
                            (
                                "SubmoduleIdentNumber",
                                ident(m.module.submodule_ident).as_str(),
                            ),
                            ("FixedInSubslots", def::IO_SUBSLOT.to_string().as_str()),
                            ("MayIssueProcessAlarm", "false"),
                        ])
                        .write_inner_content(|w| {
                            w.create_element("IOData").write_inner_content(|w| {
                                let all = ("Consistency", "All items consistency");
                                if !m.inputs.is_empty() {
                                    w.create_element("Input")
                                        .with_attribute(all)
                                        .write_inner_content(|w| items(w, &m.inputs))?;
                                }
                                if !m.outputs.is_empty() {
                                    w.create_element("Output")
                                        .with_attribute(all)
                                        .write_inner_content(|w| items(w, &m.outputs))?;
                                }
                                Ok(())
                            })?;
                            record_list(w, &m.records)?;
                            w.create_element("ModuleInfo").write_inner_content(|w| {
                                text_ref(w, "Name", &m.name)?;
                                text_ref(w, "InfoText", &m.info)
                            })?;
                            Ok(())
                        })?;
                    Ok(())
                })?;
            Ok(())
        })?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proto::nord::ppo::PpoType;
    use quick_xml::events::Event;
    use quick_xml::Reader;
    use std::collections::HashMap;

    /// One element as the reader saw it: name, attributes, text, and the path of its
    /// ancestors' names.
    #[derive(Debug, Default, Clone)]
    struct El {
        name: String,
        attrs: HashMap<String, String>,
        text: String,
        path: Vec<String>,
        /// Index of the parent element.
        parent: Option<usize>,
    }

    /// Every element in document order (the document must parse: malformed XML, a mismatched
    /// end tag or a bad attribute fails the test).
    fn elements(xml: &str) -> Vec<El> {
        let mut reader = Reader::from_str(xml);
        reader.config_mut().check_end_names = true;
        let (mut out, mut open) = (Vec::<El>::new(), Vec::<usize>::new());
        let mut roots = 0;
        loop {
            let ev = reader.read_event().expect("well-formed XML");
            let (start, empty) = match &ev {
                Event::Start(e) => (Some(e.clone()), false),
                Event::Empty(e) => (Some(e.clone()), true),
                _ => (None, false),
            };
            if let Some(e) = start {
                let name = String::from_utf8(e.name().as_ref().to_vec()).unwrap();
                let attrs = e
                    .attributes()
                    .map(|a| {
                        let a = a.expect("well-formed attribute");
                        let k = String::from_utf8(a.key.as_ref().to_vec()).unwrap();
                        (
                            k,
                            a.normalized_value(quick_xml::XmlVersion::Explicit1_0)
                                .unwrap()
                                .into_owned(),
                        )
                    })
                    .collect::<HashMap<_, _>>();
                if open.is_empty() {
                    roots += 1;
                }
                let path = open.iter().map(|&i| out[i].name.clone()).collect();
                out.push(El {
                    name,
                    attrs,
                    text: String::new(),
                    path,
                    parent: open.last().copied(),
                });
                if !empty {
                    open.push(out.len() - 1);
                }
                continue;
            }
            match ev {
                Event::Text(t) => {
                    if let Some(&i) = open.last() {
                        out[i].text.push_str(&t.decode().unwrap());
                    }
                }
                Event::GeneralRef(r) => {
                    if let Some(&i) = open.last() {
                        let entity = r.decode().unwrap();
                        out[i]
                            .text
                            .push_str(quick_xml::escape::resolve_xml_entity(&entity).unwrap());
                    }
                }
                Event::End(_) => {
                    open.pop();
                }
                Event::Eof => break,
                _ => {}
            }
        }
        assert!(open.is_empty());
        assert_eq!(roots, 1, "one root element");
        out
    }

    fn attr<'a>(e: &'a El, k: &str) -> &'a str {
        e.attrs.get(k).map_or("", String::as_str)
    }

    fn named<'a>(els: &'a [El], name: &str) -> Vec<&'a El> {
        els.iter().filter(|e| e.name == name).collect()
    }

    /// The elements below element `i` (its descendants), in document order.
    fn below(els: &[El], i: usize) -> Vec<&El> {
        let mut inside = vec![i];
        let mut out = Vec::new();
        for (j, e) in els.iter().enumerate().skip(i + 1) {
            match e.parent {
                Some(p) if inside.contains(&p) => {
                    inside.push(j);
                    out.push(e);
                }
                _ => {}
            }
        }
        out
    }

    fn index_of(els: &[El], e: &El) -> usize {
        els.iter().position(|x| std::ptr::eq(x, e)).unwrap()
    }

    /// TextId → Value of the ExternalTextList.
    fn texts(els: &[El]) -> HashMap<String, String> {
        named(els, "Text")
            .into_iter()
            .map(|t| (attr(t, "TextId").to_string(), attr(t, "Value").to_string()))
            .collect()
    }

    /// Module ident → (input bytes, output bytes, DataItem texts in, out) as the file says.
    fn module_io(els: &[El]) -> BTreeMap<u32, (usize, usize, Vec<String>, Vec<String>)> {
        let t = texts(els);
        let mut out = BTreeMap::new();
        for m in named(els, "ModuleItem") {
            let id = u32::from_str_radix(attr(m, "ModuleIdentNumber").trim_start_matches("0x"), 16)
                .unwrap();
            let inner = below(els, index_of(els, m));
            let subs: Vec<_> = inner
                .iter()
                .filter(|e| e.name == "VirtualSubmoduleItem")
                .collect();
            assert_eq!(subs.len(), 1, "one submodule in {id}");
            assert_eq!(attr(subs[0], "SubmoduleIdentNumber"), ident(id));
            let (mut ins, mut outs) = (0, 0);
            let (mut tin, mut tout) = (Vec::new(), Vec::new());
            for d in inner.iter().filter(|e| e.name == "DataItem") {
                let bytes = match attr(d, "DataType") {
                    "Unsigned16" => 2,
                    other => panic!("data type {other}"),
                };
                let txt = t
                    .get(attr(d, "TextId"))
                    .unwrap_or_else(|| panic!("text {:?}", d))
                    .clone();
                match d.path.last().map(String::as_str) {
                    Some("Input") => {
                        ins += bytes;
                        tin.push(txt);
                    }
                    Some("Output") => {
                        outs += bytes;
                        tout.push(txt);
                    }
                    other => panic!("DataItem under {other:?}"),
                }
            }
            out.insert(id, (ins, outs, tin, tout));
        }
        out
    }

    fn allowed(els: &[El]) -> HashMap<String, String> {
        named(els, "ModuleItemRef")
            .into_iter()
            .map(|r| {
                (
                    attr(r, "ModuleItemTarget").to_string(),
                    attr(r, "AllowedInSlots").to_string(),
                )
            })
            .collect()
    }

    /// The ID of the ModuleItem with ident `id`.
    fn module_id(els: &[El], id: u32) -> String {
        named(els, "ModuleItem")
            .into_iter()
            .find(|m| attr(m, "ModuleIdentNumber") == ident(id))
            .map(|m| attr(m, "ID").to_string())
            .unwrap_or_default()
    }

    /// Record indices and lengths of the ParameterRecordDataItems below `e`.
    fn records_in(els: &[El], e: &El) -> Vec<(u16, usize)> {
        below(els, index_of(els, e))
            .into_iter()
            .filter(|r| r.name == "ParameterRecordDataItem")
            .map(|r| {
                (
                    attr(r, "Index").parse().unwrap(),
                    attr(r, "Length").parse().unwrap(),
                )
            })
            .collect()
    }

    fn module_el(els: &[El], id: u32) -> &El {
        named(els, "ModuleItem")
            .into_iter()
            .find(|m| attr(m, "ModuleIdentNumber") == ident(id))
            .unwrap()
    }

    fn error_types(els: &[El]) -> Vec<u16> {
        named(els, "ChannelDiagItem")
            .into_iter()
            .map(|d| attr(d, "ErrorType").parse().unwrap())
            .collect()
    }

    #[test]
    fn identity_and_structure_of_both_products() {
        for p in [Product::Sk550p, Product::Tu3Pnt] {
            let xml = gsdml(p, p.max_inverters()).unwrap();
            let els = elements(&xml);
            assert_eq!(els[0].name, "ISO15745Profile");
            assert_eq!(attr(&els[0], "xmlns"), NAMESPACE);
            let id = named(&els, "DeviceIdentity")[0];
            assert_eq!(attr(id, "VendorID"), format!("0x{:04X}", def::VENDOR_ID));
            assert_eq!(
                attr(id, "DeviceID"),
                format!("0x{:04X}", def::device_id(p).unwrap())
            );
            assert_eq!(attr(id, "VendorID"), "0x0538");
            // The vendor name's "&" arrives as written (escaped in the file).
            assert!(xml.contains("Getriebebau NORD GmbH &amp; Co. KG"));
            let vendor = named(&els, "VendorName");
            assert!(vendor
                .iter()
                .all(|v| attr(v, "Value") == "Getriebebau NORD GmbH & Co. KG"));
            // One DAP in slot 0 over the product's slots, with interface and two ports.
            let daps = named(&els, "DeviceAccessPointItem");
            assert_eq!(daps.len(), 1);
            let last = def::slot_count(p) - 1;
            assert_eq!(attr(daps[0], "PhysicalSlots"), format!("0..{last}"));
            assert_eq!(attr(daps[0], "FixedInSlots"), "0");
            assert_eq!(attr(daps[0], "ModuleIdentNumber"), "0x00000001");
            let iface = named(&els, "InterfaceSubmoduleItem");
            assert_eq!(
                (
                    attr(iface[0], "SubslotNumber"),
                    attr(iface[0], "SubmoduleIdentNumber")
                ),
                ("32768", "0x00008000")
            );
            let ports: Vec<(&str, &str)> = named(&els, "PortSubmoduleItem")
                .into_iter()
                .map(|e| (attr(e, "SubslotNumber"), attr(e, "SubmoduleIdentNumber")))
                .collect();
            assert_eq!(ports, [("32769", "0x00008001"), ("32770", "0x00008002")]);
            // Every TextId used is in the ExternalTextList, and every ModuleItemRef resolves.
            let t = texts(&els);
            for e in els.iter().filter(|e| e.name != "Text") {
                if let Some(id) = e.attrs.get("TextId") {
                    assert!(t.contains_key(id), "{id} has no text");
                }
            }
            let ids: Vec<&str> = named(&els, "ModuleItem")
                .into_iter()
                .map(|m| attr(m, "ID"))
                .collect();
            for r in named(&els, "ModuleItemRef") {
                assert!(ids.contains(&attr(r, "ModuleItemTarget")), "{r:?}");
            }
            assert_eq!(t["IDT_NAME_DAP"], def::station_type(p).unwrap());
        }
    }

    #[test]
    fn every_module_with_its_ident_and_lengths() {
        for p in [Product::Sk550p, Product::Tu3Pnt] {
            let els = elements(&gsdml(p, 1).unwrap());
            let io = module_io(&els);
            let want = def::modules(p);
            assert_eq!(io.len(), want.len(), "{p:?}");
            for m in &want {
                let (ins, outs, _, _) = &io[&m.ident];
                assert_eq!((*ins, *outs), (m.input_len, m.output_len), "{}", m.name());
            }
        }
        // PPO2 on the SK 550P (ident 10): PKW, control word, setpoints 1…3 (BU 0620 §2.5.5.1).
        let els = elements(&gsdml(Product::Sk550p, 8).unwrap());
        let io = module_io(&els);
        let (_, _, tin, tout) = &io[&10];
        assert!(tout[0].starts_with("PKE") && tin[0].starts_with("PKE"));
        assert_eq!(
            tout[4..],
            ["Control word", "Setpoint 1", "Setpoint 2", "Setpoint 3"]
        );
        assert_eq!(tin[4], "Status word");
        assert_eq!(tin.len(), 8);
        // PPO3 (ident 6): no PKW.
        assert_eq!(io[&6].2, ["Status word", "Actual value 1"]);
        // The SK TU3-PNT's DIG-IO (ident 2): one word each way (P176/P177 [-01]).
        let tu = module_io(&elements(&gsdml(Product::Tu3Pnt, 1).unwrap()));
        assert_eq!(tu[&2].2, ["Bus module inputs"]);
        assert_eq!(tu[&2].3, ["Bus module outputs"]);
        let ppo6 = def::module(Product::Tu3Pnt, ModuleKind::Ppo(PpoType::TYPE_6)).unwrap();
        assert_eq!(tu[&ppo6.ident].2.len(), 6);
    }

    #[test]
    fn sk550p_slots_follow_the_inverters() {
        for (n, slots) in [(1, "3"), (3, "3..5"), (8, "3..10")] {
            let els = elements(&gsdml(Product::Sk550p, n).unwrap());
            let allowed = allowed(&els);
            assert_eq!(allowed.len(), def::modules(Product::Sk550p).len());
            for m in def::modules(Product::Sk550p) {
                assert_eq!(allowed[&module_id(&els, m.ident)], slots, "{n} inverters");
            }
            // Records 100 and 101…100 + n on every FI module (BU 0620 §2.5.6.2).
            let mut want = vec![(100, 8)];
            want.extend((1..=u16::from(n)).map(|i| (100 + i, 8)));
            assert_eq!(records_in(&els, module_el(&els, 6)), want);
            assert!(records_in(&els, named(&els, "DeviceAccessPointItem")[0])
                .iter()
                .all(|r| r.0 != 47));
        }
    }

    #[test]
    fn tu3_pnt_slots_and_records() {
        let els = elements(&gsdml(Product::Tu3Pnt, 1).unwrap());
        let allowed = allowed(&els);
        assert_eq!(allowed[&module_id(&els, def::DIG_IO_IDENT)], "2");
        for m in def::modules(Product::Tu3Pnt)
            .iter()
            .filter(|m| m.kind != ModuleKind::DigIo)
        {
            assert_eq!(allowed[&module_id(&els, m.ident)], "3", "{}", m.name());
            assert_eq!(records_in(&els, module_el(&els, m.ident)), [(101, 8)]);
        }
        assert_eq!(
            records_in(&els, module_el(&els, def::DIG_IO_IDENT)),
            [(100, 8)]
        );
        // Record 47 (11 bytes, BU 0590 §4.2.4.3) on the DAP, slot 0.
        let dap = named(&els, "DeviceAccessPointItem")[0];
        let on_dap: Vec<_> = below(&els, index_of(&els, dap))
            .into_iter()
            .filter(|e| e.name == "ParameterRecordDataItem")
            .collect();
        assert_eq!(on_dap.len(), 1);
        assert_eq!(
            (attr(on_dap[0], "Index"), attr(on_dap[0], "Length")),
            ("47", "11")
        );
        assert!(on_dap[0].path.iter().any(|p| p == "VirtualSubmoduleList"));
        let zeros = below(&els, index_of(&els, on_dap[0]))
            .into_iter()
            .find(|e| e.name == "Const")
            .map(|c| attr(c, "Data").split(',').count());
        assert_eq!(zeros, Some(11));
    }

    #[test]
    fn alarm_numbers_of_the_manuals() {
        let sk = elements(&gsdml(Product::Sk550p, 8).unwrap());
        let types = error_types(&sk);
        // BU 0620 §5.4.2: E10.3 → 359; lost inverter 1256; BU 0590 P163: E5.0 → 132h.
        for a in [359, 1256, 0x132, def::fi_error_alarm(102)] {
            assert!(types.contains(&a), "{a}");
        }
        assert!(types.windows(2).all(|w| w[0] < w[1]), "ascending, unique");
        assert!(types.iter().all(|&t| def::manufacturer_error_type(t)));
        let t = texts(&sk);
        let e103 = named(&sk, "ChannelDiagItem")
            .into_iter()
            .find(|d| attr(d, "ErrorType") == "359")
            .unwrap();
        let name = below(&sk, index_of(&sk, e103))[0];
        assert!(t[attr(name, "TextId")].starts_with("E10.3"), "{name:?}");
        // The SK TU3-PNT: inverter errors and its P170 1020 (→ 1276), no system bus.
        let tu = error_types(&elements(&gsdml(Product::Tu3Pnt, 1).unwrap()));
        assert!(tu.contains(&359) && tu.contains(&1276));
        assert!(!tu.contains(&1256));
        assert!(!types.contains(&1276));
    }

    #[test]
    fn refusals() {
        assert!(gsdml(Product::Tu3Eip, 1)
            .unwrap_err()
            .to_string()
            .contains("no PROFINET"));
        assert!(gsdml(Product::Tu3Pnt, 2).is_err());
        assert!(gsdml(Product::Sk550p, 0).is_err());
        assert!(gsdml(Product::Sk550p, 9).is_err());
    }

    #[test]
    fn value_lists() {
        assert_eq!(runs([3, 4, 5, 10]), "3..5 10");
        assert_eq!(runs([2]), "2");
        assert_eq!(runs([]), "");
        assert_eq!(
            parameter_ranges(Product::Sk550p, RecordTarget::Interface),
            "P850…P899"
        );
        let fi = RecordTarget::Inverter(Inverter::new(1).unwrap());
        assert_eq!(
            parameter_ranges(Product::Sk550p, fi),
            "P000…P849, P900…P999"
        );
    }
}
