//! I&M0, the identification record every PROFINET IO device answers (IEC 61158-6-10 "I&M0",
//! record index AFF0h at the DAP, slot 0 subslot 1). BU 0620 §2.5.3 lists "Identification &
//! Maintenance I&M for reading out device information" among the functions of every
//! conformance class.
//!
//! The record data is one block, big-endian:
//!
//! | offset | field |
//! |---|---|
//! | 0 | BlockType 0020h, BlockLength 56, BlockVersion 1.0 |
//! | 6 | VendorID (u16) |
//! | 8 | OrderID: 20 visible characters, space-padded |
//! | 28 | IM_Serial_Number: 16 visible characters, space-padded |
//! | 44 | IM_Hardware_Revision (u16) |
//! | 46 | IM_Software_Revision: a prefix letter (`V` version, `R` revision, `P` prototype, `U` under field test, `T` test device) and three bytes (functional enhancement, bug fix, internal change) |
//! | 50 | IM_Revision_Counter (u16) |
//! | 52 | IM_Profile_ID (u16) |
//! | 54 | IM_Profile_Specific_Type (u16) |
//! | 56 | IM_Version: major, minor (1.1) |
//! | 58 | IM_Supported (u16): bit n = I&Mn offered |

use super::block::{VERSION_HIGH, VERSION_LOW};
use crate::wire::{Error, Reader};

/// Record index of I&M0.
pub const INDEX: u16 = 0xAFF0;
/// BlockType of the I&M0 block.
pub const BLOCK_TYPE: u16 = 0x0020;
/// The whole record: block header and the fields.
pub const LEN: usize = 60;
/// OrderID characters.
const ORDER_ID_LEN: usize = 20;
/// IM_Serial_Number characters.
const SERIAL_LEN: usize = 16;

/// IM_Software_Revision.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SoftwareRevision {
    /// `V`, `R`, `P`, `U` or `T`.
    pub prefix: u8,
    /// Functional enhancement.
    pub functional: u8,
    /// Bug fix.
    pub bug_fix: u8,
    /// Internal change.
    pub internal: u8,
}

impl std::fmt::Display for SoftwareRevision {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}{}.{}.{}",
            char::from(self.prefix),
            self.functional,
            self.bug_fix,
            self.internal
        )
    }
}

/// The I&M0 record.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Im0Repr {
    /// VendorID.
    pub vendor_id: u16,
    /// OrderID, without the padding.
    pub order_id: String,
    /// IM_Serial_Number, without the padding.
    pub serial: String,
    /// IM_Hardware_Revision.
    pub hardware_revision: u16,
    /// IM_Software_Revision.
    pub software_revision: SoftwareRevision,
    /// IM_Revision_Counter.
    pub revision_counter: u16,
    /// IM_Profile_ID.
    pub profile_id: u16,
    /// IM_Profile_Specific_Type.
    pub profile_specific_type: u16,
    /// IM_Version (major, minor).
    pub version: (u8, u8),
    /// IM_Supported.
    pub supported: u16,
}

/// A visible string field: the text, space-padded to `len`; longer text or characters outside
/// 20h..7Eh do not fit.
fn visible(out: &mut Vec<u8>, text: &str, len: usize, what: &'static str) -> Result<(), Error> {
    if text.len() > len {
        return Err(Error::TooLong {
            what,
            len: text.len(),
            max: len,
        });
    }
    if let Some(b) = text.bytes().find(|b| !(0x20..=0x7E).contains(b)) {
        return Err(Error::Invalid {
            field: what,
            value: u32::from(b),
            why: "outside the visible characters 20h..7Eh",
        });
    }
    out.extend(text.bytes());
    out.resize(out.len() + len - text.len(), b' ');
    Ok(())
}

