//! An EtherNet/IP EDS as the harness plans from it (CIP Vol 1 ch. 7, "Electronic Data
//! Sheets"): the identity in `[Device]`, the assemblies' sizes in `[Assembly]`, and each
//! I/O connection of `[Connection Manager]`: its path (configuration instance, O→T and T→O
//! connection points), sizes and RPI range.

use std::collections::BTreeMap;

use super::xml::number;
use super::{DescriptionError, Identity};

/// One I/O connection the EDS declares: fields 1 trigger and transport, 2 connection
/// parameters, 3–5 O→T RPI, size, format, 6–8 the same T→O, 9–12 configuration sizes and
/// formats, 13 name, 14 help, 15 path.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Connection {
    /// Its name (`"Exclusive Owner"`).
    pub(crate) name: String,
    /// Transport type bits (24–27 of the first field): 1 listen only, 2 input only, 4
    /// exclusive owner, 8 redundant owner.
    pub(crate) transport_types: u8,
    /// The configuration instance (`24 xx` of the path).
    pub(crate) config: u16,
    /// O→T and T→O connection points (the path's two `2C xx`).
    pub(crate) o_t: u16,
    pub(crate) t_o: u16,
    /// Application data bytes each way (no sequence count, no run/idle header).
    pub(crate) o_t_size: u16,
    pub(crate) t_o_size: u16,
    /// The RPI range in µs, where the EDS gives one (a Param's minimum and maximum).
    pub(crate) rpi_us: Option<(u32, u32)>,
    /// O→T data carries the 32-bit run/idle header (real-time format 4, bits 8–10 of the
    /// second field).
    pub(crate) run_idle: bool,
}

/// What the harness takes from an EDS.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct Eds {
    pub(crate) identity: Identity,
    /// Assembly instance → data bytes.
    pub(crate) assemblies: BTreeMap<u16, u16>,
    pub(crate) connections: Vec<Connection>,
}

impl Eds {
    /// The connection an owner opens: the first exclusive-owner one, else the first.
    pub(crate) fn owner(&self) -> Option<&Connection> {
        self.connections
            .iter()
            .find(|c| c.transport_types & 0x4 != 0)
            .or(self.connections.first())
    }
}

/// Sections of entries of fields, comments gone.
type Sections = BTreeMap<String, BTreeMap<String, Vec<String>>>;

/// Splits the text into sections, entries (`Key = f1, f2, …;`) and fields; `$` starts a
/// comment outside quotes.
fn sections(text: &str) -> Sections {
    let mut clean = String::with_capacity(text.len());
    for line in text.lines() {
        let mut quoted = false;
        for c in line.chars() {
            match c {
                '"' => quoted = !quoted,
                '$' if !quoted => break,
                _ => {}
            }
            clean.push(c);
        }
        clean.push('\n');
    }
    let mut out = Sections::new();
    let mut section = String::new();
    let mut rest = clean.as_str();
    while let Some(start) = rest.find(|c: char| !c.is_whitespace()) {
        rest = &rest[start..];
        if let Some(tail) = rest.strip_prefix('[') {
            let end = tail.find(']').unwrap_or(tail.len());
            section = tail[..end].trim().to_string();
            out.entry(section.clone()).or_default();
            rest = tail.get(end + 1..).unwrap_or("");
            continue;
        }
        // An entry runs to the first `;` outside quotes.
        let mut quoted = false;
        let end = rest
            .char_indices()
            .find(|&(_, c)| {
                if c == '"' {
                    quoted = !quoted;
                }
                c == ';' && !quoted
            })
            .map_or(rest.len(), |(i, _)| i);
        let entry = &rest[..end];
        rest = rest.get(end + 1..).unwrap_or("");
        let Some((key, value)) = entry.split_once('=') else {
            continue;
        };
        let mut fields = Vec::new();
        let (mut field, mut quoted) = (String::new(), false);
        for c in value.chars() {
            match c {
                '"' => quoted = !quoted,
                ',' if !quoted => fields.push(std::mem::take(&mut field).trim().to_string()),
                _ => field.push(c),
            }
        }
        fields.push(field.trim().to_string());
        out.entry(section.clone())
            .or_default()
            .insert(key.trim().to_string(), fields);
    }
    out
}

/// Whether the text is an EDS: its first section is `[File]`.
pub(crate) fn is_eds(text: &str) -> bool {
    let first = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('$'));
    first.is_some_and(|l| l.eq_ignore_ascii_case("[File]"))
}

