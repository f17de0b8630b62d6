//! `harness describe xdd`: the POWERLINK XML Device Description (EPSG DS 311) of a NORD
//! controlled node, written from `proto::nord::epl` — the definition the simulated node
//! (`sim::epl`) builds its identity, object dictionary and process maps from — and from the
//! parameter catalogue (`proto::nord::params`) the node's parameter objects answer from. A
//! configurator set up from this file finds the device it describes (BU 2200 §5.2.1: "Die
//! Datei … enthält eine Beschreibung der Geräteeigenschaften der Busschnittstelle und deren
//! Parameter"; BU 0620 §2.4.5: the process data "are determined by the device description
//! file (XDD file)").
//!
//! The file is an `ISO15745ProfileContainer` of two profiles (DS 311 §7): the device profile
//! (`ProfileBody_Device_Powerlink`: `DeviceIdentity`) and the communication profile
//! (`ProfileBody_CommunicationNetwork_Powerlink`: `ApplicationLayers` with the data types and
//! the `ObjectList`, `TransportLayers`, `NetworkManagement` with `GeneralFeatures` and
//! `CNFeatures`). The object list holds
//! - every object of [`def::object_dictionary`] (1000h, 1008h, 1018h, 1400h/1600h, 1800h/1A00h,
//!   1F82h, the process data objects 5000h…);
//! - the objects whose value lives in the node (DS 301: 1001h, 1003h, 1006h, 1F8Ch, 1F93h,
//!   1F99h), with the types and access the simulator answers them with;
//! - the NORD parameter objects at device id + parameter number (BU 0620 §2.4.6, BU 2200 §6.4)
//!   for FI 1…`inverters` that have one (the SK TU3-POL's FU5…FU8 have none,
//!   [`def::device_id_inverters`]), and for the modules their own parameters at 2000h + P; on the
//!   SK 550P the interface parameters (P85x…P89x) answer at FI 1's ids, as the simulator does.
//!   A parameter with sets or elements is an ARRAY whose sub-index 0 is the count
//!   (`proto::nord::ecat::parameter_subindex`, shared with EtherCAT).
//!
//! Assumptions (neither manual gives them), said so once: the SK 550P's file name
//! "0xED_NORD_SK550P.xdd" (BU 2200 §5.2.1 names the modules' files only); the version strings
//! made from [`def::revision`]; `NMTBootTimeNotActive` and `NMTCNSoC2PReq` (see the constants).

use std::collections::BTreeSet;
use std::io::Cursor;

use proto::nord::ecat::{DataType, Entry, EntryAccess, Object, ObjectCode, PdoMapping, Value};
use proto::nord::epl as def;
use proto::nord::params::Owner;
use proto::nord::{Family, Inverter, Product, Protocol};
use quick_xml::events::{BytesDecl, BytesText, Event};
use quick_xml::Writer;

use super::{defs, inverter_parameters, parameter, DescribeError, ObjectDoc};

type W = Writer<Cursor<Vec<u8>>>;

/// DS 311 data type codes beyond [`DataType::code`]: BOOLEAN and DOMAIN (1F93h.2, 1003h).
const BOOLEAN: u16 = 0x0001;
const DOMAIN: u16 = 0x000F;

/// `NMTBootTimeNotActive` (µs, DS 311 GeneralFeatures: the longest time from power-on to
/// NOT_ACTIVE): the simulated node is NOT_ACTIVE from its first instant; 0.
const BOOT_TIME_NOT_ACTIVE_US: u32 = 0;

/// `NMTCNSoC2PReq` (ns, DS 311 CNFeatures: the time the CN needs between SoC and its PReq):
/// the node handles each frame as it comes and needs none; 0.
const SOC_TO_PREQ_NS: u32 = 0;

/// `NMTErrorEntries`: the error entries a StatusResponse carries — the node's error history
/// length (`sim::epl`'s `HISTORY_LEN`, 8).
const ERROR_ENTRIES: u32 = 8;

