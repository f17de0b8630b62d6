//! The emergency object (CiA 301 "Emergency object", EMCY; on CAN at 080h + node): the error
//! code, the error register (object 1001h) and 5 manufacturer-specific bytes. CoE carries the
//! same 8 bytes after its header (`ecat::coe` adds `parse_coe` / `emit_coe`).
//!
//! | bytes | field |
//! |---|---|
//! | 0–1 | emergency error code (u16; 0000h: error reset or no error) |
//! | 2 | error register (object 1001h, [`register`]) |
//! | 3–7 | manufacturer-specific error field |

use crate::wire::{Error, Reader};

/// Bits of the error register, object 1001h (CiA 301 "Error register").
pub mod register {
    /// Generic error (set whenever any error is present).
    pub const GENERIC: u8 = 0x01;
    /// Current.
    pub const CURRENT: u8 = 0x02;
    /// Voltage.
    pub const VOLTAGE: u8 = 0x04;
    /// Temperature.
    pub const TEMPERATURE: u8 = 0x08;
    /// Communication error (overrun, error state).
    pub const COMMUNICATION: u8 = 0x10;
    /// Device profile specific.
    pub const PROFILE: u8 = 0x20;
    /// Manufacturer-specific.
    pub const MANUFACTURER: u8 = 0x80;
}

/// An emergency message.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Emergency {
    /// Emergency error code (CiA 301 "Emergency error codes"; 0000h = error reset / no error).
    pub code: u16,
    /// Error register (object 1001h).
    pub register: u8,
    /// Manufacturer-specific error field.
    pub data: [u8; 5],
}

impl Emergency {
    /// Length of the message.
    pub const LEN: usize = 8;

    /// Parses at least 8 bytes; bytes after them are ignored (the padding of a CoE mailbox; a
    /// CAN frame has no more than 8).
    pub fn parse(bytes: &[u8]) -> Result<Emergency, Error> {
        let mut r = Reader::new(bytes);
        let b = r.bytes(Emergency::LEN, "emergency")?;
        Ok(Emergency::from_bytes([
            b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7],
        ]))
    }

    /// Reads the 8 bytes.
    pub fn from_bytes(b: [u8; 8]) -> Emergency {
        Emergency {
            code: u16::from_le_bytes([b[0], b[1]]),
            register: b[2],
            data: [b[3], b[4], b[5], b[6], b[7]],
        }
    }

    /// The 8 bytes.
    pub fn emit(&self) -> [u8; 8] {
        let c = self.code.to_le_bytes();
        let d = self.data;
        [c[0], c[1], self.register, d[0], d[1], d[2], d[3], d[4]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_truncation() {
        // 8130h (heartbeat error), register 11h (generic, communication), manufacturer 01..05.
        let b = [0x30, 0x81, 0x11, 1, 2, 3, 4, 5];
        let e = Emergency::parse(&b).unwrap();
        assert_eq!(
            e,
            Emergency {
                code: 0x8130,
                register: register::GENERIC | register::COMMUNICATION,
                data: [1, 2, 3, 4, 5]
            }
        );
        assert_eq!(e.emit(), b);
        for n in 0..8 {
            assert_eq!(
                Emergency::parse(&b[..n]),
                Err(Error::Truncated {
                    what: "emergency",
                    need: 8,
                    got: n
                })
            );
        }
    }

    mod properties {
        use super::*;
        use proptest::prelude::*;

        fn emergency() -> impl Strategy<Value = Emergency> {
            (any::<u16>(), any::<u8>(), any::<[u8; 5]>()).prop_map(|(code, register, data)| {
                Emergency {
                    code,
                    register,
                    data,
                }
            })
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn emit_then_parse_round_trips(e in emergency()) {
                let bytes = e.emit();
                prop_assert_eq!(bytes.len(), Emergency::LEN);
                prop_assert_eq!(Emergency::parse(&bytes), Ok(e));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..12)) {
                let _ = Emergency::parse(&bytes);
            }
        }
    }
}
