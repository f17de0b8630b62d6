//! Padded EPATHs: the addresses of CIP requests and connection paths.
//!
//! Logical segments address class, instance, attribute and connection point in 8-bit
//! (`20 cc`) or 16-bit (`21 00 cc cc`) form — NORD parameter numbers reach 999, so attributes
//! above 255 need the 16-bit form. Port segments route (Unconnected Send), electronic keys and
//! simple data segments appear in Forward_Open connection paths.

use std::fmt;

use super::wire::Put;
use crate::wire::{Error, Reader};

/// One path segment.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Segment {
    /// Class id.
    Class(u16),
    /// Instance id (8, 16 or 32 bit on the wire; NORD needs at most 16).
    Instance(u32),
    /// Attribute id.
    Attribute(u16),
    /// Connection point (an assembly instance in a connection path).
    ConnectionPoint(u16),
    /// Member id.
    Member(u16),
    /// Port segment: port and link address (e.g. backplane port 1, slot 0).
    Port {
        /// Port number.
        port: u16,
        /// Link address.
        link: Vec<u8>,
    },
    /// Electronic key (format 4).
    Key(ElectronicKey),
    /// Simple data segment (configuration data in a connection path).
    Data(Vec<u8>),
}

/// The electronic key of a connection path.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ElectronicKey {
    /// Vendor id (0 = any).
    pub vendor: u16,
    /// Device type (0 = any).
    pub device_type: u16,
    /// Product code (0 = any).
    pub product_code: u16,
    /// Major revision (bit 7: compatibility), 0 = any.
    pub major: u8,
    /// Minor revision, 0 = any.
    pub minor: u8,
}

/// A padded EPATH.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct EPath {
    /// Segments in order.
    pub segments: Vec<Segment>,
}

fn logical(out: &mut Vec<u8>, kind: u8, v: u32) {
    if v <= 0xFF {
        out.put_u8(0x20 | kind << 2);
        out.put_u8(v as u8);
    } else if v <= 0xFFFF {
        out.put_u8(0x21 | kind << 2);
        out.put_u8(0);
        out.put_u16(v as u16);
    } else {
        out.put_u8(0x22 | kind << 2);
        out.put_u8(0);
        out.put_u32(v);
    }
}

fn narrow(v: u32, what: &'static str) -> Result<u16, Error> {
    u16::try_from(v).map_err(|_| Error::Invalid {
        field: what,
        value: v,
        why: "a 32-bit value where 16 bits are allowed",
    })
}

impl EPath {
    /// Class, instance and attribute (an attribute request).
    pub fn attribute(class: u16, instance: u32, attribute: u16) -> EPath {
        EPath {
            segments: vec![
                Segment::Class(class),
                Segment::Instance(instance),
                Segment::Attribute(attribute),
            ],
        }
    }

    /// Class and instance (a service on an object).
    pub fn object(class: u16, instance: u32) -> EPath {
        EPath {
            segments: vec![Segment::Class(class), Segment::Instance(instance)],
        }
    }

    /// The connection path of an I/O connection to assembly connection points `o_t` and
    /// `t_o`: Assembly class, configuration instance 1 (no configuration data), the two
    /// points (`20 04 24 01 2C o_t 2C t_o`).
    pub fn io_connection(o_t: u16, t_o: u16) -> EPath {
        EPath::io_connection_configured(1, o_t, t_o)
    }

    /// The same with configuration instance `config` (`20 04 24 config 2C o_t 2C t_o`): an
    /// adapter may name its own in its EDS connection path.
    pub fn io_connection_configured(config: u16, o_t: u16, t_o: u16) -> EPath {
        EPath {
            segments: vec![
                Segment::Class(crate::enip::cip::class::ASSEMBLY),
                Segment::Instance(u32::from(config)),
                Segment::ConnectionPoint(o_t),
                Segment::ConnectionPoint(t_o),
            ],
        }
    }