/// The XDD of `product` with `inverters` inverters behind its interface.
pub(crate) fn xdd(product: Product, inverters: u8) -> Result<String, DescribeError> {
    if !product.protocols().contains(&Protocol::Powerlink) {
        return Err(DescribeError::NoInterface {
            product,
            bus: "POWERLINK",
            format: "XDD",
        });
    }
    DescribeError::check_inverters(product, inverters)?;
    let objects = object_list(product, inverters)?;
    write(product, &objects).map_err(|e| DescribeError::Write {
        format: "XDD",
        detail: e.to_string(),
    })
}

/// The DS 311 file name (BU 2200 §5.2.1; the SK 550P's assumed).
pub(crate) fn file_name(product: Product) -> &'static str {
    match product {
        Product::Tu3Pol => "0xED_NORD_TU3_POL.xdd",
        Product::Tu4Pol => "0xED_NORD_TU4_POL.xdd",
        Product::Cu4Pol => "0xED_NORD_CU4_POL.xdd",
        _ => "0xED_NORD_SK550P.xdd",
    }
}

/// Every object of the node, by index.
fn object_list(product: Product, inverters: u8) -> Result<Vec<ObjectDoc>, DescribeError> {
    let mut list: Vec<ObjectDoc> = def::object_dictionary(product)
        .iter()
        .map(from_dictionary)
        .collect();
    list.extend(node_objects(product));
    list.extend(parameter_objects(product, inverters));
    list.sort_by_key(|o| o.at);
    if let Some(w) = list.windows(2).find(|w| w[0].at == w[1].at) {
        return Err(DescribeError::Inconsistent(format!(
            "two objects at {:04X}h: {} and {} in the dictionary",
            w[0].at, w[0].name, w[1].name
        )));
    }
    Ok(list)
}

/// An object of `proto::nord::epl`'s dictionary.
fn from_dictionary(o: &Object) -> ObjectDoc {
    let sub = |e: &Entry, at: u16| {
        let mut x = ObjectDoc::var(at, e.name.clone(), e.data_type.code(), access(e.access));
        x.pdo = Some(match e.pdo {
            PdoMapping::None => "no",
            PdoMapping::Rx => "RPDO",
            PdoMapping::Tx => "TPDO",
        });
        x.default = value(e);
        x
    };
    match (o.code, o.entries.first()) {
        (ObjectCode::Var, Some(e)) => sub(e, o.index),
        _ => ObjectDoc::compound(
            o.index,
            &o.name,
            o.code,
            o.entries.iter().map(|e| sub(e, u16::from(e.sub))).collect(),
        ),
    }
}

fn access(a: EntryAccess) -> &'static str {
    match a {
        EntryAccess::Ro => "ro",
        EntryAccess::Rw => "rw",
    }
}

/// An entry's constant value as DS 311 writes it: UNSIGNED32/64 in hex (identity, mapping
/// entries), other numbers in decimal, strings as they are; process data has none.
fn value(e: &Entry) -> Option<String> {
    match &e.value {
        Value::Number(n) => Some(match e.data_type {
            DataType::U32 => format!("0x{n:08X}"),
            DataType::U64 => format!("0x{n:016X}"),
            _ => n.to_string(),
        }),
        Value::Text(s) => Some(s.to_string()),
        Value::Output { .. } | Value::Input { .. } => None,
    }
}

