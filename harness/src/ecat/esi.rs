//! `harness describe esi`: the EtherCAT Slave Information file (ETG.2000) of the SK 550P's
//! integrated EtherCAT interface, written from `proto::nord::ecat` — the same data the
//! simulated slave builds its SII EEPROM, SyncManagers, PDOs and CoE dictionary from, so a
//! master configured from this file finds the device it describes (BU 0620 §3.4, §3.6.1:
//! vendor ID, product code and revision identify it in a bus scan).

use proto::nord::ecat::{self as def, EntryAccess, Object, Pdo, PdoMapping, SmRole, Value};
use quick_xml::events::{BytesDecl, Event};
use quick_xml::Writer;
use std::io::Cursor;

/// Why the ESI could not be written.
#[derive(Debug, thiserror::Error)]
pub(crate) enum EsiError {
    /// The XML writer failed (it writes to memory: only on a bug).
    #[error("cannot write the ESI XML: {0}")]
    Xml(#[from] std::io::Error),
}

/// `#x0538`: the ESI notation of a hexadecimal number.
fn hex(v: u32, digits: usize) -> String {
    format!("#x{v:0digits$X}")
}

type W = Writer<Cursor<Vec<u8>>>;

/// One element with text.
fn text(w: &mut W, name: &str, value: &str) -> std::io::Result<()> {
    w.create_element(name)
        .write_text_content(quick_xml::events::BytesText::new(value))?;
    Ok(())
}

/// The ESI XML for the SK 550P with `inverters` inverters behind its interface.
pub(crate) fn esi(inverters: u8) -> Result<String, EsiError> {
    let mut w = Writer::new_with_indent(Cursor::new(Vec::new()), b' ', 2);
    w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))?;
    w.create_element("EtherCATInfo")
        .with_attribute(("Version", "1.6"))
        .write_inner_content(|w| {
            w.create_element("Vendor").write_inner_content(|w| {
                text(w, "Id", &hex(def::VENDOR_ID, 8))?;
                text(w, "Name", def::VENDOR_NAME)
            })?;
            w.create_element("Descriptions").write_inner_content(|w| {
                w.create_element("Groups").write_inner_content(|w| {
                    w.create_element("Group").write_inner_content(|w| {
                        text(w, "Type", def::GROUP)?;
                        text(w, "Name", def::GROUP)
                    })?;
                    Ok(())
                })?;
                w.create_element("Devices")
                    .write_inner_content(|w| device(w, inverters))?;
                Ok(())
            })?;
            Ok(())
        })?;
    let bytes = w.into_inner().into_inner();
    Ok(String::from_utf8_lossy(&bytes).into_owned() + "\n")
}

