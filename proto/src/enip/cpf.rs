//! The common packet format (CPF): an item count and typed, length-prefixed items.
//!
//! Explicit messages carry an address item (null for unconnected, connected address for
//! class 3) and a data item; class-1 I/O frames a sequenced address item and connected data;
//! Forward_Open replies may add socket-address items (the only big-endian structure in
//! EtherNet/IP).

use std::net::{Ipv4Addr, SocketAddrV4};

use super::wire::{len16, Put};
use crate::wire::{Error, Reader};

/// Item type ids.
pub mod item_type {
    /// Null address (unconnected messages).
    pub const NULL: u16 = 0x0000;
    /// ListIdentity reply item.
    pub const LIST_IDENTITY: u16 = 0x000C;
    /// Connected address (connection id).
    pub const CONNECTED_ADDRESS: u16 = 0x00A1;
    /// Connected data (class 3 explicit, class 1 I/O).
    pub const CONNECTED_DATA: u16 = 0x00B1;
    /// Unconnected data (UCMM).
    pub const UNCONNECTED_DATA: u16 = 0x00B2;
    /// ListServices reply item.
    pub const LIST_SERVICES: u16 = 0x0100;
    /// Socket address, originator → target.
    pub const SOCKADDR_O_T: u16 = 0x8000;
    /// Socket address, target → originator.
    pub const SOCKADDR_T_O: u16 = 0x8001;
    /// Sequenced address (connection id and sequence number).
    pub const SEQUENCED_ADDRESS: u16 = 0x8002;
}

/// One item.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Item {
    /// Null address.
    Null,
    /// Connected address.
    ConnectedAddress(u32),
    /// Sequenced address.
    SequencedAddress {
        /// Connection id.
        connection: u32,
        /// Encapsulation sequence number.
        sequence: u32,
    },
    /// Unconnected data: a message-router request or response.
    UnconnectedData(Vec<u8>),
    /// Connected data.
    ConnectedData(Vec<u8>),
    /// Socket address info, O→T.
    SockaddrOT(SocketAddrV4),
    /// Socket address info, T→O.
    SockaddrTO(SocketAddrV4),
    /// Any other item, kept as bytes.
    Other {
        /// Type id.
        type_id: u16,
        /// Data.
        data: Vec<u8>,
    },
}

fn sockaddr(data: &[u8]) -> Result<SocketAddrV4, Error> {
    if data.len() != 16 {
        return Err(Error::Length {
            field: "socket address item",
            value: data.len(),
            available: 16,
        });
    }
    let family = u16::from_be_bytes([data[0], data[1]]);
    if family != 2 {
        return Err(Error::Invalid {
            field: "socket address family",
            value: u32::from(family),
            why: "must be 2 (AF_INET)",
        });
    }
    let port = u16::from_be_bytes([data[2], data[3]]);
    let ip = Ipv4Addr::new(data[4], data[5], data[6], data[7]);
    Ok(SocketAddrV4::new(ip, port))
}

/// The 16 bytes of a socket-address item (big-endian, as `struct sockaddr_in`).
pub fn sockaddr_bytes(a: SocketAddrV4) -> Vec<u8> {
    let mut out = Vec::with_capacity(16);
    out.extend_from_slice(&2u16.to_be_bytes());
    out.extend_from_slice(&a.port().to_be_bytes());
    out.extend_from_slice(&a.ip().octets());
    out.extend_from_slice(&[0; 8]);
    out
}

impl Item {
    /// The item's type id.
    pub fn type_id(&self) -> u16 {
        match self {
            Item::Null => item_type::NULL,
            Item::ConnectedAddress(_) => item_type::CONNECTED_ADDRESS,
            Item::SequencedAddress { .. } => item_type::SEQUENCED_ADDRESS,
            Item::UnconnectedData(_) => item_type::UNCONNECTED_DATA,
            Item::ConnectedData(_) => item_type::CONNECTED_DATA,
            Item::SockaddrOT(_) => item_type::SOCKADDR_O_T,
            Item::SockaddrTO(_) => item_type::SOCKADDR_T_O,
            Item::Other { type_id, .. } => *type_id,
        }
    }