/// The DS 301 objects the node answers from its own state (`sim::epl`'s dictionary): their
/// types, access and power-on values.
fn node_objects(product: Product) -> Vec<ObjectDoc> {
    let u8t = DataType::U8.code();
    let u32t = DataType::U32.code();
    let count = |n: u8| ObjectDoc::var(0, "NumberOfEntries", u8t, "ro").default(n.to_string());
    let (lo, hi) = def::cycle_range_us(product);
    let history = std::iter::once(count(0))
        .chain(
            (1..=ERROR_ENTRIES as u16).map(|s| ObjectDoc::var(s, "ErrorEntry_DOM", DOMAIN, "ro")),
        )
        .collect();
    vec![
        ObjectDoc::var(0x1001, "ERR_ErrorRegister_U8", u8t, "ro").default("0"),
        ObjectDoc::compound(0x1003, "ERR_History_ADOM", ObjectCode::Array, history),
        ObjectDoc {
            limits: Some((lo as i32, hi as i32)),
            ..ObjectDoc::var(0x1006, "NMT_CycleLen_U32", u32t, "rw")
                .default(def::DEFAULT_CYCLE_US.to_string())
        },
        ObjectDoc::var(0x1F8C, "NMT_CurrNMTState_U8", u8t, "ro"),
        ObjectDoc::compound(
            0x1F93,
            "NMT_EPLNodeID_REC",
            ObjectCode::Record,
            vec![
                count(2),
                ObjectDoc::var(1, "NodeID_U8", u8t, "ro"),
                ObjectDoc::var(2, "NodeIDByHW_BOOL", BOOLEAN, "ro").default("false"),
            ],
        ),
        ObjectDoc::var(0x1F99, "NMT_CNBasicEthernetTimeout_U32", u32t, "rw")
            .default(def::BASIC_ETHERNET_TIMEOUT_US.to_string()),
    ]
}

/// The parameter objects of FI 1…`inverters` that have a device id (and of a module itself):
/// BU 2200 §6.4 lists none for FU5..FU8 of the SK TU3-POL, whose process data carry them.
fn parameter_objects(product: Product, inverters: u8) -> Vec<ObjectDoc> {
    let mut out = Vec::new();
    if product.family() == Family::Module {
        for d in defs(product, Owner::Interface) {
            out.push(parameter(0x2000, "", d));
        }
    }
    for n in 1..=inverters {
        let Ok(fi) = Inverter::new(i64::from(n)) else {
            continue;
        };
        let Some(base) = def::device_id(product, fi) else {
            continue;
        };
        let prefix = format!("FI {n} ");
        let ds = inverter_parameters(product, fi);
        out.extend(ds.into_iter().map(|d| parameter(base, &prefix, d)));
    }
    out
}

/// The DS 311 element name of a data type (`defType`).
fn type_name(code: u16) -> &'static str {
    match code {
        0x0001 => "Boolean",
        0x0003 => "Integer16",
        0x0004 => "Integer32",
        0x0005 => "Unsigned8",
        0x0006 => "Unsigned16",
        0x0007 => "Unsigned32",
        0x0009 => "Visible_String",
        0x000F => "Domain",
        0x001B => "Unsigned64",
        _ => "Unsigned8",
    }
}

/// One element with text.
fn text(w: &mut W, name: &str, value: &str) -> std::io::Result<()> {
    w.create_element(name)
        .write_text_content(BytesText::new(value))?;
    Ok(())
}

/// The ISO 15745 header of one profile.
fn header(w: &mut W, id: &str, name: &str, class: &str) -> std::io::Result<()> {
    w.create_element("ProfileHeader").write_inner_content(|w| {
        text(w, "ProfileIdentification", id)?;
        text(w, "ProfileRevision", "1")?;
        text(w, "ProfileName", name)?;
        w.create_element("ProfileSource").write_empty()?;
        text(w, "ProfileClassID", class)?;
        w.create_element("ISO15745Reference")
            .write_inner_content(|w| {
                text(w, "ISO15745Part", "4")?;
                text(w, "ISO15745Edition", "1")?;
                text(w, "ProfileTechnology", "Powerlink")
            })?;
        Ok(())
    })?;
    Ok(())
}