fn device(w: &mut W, inverters: u8) -> std::io::Result<()> {
    w.create_element("Device")
        .with_attribute(("Physics", "YY"))
        .write_inner_content(|w| {
            w.create_element("Type")
                .with_attributes([
                    ("ProductCode", hex(def::PRODUCT_CODE, 8).as_str()),
                    ("RevisionNo", hex(def::REVISION, 8).as_str()),
                ])
                .write_text_content(quick_xml::events::BytesText::new(def::ORDER_NUMBER))?;
            text(w, "Name", def::DEVICE_NAME)?;
            text(w, "GroupType", def::GROUP)?;
            w.create_element("Profile").write_inner_content(|w| {
                text(w, "ProfileNo", "5001")?;
                text(w, "AddInfo", "0")?;
                let od = def::object_dictionary(inverters);
                w.create_element("Dictionary").write_inner_content(|w| {
                    // ETG.2000 DictionaryType: DataTypes, then Objects. Every type an object
                    // names is defined here, from the same objects.
                    w.create_element("DataTypes").write_inner_content(|w| {
                        for t in data_types(&od) {
                            data_type(w, &t)?;
                        }
                        Ok(())
                    })?;
                    w.create_element("Objects").write_inner_content(|w| {
                        for o in &od {
                            object(w, o)?;
                        }
                        Ok(())
                    })?;
                    Ok(())
                })?;
                Ok(())
            })?;
            for f in def::FMMUS {
                let name = match f {
                    def::FmmuUse::Outputs => "Outputs",
                    def::FmmuUse::Inputs => "Inputs",
                    def::FmmuUse::MailboxState => "MBoxState",
                };
                text(w, "Fmmu", name)?;
            }
            for sm in def::sync_managers(inverters) {
                let name = match sm.role {
                    SmRole::MailboxOut => "MBoxOut",
                    SmRole::MailboxIn => "MBoxIn",
                    SmRole::Outputs => "Outputs",
                    SmRole::Inputs => "Inputs",
                };
                let mut e = w
                    .create_element("Sm")
                    .with_attribute(("StartAddress", hex(u32::from(sm.start), 4).as_str()))
                    .with_attribute(("ControlByte", hex(u32::from(sm.control), 2).as_str()))
                    .with_attribute(("Enable", if sm.enable { "1" } else { "0" }));
                if matches!(sm.role, SmRole::MailboxOut | SmRole::MailboxIn) {
                    e = e.with_attribute(("DefaultSize", sm.len.to_string().as_str()));
                }
                e.write_text_content(quick_xml::events::BytesText::new(name))?;
            }
            for p in def::rx_pdos(inverters) {
                pdo(w, "RxPdo", &p)?;
            }
            for p in def::tx_pdos(inverters) {
                pdo(w, "TxPdo", &p)?;
            }
            w.create_element("Mailbox").write_inner_content(|w| {
                let yes = |b: bool| if b { "true" } else { "false" };
                w.create_element("CoE")
                    .with_attributes([
                        ("SdoInfo", yes(def::COE.sdo_info)),
                        ("PdoAssign", yes(def::COE.pdo_assign)),
                        ("PdoConfig", yes(def::COE.pdo_config)),
                        ("CompleteAccess", yes(def::COE.complete_access)),
                    ])
                    .write_empty()?;
                Ok(())
            })?;
            w.create_element("Eeprom").write_inner_content(|w| {
                text(w, "ByteSize", &def::EEPROM_BYTES.to_string())?;
                // ConfigData: SII words 0..=7 as the ESC reads them at power-on (PDI control,
                // PDI configuration, …), little-endian.
                let config = [def::PDI_CONTROL, def::PDI_CONFIG];
                let bytes: String = config
                    .iter()
                    .flat_map(|w| w.to_le_bytes())
                    .map(|b| format!("{b:02X}"))
                    .collect();
                text(w, "ConfigData", &bytes)
            })?;
            Ok(())
        })?;
    Ok(())
}

/// The `<Type>` an object names: its entry's base type for a VAR, `DT1018` and the like (the
/// `<DataType>` [`data_types`] defines) for an ARRAY or RECORD.
fn type_name(o: &Object) -> String {
    match (o.code, o.entries.first()) {
        (def::ObjectCode::Var, Some(e)) => e.data_type.esi_name(),
        _ => format!("DT{:04X}", o.index),
    }
}

/// Where an object's entries sit in its complete-access image (ETG.2000 `BitOffs`, as ESIs
/// write them): sub-index 0 at bit 0, padded to a word, so sub-index 1 starts at bit 16;
/// entries of 16 bits and more on word boundaries, bytes on byte boundaries. `offsets` runs
/// parallel to `Object::entries`; `bit_size` is the object's (and its type's) `BitSize`.
struct Layout {
    offsets: Vec<u16>,
    bit_size: u16,
}

