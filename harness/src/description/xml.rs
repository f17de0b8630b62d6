//! A small element tree of an XML description (ESI, XDD, GSDML): the readers look things up
//! by element and attribute names, namespace prefixes dropped.

use quick_xml::events::{BytesStart, Event};
use quick_xml::Reader;

use super::DescriptionError;

/// One element: its local name, attributes, text and children.
#[derive(Debug, Default, Clone)]
pub(crate) struct Element {
    pub(crate) name: String,
    attrs: Vec<(String, String)>,
    pub(crate) text: String,
    pub(crate) children: Vec<Element>,
}

impl Element {
    /// An attribute's value.
    pub(crate) fn attr(&self, name: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.as_str())
    }

    /// The first child of that name.
    pub(crate) fn child(&self, name: &str) -> Option<&Element> {
        self.children.iter().find(|c| c.name == name)
    }

    /// Every child of that name.
    pub(crate) fn children<'a>(&'a self, name: &'a str) -> impl Iterator<Item = &'a Element> {
        self.children.iter().filter(move |c| c.name == name)
    }

    /// Every element below this one (depth first) of that name.
    pub(crate) fn descendants<'a>(&'a self, name: &str) -> Vec<&'a Element> {
        let mut out = Vec::new();
        let mut stack: Vec<&Element> = self.children.iter().rev().collect();
        while let Some(e) = stack.pop() {
            if e.name == name {
                out.push(e);
            }
            stack.extend(e.children.iter().rev());
        }
        out
    }

    /// The first element below this one of that name.
    pub(crate) fn find<'a>(&'a self, name: &str) -> Option<&'a Element> {
        self.descendants(name).into_iter().next()
    }
}

/// The local part of a qualified name (`gsdml:DeviceIdentity` → `DeviceIdentity`).
fn local(name: &[u8]) -> String {
    let s = String::from_utf8_lossy(name);
    match s.rsplit_once(':') {
        Some((_, l)) => l.to_string(),
        None => s.into_owned(),
    }
}

fn element(e: &BytesStart<'_>, file: &str) -> Result<Element, DescriptionError> {
    let mut attrs = Vec::new();
    for a in e.attributes() {
        let a = a.map_err(|err| DescriptionError::Xml {
            file: file.to_string(),
            why: err.to_string(),
        })?;
        let v = a
            .normalized_value(quick_xml::XmlVersion::Explicit1_0)
            .map_err(|err| DescriptionError::Xml {
                file: file.to_string(),
                why: err.to_string(),
            })?;
        attrs.push((local(a.key.as_ref()), v.into_owned()));
    }
    Ok(Element {
        name: local(e.name().as_ref()),
        attrs,
        ..Element::default()
    })
}

/// The root element of `text`; malformed XML is an error naming the byte position.
pub(crate) fn parse(text: &str, file: &str) -> Result<Element, DescriptionError> {
    let mut reader = Reader::from_str(text);
    reader.config_mut().check_end_names = true;
    let bad = |reader: &Reader<&[u8]>, why: String| DescriptionError::Xml {
        file: file.to_string(),
        why: format!("at byte {}: {why}", reader.buffer_position()),
    };
    let mut open: Vec<Element> = Vec::new();
    loop {
        let ev = reader
            .read_event()
            .map_err(|e| bad(&reader, e.to_string()))?;
        match ev {
            Event::Start(e) => open.push(element(&e, file)?),
            Event::Empty(e) => {
                let el = element(&e, file)?;
                match open.last_mut() {
                    Some(parent) => parent.children.push(el),
                    None => return Ok(el),
                }
            }
            Event::Text(t) => {
                if let Some(el) = open.last_mut() {
                    let s = t.decode().map_err(|e| bad(&reader, e.to_string()))?;
                    el.text.push_str(&s);
                }
            }
            Event::End(_) => {
                let Some(el) = open.pop() else {
                    return Err(bad(&reader, "an end tag without a start".into()));
                };
                match open.last_mut() {
                    Some(parent) => parent.children.push(el),
                    None => return Ok(el),
                }
            }
            Event::Eof => return Err(bad(&reader, "no complete root element".into())),
            _ => {}
        }
    }
}

/// A number as descriptions write it: decimal, `0x…`, `#x…` (ESI) or `…h`.
pub(crate) fn number(s: &str) -> Option<u64> {
    let s = s.trim();
    if let Some(h) = s
        .strip_prefix("0x")
        .or_else(|| s.strip_prefix("0X"))
        .or_else(|| s.strip_prefix("#x"))
    {
        return u64::from_str_radix(h, 16).ok();
    }
    if let Some(h) = s.strip_suffix('h').or_else(|| s.strip_suffix('H')) {
        return u64::from_str_radix(h, 16).ok();
    }
    s.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn elements_nest_and_prefixes_go() {
        let root = parse(
            r#"<?xml version="1.0"?><a:Root x="1"><B y="2">t</B><B/><C><B z="3"/></C></a:Root>"#,
            "f",
        )
        .unwrap();
        assert_eq!(root.name, "Root");
        assert_eq!(root.attr("x"), Some("1"));
        assert_eq!(root.children("B").count(), 2);
        assert_eq!(root.child("B").unwrap().text, "t");
        assert_eq!(root.descendants("B").len(), 3);
        assert_eq!(
            root.find("C").unwrap().child("B").unwrap().attr("z"),
            Some("3")
        );
    }

    #[test]
    fn malformed_xml_is_an_error_with_a_position() {
        let e = parse("<a><b></a>", "dev.xml").unwrap_err().to_string();
        assert!(e.contains("dev.xml") && e.contains("at byte"), "{e}");
        assert!(parse("<a>", "f").is_err());
    }

    #[test]
    fn numbers_in_every_notation() {
        assert_eq!(number("0x1A"), Some(26));
        assert_eq!(number("#x0538"), Some(0x538));
        assert_eq!(number("1F98h"), Some(0x1F98));
        assert_eq!(number(" 12 "), Some(12));
        assert_eq!(number("x"), None);
    }
}