fn write(product: Product, objects: &[ObjectDoc]) -> std::io::Result<String> {
    let mut w = Writer::new_with_indent(Cursor::new(Vec::new()), b' ', 2);
    w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))?;
    let vendor = format!("0x{:08X}", def::VENDOR_ID);
    let product_id = format!("0x{:08X}", def::product_code(product));
    let rev = def::revision(product);
    let version = format!("V {}.{} R{}", rev >> 16, (rev >> 8) & 0xFF, rev & 0xFF);
    let body = |w: &mut W, ty: &str, inner: &dyn Fn(&mut W) -> std::io::Result<()>| {
        w.create_element("ProfileBody")
            .with_attributes([
                ("xsi:type", ty),
                ("fileName", file_name(product)),
                ("fileCreator", "nord-harness"),
                ("fileCreationDate", "2026-01-01"),
                ("fileVersion", "01.00"),
                ("supportedLanguages", "en"),
            ])
            .write_inner_content(|w| inner(w))?;
        Ok::<(), std::io::Error>(())
    };
    w.create_element("ISO15745ProfileContainer")
        .with_attributes([
            ("xmlns", "http://www.ethernet-powerlink.org"),
            ("xmlns:xsi", "http://www.w3.org/2001/XMLSchema-instance"),
            (
                "xsi:schemaLocation",
                "http://www.ethernet-powerlink.org Powerlink_Main.xsd",
            ),
        ])
        .write_inner_content(|w| {
            w.create_element("ISO15745Profile")
                .write_inner_content(|w| {
                    header(
                        w,
                        "Powerlink_Device_Profile",
                        &format!("{} device profile", def::device_name(product)),
                        "Device",
                    )?;
                    body(w, "ProfileBody_Device_Powerlink", &|w| {
                        w.create_element("DeviceIdentity")
                            .write_inner_content(|w| {
                                text(w, "vendorName", proto::nord::ecat::VENDOR_NAME)?;
                                text(w, "vendorID", &vendor)?;
                                text(w, "productName", def::device_name(product))?;
                                text(w, "productID", &product_id)?;
                                w.create_element("version")
                                    .with_attribute(("versionType", "SW"))
                                    .write_text_content(BytesText::new(&version))?;
                                Ok(())
                            })?;
                        Ok(())
                    })
                })?;
            w.create_element("ISO15745Profile")
                .write_inner_content(|w| {
                    header(
                        w,
                        "Powerlink_Communication_Profile",
                        &format!("{} communication profile", def::device_name(product)),
                        "CommunicationNetwork",
                    )?;
                    body(w, "ProfileBody_CommunicationNetwork_Powerlink", &|w| {
                        w.create_element("ApplicationLayers")
                            .write_inner_content(|w| {
                                w.create_element("identity").write_inner_content(|w| {
                                    text(w, "vendorID", &vendor)?;
                                    text(w, "productID", &product_id)
                                })?;
                                data_types(w, objects)?;
                                w.create_element("ObjectList").write_inner_content(|w| {
                                    objects.iter().try_for_each(|o| object(w, o, "Object"))
                                })?;
                                Ok(())
                            })?;
                        w.create_element("TransportLayers").write_empty()?;
                        network_management(w, product)
                    })
                })?;
            Ok(())
        })?;
    let bytes = w.into_inner().into_inner();
    Ok(String::from_utf8_lossy(&bytes).into_owned() + "\n")
}

/// `DataTypeList`: the types the objects use.
fn data_types(w: &mut W, objects: &[ObjectDoc]) -> std::io::Result<()> {
    let mut used = BTreeSet::new();
    for o in objects {
        used.extend(o.data_type);
        used.extend(o.subs.iter().filter_map(|s| s.data_type));
    }
    w.create_element("DataTypeList").write_inner_content(|w| {
        for code in used {
            w.create_element("defType")
                .with_attribute(("dataType", format!("{code:04X}").as_str()))
                .write_inner_content(|w| {
                    w.create_element(type_name(code)).write_empty()?;
                    Ok(())
                })?;
        }
        Ok(())
    })?;
    Ok(())
}

