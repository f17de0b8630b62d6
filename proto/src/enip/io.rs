//! Class-1 I/O frames (UDP port 2222): a sequenced address item and connected data holding the
//! 16-bit sequence count, the optional 32-bit run/idle header and the application data.
//!
//! Whether the run/idle header is present is a property of the connection, not of the frame:
//! BU 2100 §7.1.2 P166 "PZD transmission format" — 0 = "32 Bit header + status", 1 = "Modeless
//! Format" (application data only).

use super::cpf::{item_type, Cpf, Item};
use super::wire::Put;
use crate::wire::{Error, Reader};

/// UDP port of class-1 I/O.
pub const IO_PORT: u16 = 2222;
/// UDP and TCP port of encapsulation messages.
pub const ENCAP_PORT: u16 = 44818;

/// One class-1 I/O frame.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct IoFrame {
    /// Connection id (the consumer's).
    pub connection: u32,
    /// Encapsulation sequence number (sequenced address item).
    pub sequence: u32,
    /// CIP sequence count (first two bytes of the connected data).
    pub count: u16,
    /// Run/idle header, when the connection has one (bit 0: 1 = run).
    pub run_idle: Option<u32>,
    /// Application data.
    pub data: Vec<u8>,
}

impl IoFrame {
    /// Parses a datagram; `run_idle` says whether the connection carries the 32-bit header.
    pub fn parse(bytes: &[u8], run_idle: bool) -> Result<IoFrame, Error> {
        let cpf = Cpf::parse(bytes)?;
        let (connection, sequence) = match cpf.items.first() {
            Some(Item::SequencedAddress {
                connection,
                sequence,
            }) => (*connection, *sequence),
            first => return Err(not_sequenced(first)),
        };
        let Some(Item::ConnectedData(payload)) = cpf.find(item_type::CONNECTED_DATA) else {
            return Err(Error::Missing {
                what: "I/O frame",
                part: "connected data item",
            });
        };
        let mut r = Reader::new(payload);
        let count = r.u16("I/O sequence count")?;
        let run_idle = if run_idle {
            Some(r.u32("run/idle header")?)
        } else {
            None
        };
        Ok(IoFrame {
            connection,
            sequence,
            count,
            run_idle,
            data: r.rest().to_vec(),
        })
    }

    /// The datagram.
    pub fn emit(&self) -> Result<Vec<u8>, Error> {
        let mut payload = Vec::with_capacity(6 + self.data.len());
        payload.put_u16(self.count);
        if let Some(h) = self.run_idle {
            payload.put_u32(h);
        }
        payload.extend_from_slice(&self.data);
        Cpf::new(vec![
            Item::SequencedAddress {
                connection: self.connection,
                sequence: self.sequence,
            },
            Item::ConnectedData(payload),
        ])
        .emit()
    }

    /// The connection id of a datagram, read without knowing the connection's format (to find
    /// the connection first).
    pub fn connection_of(bytes: &[u8]) -> Result<u32, Error> {
        match Cpf::parse(bytes)?.items.first() {
            Some(Item::SequencedAddress { connection, .. }) => Ok(*connection),
            first => Err(not_sequenced(first)),
        }
    }

    /// Whether the run/idle header says "run".
    pub fn is_run(&self) -> bool {
        self.run_idle.is_none_or(|h| h & 1 == 1)
    }
}

/// The error for an I/O frame whose first item is not the sequenced address item: the
/// connection id is read from there, so nothing else may come first.
fn not_sequenced(first: Option<&Item>) -> Error {
    match first {
        None => Error::Missing {
            what: "I/O frame",
            part: "sequenced address item",
        },
        Some(item) => Error::Invalid {
            field: "I/O frame first item type",
            value: u32::from(item.type_id()),
            why: "not the sequenced address item (8002h)",
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_with_and_without_run_idle_header() {
        let f = IoFrame {
            connection: 0x1000_0001,
            sequence: 5,
            count: 5,
            run_idle: Some(1),
            data: vec![0x7E, 0x04, 0, 0x20],
        };
        let b = f.emit().unwrap();
        assert_eq!(b.len(), 2 + 4 + 8 + 4 + 2 + 4 + 4);
        assert_eq!(IoFrame::parse(&b, true).unwrap(), f);
        assert_eq!(IoFrame::connection_of(&b).unwrap(), 0x1000_0001);
        // Read as modeless, the header becomes data: the connection decides.
        assert_eq!(IoFrame::parse(&b, false).unwrap().data.len(), 8);
        let idle = IoFrame {
            run_idle: Some(0),
            ..f
        };
        assert!(!idle.is_run());
    }

    #[test]
    fn frames_without_the_right_items_are_errors() {
        let b = Cpf::new(vec![Item::Null, Item::ConnectedData(vec![0, 0])])
            .emit()
            .unwrap();
        assert!(matches!(
            IoFrame::parse(&b, false),
            Err(Error::Invalid { value: 0, .. })
        ));
        let b = Cpf::new(vec![]).emit().unwrap();
        assert!(matches!(
            IoFrame::connection_of(&b),
            Err(Error::Missing {
                part: "sequenced address item",
                ..
            })
        ));
        let b = Cpf::new(vec![Item::SequencedAddress {
            connection: 1,
            sequence: 1,
        }])
        .emit()
        .unwrap();
        assert_eq!(
            IoFrame::parse(&b, false).unwrap_err().to_string(),
            "I/O frame: no connected data item"
        );
        let b = Cpf::new(vec![
            Item::SequencedAddress {
                connection: 1,
                sequence: 1,
            },
            Item::ConnectedData(vec![1, 0, 1]),
        ])
        .emit()
        .unwrap();
        assert!(matches!(
            IoFrame::parse(&b, true),
            Err(Error::Truncated { .. })
        ));
    }

    mod properties {
        use super::*;
        use proptest::collection::vec;
        use proptest::prelude::*;

        fn io_frame() -> impl Strategy<Value = IoFrame> {
            (
                any::<(u32, u32, u16)>(),
                proptest::option::of(any::<u32>()),
                vec(any::<u8>(), 0..=32),
            )
                .prop_map(|((connection, sequence, count), run_idle, data)| IoFrame {
                    connection,
                    sequence,
                    count,
                    run_idle,
                    data,
                })
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn emit_then_parse_round_trips(f in io_frame()) {
                let b = f.emit().unwrap();
                prop_assert_eq!(IoFrame::connection_of(&b), Ok(f.connection));
                prop_assert_eq!(IoFrame::parse(&b, f.run_idle.is_some()), Ok(f));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in vec(any::<u8>(), 0..48), run_idle in any::<bool>()) {
                let _ = IoFrame::parse(&bytes, run_idle);
                let _ = IoFrame::connection_of(&bytes);
            }
        }
    }
}
