//! `harness describe esi`: the EtherCAT Slave Information file (ETG.2000) of the SK 550P's
//! integrated EtherCAT interface, written from `proto::nord::ecat` — the same data the
//! simulated slave builds its SII EEPROM, SyncManagers, PDOs and CoE dictionary from, so a
//! master configured from this file finds the device it describes (BU 0620 §3.4, §3.6.1:
//! vendor ID, product code and revision identify it in a bus scan).

use proto::nord::ecat::{self as def, EntryAccess, Object, Pdo, SmRole, Value};
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
                w.create_element("Dictionary").write_inner_content(|w| {
                    w.create_element("Objects").write_inner_content(|w| {
                        for o in def::object_dictionary(inverters) {
                            object(w, &o)?;
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

fn object(w: &mut W, o: &Object) -> std::io::Result<()> {
    w.create_element("Object").write_inner_content(|w| {
        text(w, "Index", &hex(u32::from(o.index), 4))?;
        text(w, "Name", &o.name)?;
        let first = o.entries.first();
        let bits: u16 = o.entries.iter().map(|e| e.data_type.bits()).sum();
        match (o.code, first) {
            (def::ObjectCode::Var, Some(e)) => text(w, "Type", &e.data_type.esi_name())?,
            _ => text(w, "Type", &format!("DT{:04X}", o.index))?,
        }
        text(w, "BitSize", &bits.to_string())?;
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
    w.create_element("Flags").write_inner_content(|w| {
        text(
            w,
            "Access",
            match access {
                EntryAccess::Ro => "ro",
                EntryAccess::Rw => "rw",
            },
        )
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