/// One `Object` (index in 4 hex digits) or `SubObject` (sub-index in 2).
fn object(w: &mut W, o: &ObjectDoc, element: &str) -> std::io::Result<()> {
    let (key, at) = if element == "Object" {
        ("index", format!("{:04X}", o.at))
    } else {
        ("subIndex", format!("{:02X}", o.at))
    };
    let mut attrs: Vec<(&str, String)> = vec![
        (key, at),
        ("name", o.name.clone()),
        ("objectType", o.object_type.to_string()),
    ];
    if let Some(t) = o.data_type {
        attrs.push(("dataType", format!("{t:04X}")));
    }
    if let Some((lo, hi)) = o.limits {
        attrs.push(("lowLimit", lo.to_string()));
        attrs.push(("highLimit", hi.to_string()));
    }
    if let Some(a) = o.access {
        attrs.push(("accessType", a.into()));
    }
    if let Some(p) = o.pdo {
        attrs.push(("PDOmapping", p.into()));
    }
    if let Some(d) = &o.default {
        attrs.push(("defaultValue", d.clone()));
    }
    let e = w
        .create_element(element)
        .with_attributes(attrs.iter().map(|(k, v)| (*k, v.as_str())));
    if o.subs.is_empty() {
        e.write_empty()?;
    } else {
        e.write_inner_content(|w| o.subs.iter().try_for_each(|s| object(w, s, "SubObject")))?;
    }
    Ok(())
}