/// Reads an EDS.
pub(crate) fn parse(text: &str, file: &str) -> Result<Eds, DescriptionError> {
    let s = sections(text);
    let missing = |what: &str| DescriptionError::Missing {
        file: file.to_string(),
        what: what.to_string(),
    };
    let device = s.get("Device").ok_or_else(|| missing("[Device]"))?;
    let field = |key: &str| device.get(key).and_then(|f| f.first()).cloned();
    let int = |key: &str| field(key).as_deref().and_then(number);
    let identity = Identity {
        vendor: int("VendCode").map(|v| v as u32),
        product: int("ProdCode").map(|v| v as u32),
        revision: match (int("MajRev"), int("MinRev")) {
            (Some(a), Some(b)) => Some(format!("{a}.{b:03}")),
            _ => None,
        },
        name: field("ProdName"),
    };
    let params = s.get("Params").cloned().unwrap_or_default();
    let mut assemblies = BTreeMap::new();
    for (key, f) in s.get("Assembly").into_iter().flatten() {
        let (Some(n), Some(size)) = (
            key.strip_prefix("Assem")
                .and_then(|n| n.parse::<u16>().ok()),
            f.get(2).and_then(|v| number(v)),
        ) else {
            continue;
        };
        assemblies.insert(n, size as u16);
    }
    // A size field: a number, or empty and the format field's assembly gives it.
    let size = |size: &str, format: &str| -> Option<u16> {
        number(size).map(|v| v as u16).or_else(|| {
            let n: u16 = format.strip_prefix("Assem")?.parse().ok()?;
            assemblies.get(&n).copied()
        })
    };
    let rpi = |f: &str| -> Option<(u32, u32)> {
        let p = params.get(f)?;
        Some((number(p.get(9)?)? as u32, number(p.get(10)?)? as u32))
    };
    let mut connections = Vec::new();
    for (key, f) in s.get("Connection Manager").into_iter().flatten() {
        if !key.starts_with("Connection") || f.len() < 15 {
            continue;
        }
        let bad = |what: &str| DescriptionError::Bad {
            file: file.to_string(),
            what: format!("[Connection Manager] {key}: {what}"),
        };
        let transport = number(&f[0]).ok_or_else(|| bad("transport field"))?;
        let params = number(&f[1]).ok_or_else(|| bad("connection parameters field"))?;
        let path: Vec<u8> = f[14]
            .split_whitespace()
            .map(|b| u8::from_str_radix(b, 16))
            .collect::<Result<_, _>>()
            .map_err(|_| bad("path is not hex bytes"))?;
        // `20 04` class Assembly, `24 cc` configuration instance, `2C oo` `2C tt` points.
        let mut config = None;
        let mut points = Vec::new();
        for w in path.chunks(2) {
            match w {
                [0x24, v] => config = Some(u16::from(*v)),
                [0x2C, v] => points.push(u16::from(*v)),
                _ => {}
            }
        }
        let [o_t, t_o] = points[..] else {
            return Err(bad("the path names no two connection points"));
        };
        connections.push(Connection {
            name: f[12].clone(),
            transport_types: ((transport >> 24) & 0x0F) as u8,
            config: config.ok_or_else(|| bad("the path names no configuration instance"))?,
            o_t,
            t_o,
            o_t_size: size(&f[3], &f[4]).unwrap_or(0),
            t_o_size: size(&f[6], &f[7]).unwrap_or(0),
            rpi_us: rpi(&f[2]).or_else(|| rpi(&f[5])),
            run_idle: (params >> 8) & 0x7 == 4,
        });
    }
    Ok(Eds {
        identity,
        assemblies,
        connections,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const SAMPLE: &str = r#"$ a comment
[File]
        DescText = "x";
[Device]
        VendCode = 1;
        ProdCode = 65001;
        MajRev = 2;  MinRev = 3;
        ProdName = "OpENer; PC";
[Params]
        Param4 = 0, ,, 0x0000, 0xC8, 4, "RPI", "Microsecond", "", 10000, 3200000, 10000, ,,,, ,,,, ;
[Assembly]
        Assem100 = "Input", "", 32, 0x0000, ,, 8,Param1, 8,Param1;
        Assem150 = "Output", "", 32, 0x0001, ,, 8,Param2;
        Assem151 = "Config", "", 10, 0x0001, ,,;
[Connection Manager]
        Connection1 = 0x84010002, 0x44640405,
                Param4,,Assem150,   $ O->T
                Param4,,Assem100,
                ,, ,Assem151,
                "Exclusive Owner", "",
                "20 04 24 97 2C 96 2C 64";
        Connection2 = 0x02010002, 0x44640305, Param4,0,, Param4,32,Assem100, ,, 0,,
                "Input Only", "", "20 04 24 97 2C 98 2C 64";
"#;

    #[test]
    fn the_owner_connection_comes_from_the_path_and_the_assemblies() {
        assert!(is_eds(SAMPLE));
        let e = parse(SAMPLE, "s.eds").unwrap();
        assert_eq!(e.identity.vendor, Some(1));
        assert_eq!(e.identity.product, Some(65001));
        assert_eq!(e.identity.name.as_deref(), Some("OpENer; PC"));
        assert_eq!(e.identity.revision.as_deref(), Some("2.003"));
        assert_eq!(e.assemblies.get(&151), Some(&10));
        let c = e.owner().unwrap();
        assert_eq!((c.config, c.o_t, c.t_o), (0x97, 0x96, 0x64));
        assert_eq!((c.o_t_size, c.t_o_size), (32, 32));
        assert_eq!(c.rpi_us, Some((10_000, 3_200_000)));
        assert_eq!(c.name, "Exclusive Owner");
        assert!(c.run_idle);
        let input_only = &e.connections[1];
        assert_eq!((input_only.transport_types, input_only.o_t), (2, 0x98));
        assert_eq!((input_only.o_t_size, input_only.t_o_size), (0, 32));
    }

    #[test]
    fn a_connection_without_two_points_is_an_error_naming_it() {
        let text = SAMPLE.replace("2C 96 2C 64", "2C 96");
        let e = parse(&text, "s.eds").unwrap_err().to_string();
        assert!(
            e.contains("Connection1") && e.contains("two connection points"),
            "{e}"
        );
        assert!(!is_eds("<?xml version=\"1.0\"?>"));
    }
}