    fn parse(type_id: u16, data: &[u8]) -> Result<Item, Error> {
        let fixed = |n: usize, what: &'static str| {
            if data.len() == n {
                Ok(())
            } else {
                Err(Error::Length {
                    field: what,
                    value: data.len(),
                    available: n,
                })
            }
        };
        let mut r = Reader::new(data);
        Ok(match type_id {
            item_type::NULL => {
                fixed(0, "null address item")?;
                Item::Null
            }
            item_type::CONNECTED_ADDRESS => {
                fixed(4, "connected address item")?;
                Item::ConnectedAddress(r.u32("connection id")?)
            }
            item_type::SEQUENCED_ADDRESS => {
                fixed(8, "sequenced address item")?;
                Item::SequencedAddress {
                    connection: r.u32("connection id")?,
                    sequence: r.u32("sequence number")?,
                }
            }
            item_type::UNCONNECTED_DATA => Item::UnconnectedData(data.to_vec()),
            item_type::CONNECTED_DATA => Item::ConnectedData(data.to_vec()),
            item_type::SOCKADDR_O_T => Item::SockaddrOT(sockaddr(data)?),
            item_type::SOCKADDR_T_O => Item::SockaddrTO(sockaddr(data)?),
            type_id => Item::Other {
                type_id,
                data: data.to_vec(),
            },
        })
    }

    /// Appends the item's data to `out`.
    fn put_data(&self, out: &mut Vec<u8>) {
        match self {
            Item::Null => {}
            Item::ConnectedAddress(c) => out.put_u32(*c),
            Item::SequencedAddress {
                connection,
                sequence,
            } => {
                out.put_u32(*connection);
                out.put_u32(*sequence);
            }
            Item::UnconnectedData(d) | Item::ConnectedData(d) | Item::Other { data: d, .. } => {
                out.extend_from_slice(d)
            }
            Item::SockaddrOT(a) | Item::SockaddrTO(a) => out.extend(sockaddr_bytes(*a)),
        }
    }
}

/// A common packet format list.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Cpf {
    /// The items in order.
    pub items: Vec<Item>,
}

impl Cpf {
    /// A list of items.
    pub fn new(items: Vec<Item>) -> Cpf {
        Cpf { items }
    }

    /// Parses an item count and exactly that many items filling the buffer.
    pub fn parse(bytes: &[u8]) -> Result<Cpf, Error> {
        let mut r = Reader::new(bytes);
        let count = r.u16("CPF item count")?;
        let mut items = Vec::with_capacity(usize::from(count).min(8));
        for _ in 0..count {
            let type_id = r.u16("CPF item type")?;
            let len = usize::from(r.u16("CPF item length")?);
            let data = r.sized(len, "CPF item length")?;
            items.push(Item::parse(type_id, data)?);
        }
        r.finish("CPF item list")?;
        Ok(Cpf { items })
    }

    /// The bytes.
    pub fn emit(&self) -> Result<Vec<u8>, Error> {
        let mut out = Vec::with_capacity(64);
        self.emit_into(&mut out)?;
        Ok(out)
    }

    /// Appends the encoded list to `out`: one buffer for a whole message.
    pub fn emit_into(&self, out: &mut Vec<u8>) -> Result<(), Error> {
        out.put_u16(len16("CPF item count", self.items.len())?);
        for item in &self.items {
            out.put_u16(item.type_id());
            let at = out.len();
            out.put_u16(0);
            item.put_data(out);
            let len = len16("CPF item data", out.len() - at - 2)?;
            out[at..at + 2].copy_from_slice(&len.to_le_bytes());
        }
        Ok(())
    }