/// `NetworkManagement`: a controlled node (no MN functions) with the cycle range of P858 /
/// P165 (BU 0620 §4.2.3, BU 2200 §7.1.2: the range the node accepts in 1006h), the services of
/// [`def::FEATURE_FLAGS`] (isochronous, SDO over UDP/IP and ASnd) and static mapping
/// (BU 0620 §2.4.1).
fn network_management(w: &mut W, product: Product) -> std::io::Result<()> {
    let yes = |b: bool| if b { "true" } else { "false" };
    let flag = |bit: u32| yes(def::FEATURE_FLAGS & (1 << bit) != 0);
    let (lo, hi) = def::cycle_range_us(product);
    let (lo, hi) = (lo.to_string(), hi.to_string());
    let boot = BOOT_TIME_NOT_ACTIVE_US.to_string();
    let errors = ERROR_ENTRIES.to_string();
    let soc2preq = SOC_TO_PREQ_NS.to_string();
    w.create_element("NetworkManagement")
        .write_inner_content(|w| {
            w.create_element("GeneralFeatures")
                .with_attributes([
                    ("DLLFeatureMN", "false"),
                    ("NMTBootTimeNotActive", boot.as_str()),
                    ("NMTCycleTimeMax", hi.as_str()),
                    ("NMTCycleTimeMin", lo.as_str()),
                    ("NMTErrorEntries", errors.as_str()),
                    ("NMTIsochronous", flag(0)),
                    ("NWLIPSupport", flag(1)),
                    ("PDODynamicMapping", "false"),
                    ("SDOServer", "true"),
                    ("SDOSupportASnd", flag(2)),
                    ("SDOSupportUdpIp", flag(1)),
                ])
                .write_empty()?;
            w.create_element("CNFeatures")
                .with_attribute(("NMTCNSoC2PReq", soc2preq.as_str()))
                .write_empty()?;
            Ok(())
        })?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use quick_xml::events::Event;
    use quick_xml::Reader;
    use std::collections::HashMap;

    /// One element as the reader saw it: name, attributes, text, and the index of its parent
    /// `Object` for a `SubObject`.
    #[derive(Debug, Default, Clone)]
    struct El {
        name: String,
        attrs: HashMap<String, String>,
        text: String,
        object: Option<String>,
    }

    /// Every element in document order (the document must parse: malformed XML, a mismatched
    /// end tag or a bad attribute fails the test).
    fn elements(xml: &str) -> Vec<El> {
        let mut reader = Reader::from_str(xml);
        reader.config_mut().check_end_names = true;
        let (mut out, mut open, mut object) = (Vec::new(), Vec::<usize>::new(), None);
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
                if name == "Object" {
                    object = attrs.get("index").cloned();
                }
                let el = El {
                    object: (name == "SubObject").then(|| object.clone()).flatten(),
                    name,
                    attrs,
                    text: String::new(),
                };
                out.push(el);
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
        out
    }

    fn object<'a>(els: &'a [El], index: &str) -> Option<&'a El> {
        els.iter()
            .find(|e| e.name == "Object" && e.attrs.get("index").map(String::as_str) == Some(index))
    }

    fn sub<'a>(els: &'a [El], index: &str, sub: &str) -> Option<&'a El> {
        els.iter().find(|e| {
            e.name == "SubObject"
                && e.object.as_deref() == Some(index)
                && e.attrs.get("subIndex").map(String::as_str) == Some(sub)
        })
    }

    fn attr<'a>(e: &'a El, k: &str) -> &'a str {
        e.attrs.get(k).map_or("", String::as_str)
    }

    #[test]
    fn identity_and_mapping_of_the_sk550p() {
        let xml = xdd(Product::Sk550p, 8).unwrap();
        let els = elements(&xml);
        let texts = |n: &str| -> Vec<&str> {
            els.iter()
                .filter(|e| e.name == n)
                .map(|e| e.text.as_str())
                .collect()
        };
        assert_eq!(texts("vendorID"), ["0x000000ED", "0x000000ED"]);
        assert_eq!(texts("productName"), ["NORDAC PRO SK 550P"]);
        assert_eq!(texts("vendorName"), ["Getriebebau NORD GmbH & Co. KG"]);
        // 1018h: vendor, product code, revision as the IdentResponse reports them.
        let id = object(&els, "1018").expect("1018h");
        assert_eq!(attr(id, "objectType"), "9");
        let vendor = sub(&els, "1018", "01").unwrap();
        assert_eq!(
            (attr(vendor, "dataType"), attr(vendor, "accessType")),
            ("0007", "ro")
        );
        assert_eq!(attr(vendor, "defaultValue"), "0x000000ED");
        assert_eq!(attr(sub(&els, "1018", "00").unwrap(), "defaultValue"), "4");
        // 1600h/1A00h: 48 words each (§2.4.5); entry 2 maps 5000h.2 at bit 16, 16 bits.
        for m in ["1600", "1A00"] {
            let o = object(&els, m).expect(m);
            assert_eq!((attr(o, "objectType"), attr(o, "dataType")), ("8", "001B"));
            assert_eq!(attr(sub(&els, m, "00").unwrap(), "defaultValue"), "48");
            assert!(sub(&els, m, "30").is_some() && sub(&els, m, "31").is_none());
        }
        assert_eq!(
            attr(sub(&els, "1600", "02").unwrap(), "defaultValue"),
            "0x0010001000025000"
        );
        // Process data: 5000h.1 is FI 1's control word, mappable into the RPDO.
        let cw = sub(&els, "5000", "01").unwrap();
        assert_eq!(
            (attr(cw, "PDOmapping"), attr(cw, "dataType")),
            ("RPDO", "0006")
        );
        assert_eq!(attr(sub(&els, "5010", "01").unwrap(), "PDOmapping"), "TPDO");
        // BU 0620 §2.4.6 example: P102 of FI 5 at 3800h + 66h = 3866h, 4 sets.
        let p102 = object(&els, "3866").expect("3866h");
        assert!(attr(p102, "name").contains("P102"), "{p102:?}");
        assert_eq!(
            (attr(p102, "objectType"), attr(p102, "dataType")),
            ("8", "0003")
        );
        assert_eq!(attr(sub(&els, "3866", "00").unwrap(), "defaultValue"), "4");
        let set2 = sub(&els, "3866", "02").unwrap();
        assert_eq!(
            (attr(set2, "accessType"), attr(set2, "defaultValue")),
            ("rw", "200")
        );
        // The interface's P858 answers at FI 1 (2000h + 35Ah), bounded 400…2000 µs.
        let p858 = object(&els, "235A").expect("235Ah");
        assert_eq!(
            (attr(p858, "lowLimit"), attr(p858, "highLimit")),
            ("400", "2000")
        );
        // P717 (read-only) of FI 8 at 4A00h + 2CDh.
        assert_eq!(attr(object(&els, "4CCD").unwrap(), "accessType"), "ro");
        // Node objects and features.
        assert_eq!(
            attr(object(&els, "1F99").unwrap(), "defaultValue"),
            "5000000"
        );
        let general = els.iter().find(|e| e.name == "GeneralFeatures").unwrap();
        assert_eq!(
            (
                attr(general, "NMTCycleTimeMin"),
                attr(general, "NMTCycleTimeMax"),
                attr(general, "SDOSupportUdpIp"),
                attr(general, "SDOSupportASnd"),
            ),
            ("400", "2000", "true", "true")
        );
        assert!(els.iter().any(|e| e.name == "CNFeatures"));
        // Indices ascend and are unique; every data type used is declared.
        let idx: Vec<u16> = els
            .iter()
            .filter(|e| e.name == "Object")
            .map(|e| u16::from_str_radix(attr(e, "index"), 16).unwrap())
            .collect();
        assert!(idx.windows(2).all(|w| w[0] < w[1]));
        let declared: Vec<&str> = els
            .iter()
            .filter(|e| e.name == "defType")
            .map(|e| attr(e, "dataType"))
            .collect();
        for e in els
            .iter()
            .filter(|e| e.attrs.contains_key("dataType") && e.name != "defType")
        {
            assert!(declared.contains(&attr(e, "dataType")), "{e:?}");
        }
    }

    #[test]
    fn the_modules_have_their_own_table() {
        let xml = xdd(Product::Tu4Pol, 4).unwrap();
        let els = elements(&xml);
        // BU 2200 §6.4 example: P102 of FU1 at 2800h + 66h = 2866h.
        let p102 = object(&els, "2866").expect("2866h");
        assert!(attr(p102, "name").contains("P102"));
        // The module's own parameters at 2000h + P: P165 "POWERLINK Zyklus" at 20A5h.
        assert!(attr(object(&els, "20A5").unwrap(), "name").contains("P165"));
        // FU4 is the last (4000h + P); 50 bytes each way (BU 2200 §6.3.5).
        assert!(object(&els, "4066").is_some() && object(&els, "4866").is_none());
        assert_eq!(attr(sub(&els, "1A00", "00").unwrap(), "defaultValue"), "25");
        assert!(els
            .iter()
            .any(|e| e.name == "ProfileBody" && attr(e, "fileName") == "0xED_NORD_TU4_POL.xdd"));
        // Two inverters: FU3 has none.
        let two = elements(&xdd(Product::Tu4Pol, 2).unwrap());
        assert!(object(&two, "3066").is_some() && object(&two, "3866").is_none());
    }

    #[test]
    fn every_powerlink_product_is_described_and_others_refused() {
        for p in [
            Product::Sk550p,
            Product::Tu3Pol,
            Product::Tu4Pol,
            Product::Cu4Pol,
        ] {
            let els = elements(&xdd(p, p.max_inverters()).unwrap());
            assert!(object(&els, "1018").is_some(), "{p:?}");
            let code = format!("0x{:08X}", def::product_code(p));
            assert_eq!(attr(sub(&els, "1018", "02").unwrap(), "defaultValue"), code);
        }
        assert!(xdd(Product::Tu3Eip, 1)
            .unwrap_err()
            .to_string()
            .contains("no POWERLINK"));
        assert!(xdd(Product::Tu4Pol, 5).is_err());
        // The SK TU3-POL carries FU1..FU8 (BU 2200 §6.3.5), the parameter objects stop at FU4
        // (§6.4): 5000h…5003h stay the process-data objects, FU5's mapped there.
        let tu3 = elements(&xdd(Product::Tu3Pol, 8).unwrap());
        assert!(object(&tu3, "4066").is_some() && object(&tu3, "4866").is_none());
        assert!(attr(object(&tu3, "5000").unwrap(), "name").starts_with("PDO_"));
        assert!(attr(sub(&tu3, "5000", "05").unwrap(), "name").contains("FI 5 control word"));
        assert!(xdd(Product::Sk550p, 0).is_err());
    }
}