    /// Parses a padded path filling `bytes`.
    pub fn parse(bytes: &[u8]) -> Result<EPath, Error> {
        let mut r = Reader::new(bytes);
        let mut segments = Vec::new();
        while r.remaining() > 0 {
            segments.push(Self::segment(&mut r)?);
        }
        Ok(EPath { segments })
    }

    fn segment(r: &mut Reader<'_>) -> Result<Segment, Error> {
        let t = r.u8("path segment type")?;
        match t >> 5 {
            0 => {
                let extended = t & 0x10 != 0;
                let mut port = u16::from(t & 0x0F);
                let link = if extended {
                    let n = usize::from(r.u8("port segment link address size")?);
                    if port == 15 {
                        port = r.u16("extended port")?;
                    }
                    let link = r.bytes(n, "port segment link address")?.to_vec();
                    if n % 2 == 1 {
                        r.u8("port segment pad")?;
                    }
                    link
                } else {
                    if port == 15 {
                        port = r.u16("extended port")?;
                    }
                    vec![r.u8("port segment link address")?]
                };
                if port == 0 {
                    return Err(Error::Invalid {
                        field: "port segment port",
                        value: 0,
                        why: "port 0 is reserved",
                    });
                }
                Ok(Segment::Port { port, link })
            }
            1 => {
                let kind = (t >> 2) & 0x07;
                let format = t & 0x03;
                if kind == 5 {
                    // Special: electronic key.
                    if t != 0x34 {
                        return Err(Error::Invalid {
                            field: "logical segment",
                            value: u32::from(t),
                            why: "a special segment other than the electronic key (34h)",
                        });
                    }
                    let fmt = r.u8("electronic key format")?;
                    if fmt != 4 {
                        return Err(Error::Invalid {
                            field: "electronic key format",
                            value: u32::from(fmt),
                            why: "only format 4 exists",
                        });
                    }
                    return Ok(Segment::Key(ElectronicKey {
                        vendor: r.u16("key vendor id")?,
                        device_type: r.u16("key device type")?,
                        product_code: r.u16("key product code")?,
                        major: r.u8("key major revision")?,
                        minor: r.u8("key minor revision")?,
                    }));
                }
                let value = match format {
                    0 => u32::from(r.u8("logical segment value")?),
                    1 => {
                        r.u8("logical segment pad")?;
                        u32::from(r.u16("logical segment value")?)
                    }
                    2 => {
                        r.u8("logical segment pad")?;
                        r.u32("logical segment value")?
                    }
                    _ => {
                        return Err(Error::Invalid {
                            field: "logical segment format",
                            value: u32::from(t),
                            why: "the reserved format 3",
                        })
                    }
                };
                match kind {
                    0 => Ok(Segment::Class(narrow(value, "class segment")?)),
                    1 => Ok(Segment::Instance(value)),
                    2 => Ok(Segment::Member(narrow(value, "member segment")?)),
                    3 => Ok(Segment::ConnectionPoint(narrow(
                        value,
                        "connection point segment",
                    )?)),
                    4 => Ok(Segment::Attribute(narrow(value, "attribute segment")?)),
                    _ => Err(Error::Invalid {
                        field: "logical segment type",
                        value: u32::from(t),
                        why: "not a class, instance, member, connection point or attribute",
                    }),
                }
            }
            4 if t == 0x80 => {
                let words = usize::from(r.u8("data segment size")?);
                Ok(Segment::Data(r.bytes(words * 2, "data segment")?.to_vec()))
            }
            _ => Err(Error::Invalid {
                field: "path segment type",
                value: u32::from(t),
                why: "not a port, logical or data segment",
            }),
        }
    }