    /// The first item of `type_id`.
    pub fn find(&self, type_id: u16) -> Option<&Item> {
        self.items.iter().find(|i| i.type_id() == type_id)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    #[test]
    fn unconnected_request_items_round_trip() {
        let cpf = Cpf::new(vec![
            Item::Null,
            Item::UnconnectedData(vec![0x0E, 0x02, 0x20, 0x01, 0x24, 0x01]),
        ]);
        let b = cpf.emit().unwrap();
        assert_eq!(
            b,
            [2, 0, 0, 0, 0, 0, 0xB2, 0, 6, 0, 0x0E, 0x02, 0x20, 0x01, 0x24, 0x01]
        );
        assert_eq!(Cpf::parse(&b).unwrap(), cpf);
    }

    #[test]
    fn sockaddr_is_big_endian() {
        let a = SocketAddrV4::new(Ipv4Addr::new(192, 168, 1, 100), 2222);
        let cpf = Cpf::new(vec![Item::SockaddrTO(a)]);
        let b = cpf.emit().unwrap();
        assert_eq!(&b[6..14], &[0, 2, 0x08, 0xAE, 192, 168, 1, 100]);
        assert_eq!(Cpf::parse(&b).unwrap(), cpf);
    }

    #[test]
    fn bad_counts_and_lengths_are_errors() {
        // Two items announced, one present.
        assert!(matches!(
            Cpf::parse(&[2, 0, 0, 0, 0, 0]),
            Err(Error::Truncated { .. })
        ));
        // Item length beyond the buffer.
        assert!(matches!(
            Cpf::parse(&[1, 0, 0xB2, 0, 9, 0, 1, 2]),
            Err(Error::Length {
                value: 9,
                available: 2,
                ..
            })
        ));
        // A null address with data.
        assert!(matches!(
            Cpf::parse(&[1, 0, 0, 0, 1, 0, 7]),
            Err(Error::Length { .. })
        ));
        // Bytes after the last item.
        assert!(matches!(
            Cpf::parse(&[1, 0, 0, 0, 0, 0, 9]),
            Err(Error::Trailing { .. })
        ));
    }

    /// The strategies of a CPF, also for the encapsulation's properties that carry one.
    pub(crate) mod properties {
        use super::*;
        use proptest::collection::vec;
        use proptest::prelude::*;

        fn sockaddr() -> impl Strategy<Value = SocketAddrV4> {
            (any::<[u8; 4]>(), any::<u16>())
                .prop_map(|(ip, port)| SocketAddrV4::new(Ipv4Addr::from(ip), port))
        }

        const KNOWN: [u16; 7] = [
            item_type::NULL,
            item_type::CONNECTED_ADDRESS,
            item_type::SEQUENCED_ADDRESS,
            item_type::UNCONNECTED_DATA,
            item_type::CONNECTED_DATA,
            item_type::SOCKADDR_O_T,
            item_type::SOCKADDR_T_O,
        ];

        fn item() -> impl Strategy<Value = Item> {
            prop_oneof![
                Just(Item::Null),
                any::<u32>().prop_map(Item::ConnectedAddress),
                (any::<u32>(), any::<u32>()).prop_map(|(connection, sequence)| {
                    Item::SequencedAddress {
                        connection,
                        sequence,
                    }
                }),
                vec(any::<u8>(), 0..=32).prop_map(Item::UnconnectedData),
                vec(any::<u8>(), 0..=32).prop_map(Item::ConnectedData),
                sockaddr().prop_map(Item::SockaddrOT),
                sockaddr().prop_map(Item::SockaddrTO),
                // Types the codec does not interpret are kept as bytes.
                (
                    any::<u16>().prop_filter("interpreted type", |t| !KNOWN.contains(t)),
                    vec(any::<u8>(), 0..=32)
                )
                    .prop_map(|(type_id, data)| Item::Other { type_id, data }),
            ]
        }

        pub(crate) fn cpf() -> impl Strategy<Value = Cpf> {
            vec(item(), 0..5).prop_map(Cpf::new)
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn emit_then_parse_round_trips(c in cpf()) {
                let b = c.emit().unwrap();
                prop_assert_eq!(Cpf::parse(&b), Ok(c));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in vec(any::<u8>(), 0..48)) {
                let _ = Cpf::parse(&bytes);
            }

            #[test]
            fn parsing_arbitrary_items_never_panics(
                items in vec((prop_oneof![proptest::sample::select(KNOWN.to_vec()), any::<u16>()], vec(any::<u8>(), 0..20)), 0..4),
            ) {
                // Well-framed items of any type and content: only the item's own check may fail.
                let mut b = (items.len() as u16).to_le_bytes().to_vec();
                for (t, d) in &items {
                    b.extend(t.to_le_bytes());
                    b.extend((d.len() as u16).to_le_bytes());
                    b.extend(d);
                }
                let _ = Cpf::parse(&b);
            }
        }
    }
}