fn read_visible(r: &mut Reader<'_>, len: usize, what: &'static str) -> Result<String, Error> {
    let b = r.bytes(len, what)?;
    if let Some(c) = b.iter().find(|c| !(0x20..=0x7E).contains(*c)) {
        return Err(Error::Invalid {
            field: what,
            value: u32::from(*c),
            why: "outside the visible characters 20h..7Eh",
        });
    }
    Ok(String::from_utf8_lossy(b).trim_end().to_string())
}

impl Im0Repr {
    /// Parses the record data: exactly one I&M0 block.
    pub fn parse(data: &[u8]) -> Result<Im0Repr, Error> {
        let mut r = Reader::new(data);
        let block_type = r.u16_be("I&M0 BlockType")?;
        if block_type != BLOCK_TYPE {
            return Err(Error::Unknown {
                field: "I&M0 BlockType",
                value: u32::from(block_type),
            });
        }
        let length = usize::from(r.u16_be("I&M0 BlockLength")?);
        if length != LEN - 4 {
            return Err(Error::Length {
                field: "I&M0 BlockLength",
                value: length,
                available: LEN - 4,
            });
        }
        let version = (
            r.u8("I&M0 BlockVersionHigh")?,
            r.u8("I&M0 BlockVersionLow")?,
        );
        if version != (VERSION_HIGH, VERSION_LOW) {
            return Err(Error::Invalid {
                field: "I&M0 BlockVersion",
                value: u32::from(version.0) << 8 | u32::from(version.1),
                why: "the typed blocks are version 1.0",
            });
        }
        let im = Im0Repr {
            vendor_id: r.u16_be("VendorID")?,
            order_id: read_visible(&mut r, ORDER_ID_LEN, "OrderID")?,
            serial: read_visible(&mut r, SERIAL_LEN, "IM_Serial_Number")?,
            hardware_revision: r.u16_be("IM_Hardware_Revision")?,
            software_revision: SoftwareRevision {
                prefix: r.u8("IM_Software_Revision")?,
                functional: r.u8("IM_Software_Revision")?,
                bug_fix: r.u8("IM_Software_Revision")?,
                internal: r.u8("IM_Software_Revision")?,
            },
            revision_counter: r.u16_be("IM_Revision_Counter")?,
            profile_id: r.u16_be("IM_Profile_ID")?,
            profile_specific_type: r.u16_be("IM_Profile_Specific_Type")?,
            version: (r.u8("IM_Version")?, r.u8("IM_Version")?),
            supported: r.u16_be("IM_Supported")?,
        };
        r.finish("I&M0 record")?;
        Ok(im)
    }