    /// The padded bytes (always an even count).
    pub fn emit(&self) -> Vec<u8> {
        let mut out = Vec::new();
        for s in &self.segments {
            match s {
                Segment::Class(v) => logical(&mut out, 0, u32::from(*v)),
                Segment::Instance(v) => logical(&mut out, 1, *v),
                Segment::Member(v) => logical(&mut out, 2, u32::from(*v)),
                Segment::ConnectionPoint(v) => logical(&mut out, 3, u32::from(*v)),
                Segment::Attribute(v) => logical(&mut out, 4, u32::from(*v)),
                Segment::Port { port, link } => {
                    let extended = link.len() != 1;
                    let id = if *port >= 15 { 15 } else { *port as u8 };
                    out.put_u8(id | if extended { 0x10 } else { 0 });
                    if extended {
                        out.put_u8(link.len() as u8);
                    }
                    if *port >= 15 {
                        out.put_u16(*port);
                    }
                    out.extend_from_slice(link);
                    if out.len() % 2 == 1 {
                        out.put_u8(0);
                    }
                }
                Segment::Key(k) => {
                    out.extend_from_slice(&[0x34, 4]);
                    out.put_u16(k.vendor);
                    out.put_u16(k.device_type);
                    out.put_u16(k.product_code);
                    out.put_u8(k.major);
                    out.put_u8(k.minor);
                }
                Segment::Data(d) => {
                    out.put_u8(0x80);
                    out.put_u8((d.len() / 2) as u8);
                    out.extend_from_slice(d);
                }
            }
        }
        out
    }

    /// Size in 16-bit words, as the path size fields count it.
    pub fn words(&self) -> usize {
        self.emit().len() / 2
    }

    /// The class segment, if any.
    pub fn class_id(&self) -> Option<u16> {
        self.segments.iter().find_map(|s| match s {
            Segment::Class(c) => Some(*c),
            _ => None,
        })
    }

    /// The instance segment, if any.
    pub fn instance_id(&self) -> Option<u32> {
        self.segments.iter().find_map(|s| match s {
            Segment::Instance(c) => Some(*c),
            _ => None,
        })
    }

    /// The attribute segment, if any.
    pub fn attribute_id(&self) -> Option<u16> {
        self.segments.iter().find_map(|s| match s {
            Segment::Attribute(c) => Some(*c),
            _ => None,
        })
    }

    /// The connection points in order (a connection path: O→T, then T→O; or config first).
    pub fn connection_points(&self) -> Vec<u16> {
        self.segments
            .iter()
            .filter_map(|s| match s {
                Segment::ConnectionPoint(c) => Some(*c),
                _ => None,
            })
            .collect()
    }
}