fn layout(o: &Object) -> Layout {
    if o.code == def::ObjectCode::Var {
        let bits = o.entries.first().map_or(0, |e| e.data_type.bits());
        return Layout {
            offsets: vec![0; o.entries.len()],
            bit_size: bits,
        };
    }
    let align = |at: u16, to: u16| at.div_ceil(to) * to;
    let (mut offsets, mut at) = (Vec::with_capacity(o.entries.len()), 0u16);
    for (i, e) in o.entries.iter().enumerate() {
        let bits = e.data_type.bits();
        let to = match bits {
            16.. => 16,
            b if b % 8 == 0 => 8,
            _ => 1,
        };
        at = align(at, to);
        offsets.push(at);
        at += bits;
        if i == 0 {
            at = align(at, 16);
        }
    }
    Layout {
        offsets,
        bit_size: at,
    }
}

/// One `<SubItem>` of a RECORD's (or ARRAY's) `<DataType>`.
struct SubItem {
    /// `None` for an ARRAY's elements (one SubItem of the `…ARR` type).
    sub: Option<u8>,
    name: String,
    type_name: String,
    bits: u16,
    offset: u16,
    access: EntryAccess,
    pdo: PdoMapping,
}

/// One `<DataType>` of the dictionary.
enum DataType {
    /// A base type (`USINT`, `STRING(18)`, …): name and size only.
    Base { name: String, bits: u16 },
    /// The elements of an ARRAY (`DT1C12ARR`): base type, size and count, lower bound 1.
    Array {
        name: String,
        base: String,
        bits: u16,
        elements: u16,
    },
    /// An ARRAY's or RECORD's type (`DT1018`): its SubItems.
    Compound {
        name: String,
        bits: u16,
        items: Vec<SubItem>,
    },
}

impl DataType {
    fn name(&self) -> &str {
        match self {
            DataType::Base { name, .. }
            | DataType::Array { name, .. }
            | DataType::Compound { name, .. } => name,
        }
    }
}

/// The `<DataTypes>` of the dictionary `od`: every base type its entries use (in order of
/// first use), then per ARRAY its `…ARR` element type and per ARRAY and RECORD its own type,
/// with the sizes and offsets of [`layout`] — the ones its `<Object>` states.
fn data_types(od: &[Object]) -> Vec<DataType> {
    let mut out: Vec<DataType> = Vec::new();
    for e in od.iter().flat_map(|o| &o.entries) {
        let name = e.data_type.esi_name();
        if !out.iter().any(|t| t.name() == name) {
            out.push(DataType::Base {
                name,
                bits: e.data_type.bits(),
            });
        }
    }
    for o in od.iter().filter(|o| o.code != def::ObjectCode::Var) {
        let name = type_name(o);
        let Layout { offsets, bit_size } = layout(o);
        let item = |e: &def::Entry, offset: u16| SubItem {
            sub: Some(e.sub),
            name: e.name.clone(),
            type_name: e.data_type.esi_name(),
            bits: e.data_type.bits(),
            offset,
            access: e.access,
            pdo: e.pdo,
        };
        let mut items: Vec<SubItem> = Vec::new();
        let mut parts = o.entries.iter().zip(offsets);
        if o.code == def::ObjectCode::Array {
            // Sub-index 0, then one SubItem for all elements (ETG.2000: an ARRAY's type is
            // sub-index 0 and an array of the element type, lower bound 1).
            items.extend(parts.next().map(|(e, at)| item(e, at)));
            let elements: Vec<(&def::Entry, u16)> = parts.collect();
            let base = elements.first().map(|(e, _)| e.data_type);
            let at = elements.first().map_or(16, |(_, at)| *at);
            let bits = bit_size - at;
            let array = format!("{name}ARR");
            out.push(DataType::Array {
                name: array.clone(),
                // An empty array (1C10h, 1C11h: no PDO on a mailbox SM) has no element type
                // of its own: it counts UNSIGNED16 PDO indices like 1C12h.
                base: base.map_or_else(|| "UINT".into(), |t| t.esi_name()),
                bits,
                elements: elements.len() as u16,
            });
            let first = elements.first().map(|(e, _)| *e);
            items.push(SubItem {
                sub: None,
                name: "Elements".into(),
                type_name: array,
                bits,
                offset: at,
                access: first.map_or(EntryAccess::Ro, |e| e.access),
                pdo: first.map_or(PdoMapping::None, |e| e.pdo),
            });
        } else {
            items.extend(parts.map(|(e, at)| item(e, at)));
        }
        out.push(DataType::Compound {
            name,
            bits: bit_size,
            items,
        });
    }
    out
}