    /// The record data.
    pub fn emit(&self) -> Result<Vec<u8>, Error> {
        let mut out = Vec::with_capacity(LEN);
        out.extend(BLOCK_TYPE.to_be_bytes());
        out.extend(((LEN - 4) as u16).to_be_bytes());
        out.extend([VERSION_HIGH, VERSION_LOW]);
        out.extend(self.vendor_id.to_be_bytes());
        visible(&mut out, &self.order_id, ORDER_ID_LEN, "OrderID")?;
        visible(&mut out, &self.serial, SERIAL_LEN, "IM_Serial_Number")?;
        out.extend(self.hardware_revision.to_be_bytes());
        let s = self.software_revision;
        out.extend([s.prefix, s.functional, s.bug_fix, s.internal]);
        for v in [
            self.revision_counter,
            self.profile_id,
            self.profile_specific_type,
        ] {
            out.extend(v.to_be_bytes());
        }
        out.extend([self.version.0, self.version.1]);
        out.extend(self.supported.to_be_bytes());
        debug_assert_eq!(out.len(), LEN);
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Im0Repr {
        Im0Repr {
            vendor_id: 0x0538,
            order_id: "275900190".into(),
            serial: "0590 0001".into(),
            hardware_revision: 1,
            software_revision: SoftwareRevision {
                prefix: b'V',
                functional: 1,
                bug_fix: 2,
                internal: 0,
            },
            revision_counter: 0,
            profile_id: 0,
            profile_specific_type: 0,
            version: (1, 1),
            supported: 0,
        }
    }

    #[test]
    fn round_trips_with_the_standard_layout() {
        let bytes = sample().emit().unwrap();
        assert_eq!(bytes.len(), 60);
        assert_eq!(&bytes[..8], &[0x00, 0x20, 0x00, 0x38, 1, 0, 0x05, 0x38]);
        assert_eq!(&bytes[8..28], b"275900190           ");
        assert_eq!(&bytes[46..50], &[b'V', 1, 2, 0]);
        assert_eq!(&bytes[56..58], &[1, 1]);
        assert_eq!(Im0Repr::parse(&bytes).unwrap(), sample());
        assert_eq!(sample().software_revision.to_string(), "V1.2.0");
    }

    #[test]
    fn malformed_records_are_errors_never_panics() {
        let good = sample().emit().unwrap();
        for n in 0..good.len() {
            assert!(Im0Repr::parse(&good[..n]).is_err(), "{n} bytes");
        }
        let mut long = good.clone();
        long.push(0);
        assert!(matches!(Im0Repr::parse(&long), Err(Error::Trailing { .. })));
        let mut wrong = good.clone();
        wrong[1] = 0x21;
        assert!(matches!(Im0Repr::parse(&wrong), Err(Error::Unknown { .. })));
        let mut control = good;
        control[10] = 0x07;
        assert!(matches!(
            Im0Repr::parse(&control),
            Err(Error::Invalid {
                field: "OrderID",
                ..
            })
        ));
        let too_long = Im0Repr {
            order_id: "x".repeat(21),
            ..sample()
        };
        assert!(matches!(too_long.emit(), Err(Error::TooLong { .. })));
    }

    mod properties {
        use super::*;
        use proptest::collection::vec;
        use proptest::prelude::*;

        /// Visible strings (20h..7Eh) that fit their field; the padding is trimmed on reading,
        /// so the text does not end in a space.
        fn im0() -> impl Strategy<Value = Im0Repr> {
            (
                any::<u16>(),
                "([ -~]{0,19}[!-~])?",
                "([ -~]{0,15}[!-~])?",
                any::<u16>(),
                any::<[u8; 4]>(),
                any::<(u16, u16, u16, u8, u8, u16)>(),
            )
                .prop_map(
                    |(vendor_id, order_id, serial, hardware_revision, sw, rest)| {
                        let (
                            revision_counter,
                            profile_id,
                            profile_specific_type,
                            major,
                            minor,
                            supported,
                        ) = rest;
                        Im0Repr {
                            vendor_id,
                            order_id,
                            serial,
                            hardware_revision,
                            software_revision: SoftwareRevision {
                                prefix: sw[0],
                                functional: sw[1],
                                bug_fix: sw[2],
                                internal: sw[3],
                            },
                            revision_counter,
                            profile_id,
                            profile_specific_type,
                            version: (major, minor),
                            supported,
                        }
                    },
                )
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn emit_then_parse_round_trips(im in im0()) {
                let b = im.emit().unwrap();
                prop_assert_eq!(b.len(), LEN);
                prop_assert_eq!(Im0Repr::parse(&b), Ok(im));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in vec(any::<u8>(), 0..64)) {
                let _ = Im0Repr::parse(&bytes);
            }

            #[test]
            fn parsing_an_arbitrary_body_never_panics(body in vec(any::<u8>(), LEN - 6)) {
                // A valid header over arbitrary field bytes (reaches the string checks).
                let mut b = BLOCK_TYPE.to_be_bytes().to_vec();
                b.extend(((LEN - 4) as u16).to_be_bytes());
                b.extend([VERSION_HIGH, VERSION_LOW]);
                b.extend(body);
                let _ = Im0Repr::parse(&b);
            }
        }
    }
}
