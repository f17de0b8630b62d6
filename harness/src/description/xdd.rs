//! A POWERLINK XDD as the harness plans from it (EPSG DS 311): the identity in
//! `DeviceIdentity`, the feature flags of 1F82h and the process data the node's PDO mappings
//! (1600h receive, 1A00h transmit; DS 301 §6.4.9) give it.

use super::xml::{number, Element};
use super::{missing, DescriptionError, Identity};

/// What the harness takes from an XDD.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct Xdd {
    pub(crate) identity: Identity,
    /// NMT_FeatureFlags_U32 (1F82h) as declared: bit 1 SDO by UDP/IP, bit 2 SDO by ASnd.
    pub(crate) feature_flags: Option<u32>,
    /// Bytes the node's PReq payload maps (1600h), and its PRes payload (1A00h).
    pub(crate) preq_bytes: u16,
    pub(crate) pres_bytes: u16,
}

/// The value an object or sub-object declares: its actual value, else its default.
fn value(e: &Element) -> Option<u64> {
    e.attr("actualValue")
        .or_else(|| e.attr("defaultValue"))
        .and_then(number)
}

/// The object of that index (`index="1F82"`, hex without a prefix).
fn object<'a>(objects: &'a [&'a Element], index: u16) -> Option<&'a Element> {
    objects.iter().copied().find(|o| {
        o.attr("index")
            .and_then(|i| u16::from_str_radix(i, 16).ok())
            == Some(index)
    })
}

/// Bytes a mapping object maps: the end of its furthest entry among the first sub 0 of them
/// (each entry: length in bits 48–63, offset in bits 32–47).
fn mapped_bytes(o: Option<&Element>) -> u16 {
    let Some(o) = o else { return 0 };
    let subs: Vec<&Element> = o.children("SubObject").collect();
    let sub = |e: &&Element| {
        e.attr("subIndex")
            .and_then(|s| u8::from_str_radix(s, 16).ok())
    };
    let count = subs
        .iter()
        .find(|e| sub(e) == Some(0))
        .and_then(|e| value(e))
        .unwrap_or(0);
    let bits = subs
        .iter()
        .filter(|e| sub(e).is_some_and(|s| s >= 1 && u64::from(s) <= count))
        .filter_map(|e| value(e))
        .map(|m| ((m >> 32) & 0xFFFF) + (m >> 48))
        .max()
        .unwrap_or(0);
    bits.div_ceil(8) as u16
}

/// Reads an XDD's root element.
pub(crate) fn parse(root: &Element, file: &str) -> Result<Xdd, DescriptionError> {
    let id = root
        .find("DeviceIdentity")
        .ok_or_else(|| missing(file, "DeviceIdentity"))?;
    let text = |name: &str| id.child(name).map(|e| e.text.trim().to_string());
    let identity = Identity {
        vendor: text("vendorID")
            .as_deref()
            .and_then(number)
            .map(|v| v as u32),
        product: text("productID")
            .as_deref()
            .and_then(number)
            .map(|v| v as u32),
        revision: id
            .child("version")
            .map(|e| e.text.trim().to_string())
            .filter(|t| !t.is_empty()),
        name: text("productName"),
    };
    let objects = root.descendants("Object");
    Ok(Xdd {
        identity,
        feature_flags: object(&objects, 0x1F82).and_then(value).map(|v| v as u32),
        preq_bytes: mapped_bytes(object(&objects, 0x1600)),
        pres_bytes: mapped_bytes(object(&objects, 0x1A00)),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mappings_give_the_payload_sizes() {
        let text = r#"<ISO15745ProfileContainer><ISO15745Profile><ProfileBody>
            <DeviceIdentity><vendorID>0x000000ED</vendorID><productID>0x2203</productID><productName>X</productName></DeviceIdentity>
            </ProfileBody></ISO15745Profile><ISO15745Profile><ProfileBody><ApplicationLayers><ObjectList>
            <Object index="1F82" defaultValue="0x00000245"/>
            <Object index="1600"><SubObject subIndex="00" defaultValue="2"/>
              <SubObject subIndex="01" defaultValue="0x0010000000015000"/>
              <SubObject subIndex="02" defaultValue="0x0010001000015001"/>
              <SubObject subIndex="03" defaultValue="0x0010010000015002"/></Object>
            <Object index="1A00"><SubObject subIndex="00" defaultValue="0"/>
              <SubObject subIndex="01" defaultValue="0x0008000000016000"/></Object>
            </ObjectList></ApplicationLayers></ProfileBody></ISO15745Profile></ISO15745ProfileContainer>"#;
        let root = crate::description::xml::parse(text, "x").unwrap();
        let x = parse(&root, "x").unwrap();
        assert_eq!(x.identity.vendor, Some(0xED));
        assert_eq!(x.identity.product, Some(0x2203));
        assert_eq!(x.feature_flags, Some(0x245));
        // Two entries count: 16 bits at 0, 16 at 16 — 4 bytes; the third is beyond sub 0.
        assert_eq!(x.preq_bytes, 4);
        assert_eq!(x.pres_bytes, 0);
    }
}