fn data_type(w: &mut W, t: &DataType) -> std::io::Result<()> {
    w.create_element("DataType").write_inner_content(|w| {
        text(w, "Name", t.name())?;
        match t {
            DataType::Base { bits, .. } => text(w, "BitSize", &bits.to_string())?,
            DataType::Array {
                base,
                bits,
                elements,
                ..
            } => {
                text(w, "BaseType", base)?;
                text(w, "BitSize", &bits.to_string())?;
                w.create_element("ArrayInfo").write_inner_content(|w| {
                    text(w, "LBound", "1")?;
                    text(w, "Elements", &elements.to_string())
                })?;
            }
            DataType::Compound { bits, items, .. } => {
                text(w, "BitSize", &bits.to_string())?;
                for i in items {
                    w.create_element("SubItem").write_inner_content(|w| {
                        if let Some(sub) = i.sub {
                            text(w, "SubIdx", &sub.to_string())?;
                        }
                        text(w, "Name", &i.name)?;
                        text(w, "Type", &i.type_name)?;
                        text(w, "BitSize", &i.bits.to_string())?;
                        text(w, "BitOffs", &i.offset.to_string())?;
                        flags_mapped(w, i.access, i.pdo)
                    })?;
                }
            }
        }
        Ok(())
    })?;
    Ok(())
}

fn object(w: &mut W, o: &Object) -> std::io::Result<()> {
    w.create_element("Object").write_inner_content(|w| {
        text(w, "Index", &hex(u32::from(o.index), 4))?;
        text(w, "Name", &o.name)?;
        let first = o.entries.first();
        text(w, "Type", &type_name(o))?;
        text(w, "BitSize", &layout(o).bit_size.to_string())?;
        if o.code == def::ObjectCode::Var {
            if let Some(e) = first {
                default_data(w, e)?;
                flags(w, e.access)?;
            }
        } else {
            w.create_element("Info").write_inner_content(|w| {
                for e in &o.entries {
                    w.create_element("SubItem").write_inner_content(|w| {
                        text(w, "Name", &e.name)?;
                        default_data(w, e)
                    })?;
                }
                Ok(())
            })?;
        }
        Ok(())
    })?;
    Ok(())
}

/// `<Info><DefaultData>` of a constant entry: its value little-endian as hex, as ESI writes it.
fn default_data(w: &mut W, e: &def::Entry) -> std::io::Result<()> {
    let data: Option<Vec<u8>> = match &e.value {
        Value::Number(n) => Some(n.to_le_bytes()[..e.data_type.bytes().min(8)].to_vec()),
        Value::Text(s) => Some(s.as_bytes().to_vec()),
        Value::Output { .. } | Value::Input { .. } => None,
    };
    let Some(data) = data else { return Ok(()) };
    let hexed: String = data.iter().map(|b| format!("{b:02X}")).collect();
    w.create_element("Info")
        .write_inner_content(|w| text(w, "DefaultData", &hexed))?;
    Ok(())
}

fn flags(w: &mut W, access: EntryAccess) -> std::io::Result<()> {
    flags_mapped(w, access, PdoMapping::None)
}

/// `<Flags>`: SDO access and, for a mappable entry, `<PdoMapping>` R (RxPDO) or T (TxPDO).
fn flags_mapped(w: &mut W, access: EntryAccess, pdo: PdoMapping) -> std::io::Result<()> {
    w.create_element("Flags").write_inner_content(|w| {
        text(
            w,
            "Access",
            match access {
                EntryAccess::Ro => "ro",
                EntryAccess::Rw => "rw",
            },
        )?;
        match pdo {
            PdoMapping::None => Ok(()),
            PdoMapping::Rx => text(w, "PdoMapping", "R"),
            PdoMapping::Tx => text(w, "PdoMapping", "T"),
        }
    })?;
    Ok(())
}