impl fmt::Display for EPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, s) in self.segments.iter().enumerate() {
            if i > 0 {
                f.write_str(" / ")?;
            }
            match s {
                Segment::Class(v) => write!(f, "class {v}")?,
                Segment::Instance(v) => write!(f, "instance {v}")?,
                Segment::Attribute(v) => write!(f, "attribute {v}")?,
                Segment::ConnectionPoint(v) => write!(f, "connection point {v}")?,
                Segment::Member(v) => write!(f, "member {v}")?,
                Segment::Port { port, link } => write!(f, "port {port} link {link:02X?}")?,
                Segment::Key(k) => write!(
                    f,
                    "key vendor {} type {} product {} rev {}.{}",
                    k.vendor,
                    k.device_type,
                    k.product_code,
                    k.major & 0x7F,
                    k.minor
                )?,
                Segment::Data(d) => write!(f, "data {} bytes", d.len())?,
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    #[rstest]
    // Identity object, instance 1, attribute 7 (product name).
    #[case(EPath::attribute(1, 1, 7), &[0x20, 0x01, 0x24, 0x01, 0x30, 0x07])]
    // FI 3, P465 [-02]: class 103, instance 1, attribute 465 (BU 2100 §6.3 example).
    #[case(EPath::attribute(103, 1, 465), &[0x20, 103, 0x24, 0x01, 0x31, 0x00, 0xD1, 0x01])]
    // FI 2, P400 [-03] set 3: instance 14, attribute 400.
    #[case(EPath::attribute(102, 14, 400), &[0x20, 102, 0x24, 14, 0x31, 0x00, 0x90, 0x01])]
    // Instance 0 (parameter set 1) is a legal 8-bit instance.
    #[case(EPath::attribute(101, 0, 102), &[0x20, 101, 0x24, 0x00, 0x30, 102])]
    fn logical_paths(#[case] path: EPath, #[case] bytes: &[u8]) {
        assert_eq!(path.emit(), bytes);
        assert_eq!(EPath::parse(bytes).unwrap(), path);
        assert_eq!(path.words() * 2, bytes.len());
    }

    #[test]
    fn connection_path_with_key_and_ports() {
        let p = EPath {
            segments: vec![
                Segment::Port {
                    port: 1,
                    link: vec![0],
                },
                Segment::Key(ElectronicKey {
                    vendor: 0,
                    device_type: 0,
                    product_code: 0,
                    major: 0,
                    minor: 0,
                }),
                Segment::Class(4),
                Segment::Instance(1),
                Segment::ConnectionPoint(100),
                Segment::ConnectionPoint(101),
            ],
        };
        let b = p.emit();
        assert_eq!(b.len() % 2, 0);
        assert_eq!(EPath::parse(&b).unwrap(), p);
        assert_eq!(p.connection_points(), [100, 101]);
    }

    #[rstest]
    #[case(&[0x20])] // class without value
    #[case(&[0x21, 0x00, 0x65])] // 16-bit class cut short
    #[case(&[0x23, 0x00])] // reserved logical format
    #[case(&[0x38, 0x01])] // logical type 6
    #[case(&[0x34, 0x05, 0, 0])] // key format 5
    #[case(&[0xE0, 0x01])] // reserved segment type
    #[case(&[0x00, 0x01])] // port 0
    #[case(&[0x22, 0x00, 0, 0, 1, 0])] // 32-bit class value
    fn malformed_paths_are_errors(#[case] bytes: &[u8]) {
        assert!(EPath::parse(bytes).is_err(), "{bytes:02X?}");
    }

    mod properties {
        use super::*;
        use proptest::collection::vec;
        use proptest::prelude::*;

        /// Segments the codec carries: port 1.. (0 is reserved) with a link address of at most
        /// 255 bytes (its size is one byte), data segments of whole words (at most 255).
        fn segment() -> impl Strategy<Value = Segment> {
            prop_oneof![
                any::<u16>().prop_map(Segment::Class),
                prop_oneof![0u32..=0xFF, 0u32..=0xFFFF, any::<u32>()].prop_map(Segment::Instance),
                any::<u16>().prop_map(Segment::Attribute),
                any::<u16>().prop_map(Segment::ConnectionPoint),
                any::<u16>().prop_map(Segment::Member),
                (
                    prop_oneof![1u16..=16, 1u16..=u16::MAX],
                    vec(any::<u8>(), 0..=8)
                )
                    .prop_map(|(port, link)| Segment::Port { port, link }),
                (
                    any::<u16>(),
                    any::<u16>(),
                    any::<u16>(),
                    any::<u8>(),
                    any::<u8>()
                )
                    .prop_map(
                        |(vendor, device_type, product_code, major, minor)| {
                            Segment::Key(ElectronicKey {
                                vendor,
                                device_type,
                                product_code,
                                major,
                                minor,
                            })
                        }
                    ),
                vec(any::<[u8; 2]>(), 0..=8).prop_map(|words| Segment::Data(words.concat())),
            ]
        }

        fn epath() -> impl Strategy<Value = EPath> {
            vec(segment(), 0..6).prop_map(|segments| EPath { segments })
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn emit_then_parse_round_trips(p in epath()) {
                let b = p.emit();
                prop_assert_eq!(b.len() % 2, 0, "a padded path has whole words");
                prop_assert_eq!(p.words() * 2, b.len());
                prop_assert_eq!(EPath::parse(&b), Ok(p));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in vec(any::<u8>(), 0..32)) {
                let _ = EPath::parse(&bytes);
            }
        }
    }
}