fn pdo(w: &mut W, element: &str, p: &Pdo) -> std::io::Result<()> {
    let mut e = w
        .create_element(element)
        .with_attribute(("Sm", p.sm.to_string().as_str()));
    if p.fixed {
        e = e.with_attribute(("Fixed", "1"));
    }
    e.write_inner_content(|w| {
        text(w, "Index", &hex(u32::from(p.index), 4))?;
        text(w, "Name", &p.name)?;
        for entry in &p.entries {
            w.create_element("Entry").write_inner_content(|w| {
                text(w, "Index", &hex(u32::from(entry.index), 4))?;
                text(w, "SubIndex", &entry.sub.to_string())?;
                text(w, "BitLen", &entry.bits.to_string())?;
                text(w, "Name", &entry.name)?;
                text(w, "DataType", &entry.data_type.esi_name())
            })?;
        }
        Ok(())
    })?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::description::xml::{self, Element};
    use quick_xml::events::Event;
    use quick_xml::Reader;
    use sim::device::{Device, DeviceConfig};

    /// The text of every element named `name`, in document order (the document must parse:
    /// any malformed XML fails the test).
    fn texts(xml: &str, name: &str) -> Vec<String> {
        let mut reader = Reader::from_str(xml);
        let (mut out, mut current) = (Vec::new(), None::<String>);
        loop {
            match reader.read_event().expect("well-formed XML") {
                Event::Start(e) => {
                    current = (e.name().as_ref() == name.as_bytes()).then(String::new)
                }
                Event::Text(t) => {
                    if let Some(c) = current.as_mut() {
                        c.push_str(&t.decode().unwrap());
                    }
                }
                // `&amp;` and the like come as references of their own.
                Event::GeneralRef(r) => {
                    if let Some(c) = current.as_mut() {
                        let entity = r.decode().unwrap();
                        c.push_str(quick_xml::escape::resolve_xml_entity(&entity).unwrap());
                    }
                }
                Event::End(_) => out.extend(current.take()),
                Event::Eof => break,
                _ => {}
            }
        }
        out
    }

    fn word32(image: &[u8], word: usize) -> u32 {
        let b = &image[word * 2..word * 2 + 4];
        u32::from_le_bytes([b[0], b[1], b[2], b[3]])
    }

    #[test]
    fn identity_matches_the_simulated_slaves_sii() {
        let xml = esi(8).unwrap();
        let slave =
            sim::ecat::Slave::new(Device::new(DeviceConfig::new(proto::nord::Product::Sk550p)))
                .unwrap();
        let sii = slave.sii_image();
        // SII words 8, 0Ah, 0Ch: vendor ID, product code, revision (ETG.2010 Table 2).
        assert_eq!(texts(&xml, "Id"), [hex(word32(&sii, 8), 8)]);
        assert!(xml.contains(&format!("ProductCode=\"{}\"", hex(word32(&sii, 0x0A), 8))));
        assert!(xml.contains(&format!("RevisionNo=\"{}\"", hex(word32(&sii, 0x0C), 8))));
        assert_eq!(texts(&xml, "Id"), ["#x00000538"]);
    }

    /// ESI base types (ETG.2000): they need no `<DataType>` of their own, though this ESI
    /// lists the ones it uses.
    fn is_base(t: &str) -> bool {
        matches!(
            t,
            "BOOL"
                | "BYTE"
                | "WORD"
                | "DWORD"
                | "SINT"
                | "INT"
                | "DINT"
                | "LINT"
                | "USINT"
                | "UINT"
                | "UDINT"
                | "ULINT"
                | "REAL"
                | "LREAL"
        ) || (t.starts_with("STRING(") && t.ends_with(')'))
    }

    fn child<'a>(e: &'a Element, name: &str) -> &'a Element {
        e.child(name)
            .unwrap_or_else(|| panic!("<{}> without <{name}>", e.name))
    }

    fn child_text<'a>(e: &'a Element, name: &str) -> &'a str {
        child(e, name).text.trim()
    }

    fn child_number(e: &Element, name: &str) -> u64 {
        let t = child_text(e, name);
        xml::number(t).unwrap_or_else(|| panic!("<{name}>{t}</{name}> is no number"))
    }

    /// The `<Dictionary>` of the ESI for `inverters` inverters and its data types by name.
    fn dictionary(inverters: u8) -> (Element, Vec<Element>) {
        let root = xml::parse(&esi(inverters).unwrap(), "sk550p.xml").unwrap();
        let dictionary = root.find("Dictionary").expect("a <Dictionary>").clone();
        let types: Vec<Element> = child(&dictionary, "DataTypes")
            .children("DataType")
            .cloned()
            .collect();
        (dictionary, types)
    }

    fn find<'a>(types: &'a [Element], name: &str) -> Option<&'a Element> {
        types.iter().find(|t| child_text(t, "Name") == name)
    }

    /// KickCAT (issue 21) refuses an object whose `<Type>` no `<DataType>` defines: every type
    /// an object, a SubItem or an array names is defined, once, with the size it is used with.
    #[test]
    fn every_object_type_is_a_data_type_of_its_bit_size() {
        for inverters in 1..=def::MAX_INVERTERS {
            let (dictionary, types) = dictionary(inverters);
            // DictionaryType: DataTypes first, then Objects.
            let order: Vec<&str> = dictionary
                .children
                .iter()
                .map(|c| c.name.as_str())
                .collect();
            assert_eq!(order, ["DataTypes", "Objects"]);
            for (i, t) in types.iter().enumerate() {
                let name = child_text(t, "Name");
                assert!(
                    types[..i].iter().all(|u| child_text(u, "Name") != name),
                    "DataType {name} twice"
                );
            }
            let objects: Vec<&Element> = child(&dictionary, "Objects").children("Object").collect();
            assert_eq!(objects.len(), def::object_dictionary(inverters).len());
            for o in objects {
                let (index, ty) = (child_text(o, "Index"), child_text(o, "Type"));
                let bits = child_number(o, "BitSize");
                match find(&types, ty) {
                    Some(dt) => assert_eq!(
                        child_number(dt, "BitSize"),
                        bits,
                        "object {index}: BitSize {bits}, its type {ty} another"
                    ),
                    None => assert!(is_base(ty), "object {index}: no <DataType> {ty}"),
                }
                assert!(
                    find(&types, ty).is_some(),
                    "object {index}: {ty} not listed"
                );
            }
            for dt in &types {
                let (name, size) = (child_text(dt, "Name"), child_number(dt, "BitSize"));
                let mut end = 0;
                for si in dt.children("SubItem") {
                    let ty = child_text(si, "Type");
                    let (bits, at) = (child_number(si, "BitSize"), child_number(si, "BitOffs"));
                    let st = find(&types, ty).unwrap_or_else(|| panic!("{name}: no type {ty}"));
                    assert_eq!(child_number(st, "BitSize"), bits, "{name}: SubItem of {ty}");
                    assert!(at >= end, "{name}: SubItems overlap at bit {at}");
                    end = at + bits;
                }
                assert!(end <= size, "{name}: SubItems end at {end}, beyond {size}");
                if let Some(array) = dt.child("ArrayInfo") {
                    let base = child_text(dt, "BaseType");
                    let bt = find(&types, base).unwrap_or_else(|| panic!("{name}: no {base}"));
                    assert_eq!(child_number(array, "LBound"), 1);
                    assert_eq!(
                        child_number(bt, "BitSize") * child_number(array, "Elements"),
                        size,
                        "{name}"
                    );
                }
            }
        }
    }

    /// The types say what the dictionary holds: a RECORD's SubItems are its sub-indices, an
    /// ARRAY's element count is its sub-index 0, and each `<Object>` lists as many SubItems.
    #[test]
    fn data_types_follow_the_dictionary() {
        let (dictionary, types) = dictionary(def::MAX_INVERTERS);
        let od = def::object_dictionary(def::MAX_INVERTERS);
        let objects: Vec<&Element> = child(&dictionary, "Objects").children("Object").collect();
        for (o, x) in od.iter().zip(objects) {
            assert_eq!(child_number(x, "Index"), u64::from(o.index));
            let Some(dt) = find(&types, &type_name(o)) else {
                continue;
            };
            let items: Vec<&Element> = dt.children("SubItem").collect();
            match o.code {
                def::ObjectCode::Var => assert!(items.is_empty()),
                def::ObjectCode::Record => {
                    let subs: Vec<u64> = items.iter().map(|i| child_number(i, "SubIdx")).collect();
                    let want: Vec<u64> = o.entries.iter().map(|e| u64::from(e.sub)).collect();
                    assert_eq!(subs, want, "{:04X}", o.index);
                }
                def::ObjectCode::Array => {
                    assert_eq!(
                        items.len(),
                        2,
                        "{:04X}: sub-index 0 and the elements",
                        o.index
                    );
                    let elements = &o.entries[1..];
                    assert!(elements
                        .windows(2)
                        .all(|p| p[0].data_type == p[1].data_type));
                    let arr = find(&types, child_text(items[1], "Type")).unwrap();
                    let count = child_number(child(arr, "ArrayInfo"), "Elements");
                    assert_eq!(count, elements.len() as u64, "{:04X}", o.index);
                }
            }
            if o.code != def::ObjectCode::Var {
                let info = child(x, "Info").children("SubItem").count();
                assert_eq!(info, o.entries.len(), "{:04X}", o.index);
            }
        }
        // As the ETG's own ESIs write them: sub-index 0 padded to a word.
        let dt1018 = find(&types, "DT1018").unwrap();
        assert_eq!(child_number(dt1018, "BitSize"), 144);
        let offs: Vec<u64> = dt1018
            .children("SubItem")
            .map(|i| child_number(i, "BitOffs"))
            .collect();
        assert_eq!(offs, [0, 16, 48, 80, 112]);
        // Process data entries are mappable: outputs into RxPDOs, inputs into TxPDOs.
        for (ty, mapping) in [("DT7000", "R"), ("DT6000", "T")] {
            let dt = find(&types, ty).unwrap();
            let mapped: Vec<&str> = dt
                .children("SubItem")
                .filter_map(|i| child(i, "Flags").child("PdoMapping"))
                .map(|m| m.text.trim())
                .collect();
            assert_eq!(mapped, [mapping; 6], "{ty}");
        }
    }

    #[test]
    fn sync_managers_and_pdos_follow_the_inverter_count() {
        let xml = esi(3).unwrap();
        assert_eq!(
            texts(&xml, "Sm"),
            ["MBoxOut", "MBoxIn", "Outputs", "Inputs"]
        );
        // One RxPDO and one TxPDO of six 16-bit words per inverter (BU 0620 §2.2.6.1).
        let indices = texts(&xml, "Index");
        for i in ["#x1600", "#x1601", "#x1602", "#x1A00", "#x1A01", "#x1A02"] {
            assert!(indices.iter().any(|x| x == i), "{i} missing");
        }
        assert!(!indices.iter().any(|x| x == "#x1603"));
        let bitlens = texts(&xml, "BitLen");
        assert_eq!(bitlens.len(), 3 * 2 * 6);
        assert!(bitlens.iter().all(|b| b == "16"));
        // The dictionary of §2.2.7.1 is in it: identity 1018h.
        assert!(indices.iter().any(|x| x == "#x1018"));
        assert_eq!(
            texts(&xml, "Name").first().map(String::as_str),
            Some(def::VENDOR_NAME)
        );
    }
}
