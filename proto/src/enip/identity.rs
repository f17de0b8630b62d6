//! The Identity object's attributes and the ListIdentity / ListServices reply items.

use std::net::SocketAddrV4;

use super::cpf::sockaddr_bytes;
use super::wire::Put;
use crate::wire::{Error, Reader};

/// What a device says about itself (Identity object, class 01h, instance 1).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Identity {
    /// Attribute 1: vendor id.
    pub vendor: u16,
    /// Attribute 2: device type.
    pub device_type: u16,
    /// Attribute 3: product code.
    pub product_code: u16,
    /// Attribute 4: revision, major.minor.
    pub revision: (u8, u8),
    /// Attribute 5: status word.
    pub status: u16,
    /// Attribute 6: serial number.
    pub serial: u32,
    /// Attribute 7: product name (SHORT_STRING, at most 32 characters).
    pub product_name: String,
    /// Attribute 8: state (3 = operational).
    pub state: u8,
}

/// A CIP SHORT_STRING: a length byte and the characters.
pub fn short_string(s: &str) -> Vec<u8> {
    let b = &s.as_bytes()[..s.len().min(255)];
    let mut out = Vec::with_capacity(1 + b.len());
    out.put_u8(b.len() as u8);
    out.extend_from_slice(b);
    out
}

fn read_short_string(r: &mut Reader<'_>) -> Result<String, Error> {
    let n = usize::from(r.u8("product name length")?);
    Ok(String::from_utf8_lossy(r.bytes(n, "product name")?).into_owned())
}

impl Identity {
    /// One attribute's value, if the attribute exists.
    pub fn attribute(&self, id: u16) -> Option<Vec<u8>> {
        let mut out = Vec::new();
        match id {
            1 => out.put_u16(self.vendor),
            2 => out.put_u16(self.device_type),
            3 => out.put_u16(self.product_code),
            4 => out.extend_from_slice(&[self.revision.0, self.revision.1]),
            5 => out.put_u16(self.status),
            6 => out.put_u32(self.serial),
            7 => out = short_string(&self.product_name),
            8 => out.put_u8(self.state),
            _ => return None,
        }
        Some(out)
    }

    /// Get_Attributes_All: attributes 1..7 in order.
    pub fn all(&self) -> Vec<u8> {
        (1..=7)
            .filter_map(|a| self.attribute(a))
            .flatten()
            .collect()
    }

    /// The ListIdentity reply item's data (item type 0Ch).
    pub fn list_identity_item(&self, addr: SocketAddrV4) -> Vec<u8> {
        let mut out = Vec::new();
        out.put_u16(1);
        out.extend(sockaddr_bytes(addr));
        out.extend(self.all());
        out.put_u8(self.state);
        out
    }

    /// Parses a ListIdentity item's data.
    pub fn parse_list_identity_item(data: &[u8]) -> Result<(Identity, SocketAddrV4), Error> {
        let mut r = Reader::new(data);
        let version = r.u16("encapsulation protocol version")?;
        if version != 1 {
            return Err(Error::Invalid {
                field: "ListIdentity protocol version",
                value: u32::from(version),
                why: "must be 1",
            });
        }
        let sa = r.bytes(16, "socket address")?;
        let addr = SocketAddrV4::new(
            std::net::Ipv4Addr::new(sa[4], sa[5], sa[6], sa[7]),
            u16::from_be_bytes([sa[2], sa[3]]),
        );
        let id = Identity {
            vendor: r.u16("vendor id")?,
            device_type: r.u16("device type")?,
            product_code: r.u16("product code")?,
            revision: (r.u8("major revision")?, r.u8("minor revision")?),
            status: r.u16("status")?,
            serial: r.u32("serial number")?,
            product_name: read_short_string(&mut r)?,
            state: r.u8("state")?,
        };
        r.finish("ListIdentity item")?;
        Ok((id, addr))
    }
}

/// The ListServices reply item's data (item type 0100h): version 1, capability flags
/// (bit 5 CIP over TCP, bit 8 class 0/1 over UDP), name "Communications".
pub fn list_services_item() -> Vec<u8> {
    let mut out = Vec::with_capacity(20);
    out.put_u16(1);
    out.put_u16(0x0120);
    let mut name = [0u8; 16];
    name[..14].copy_from_slice(b"Communications");
    out.extend_from_slice(&name);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::net::Ipv4Addr;

    #[test]
    fn list_identity_item_round_trips() {
        let id = Identity {
            vendor: 0x1234,
            device_type: 0x0C,
            product_code: 100,
            revision: (1, 3),
            status: 0x0030,
            serial: 0xDEAD_BEEF,
            product_name: "SK TU3-EIP".into(),
            state: 3,
        };
        let a = SocketAddrV4::new(Ipv4Addr::new(127, 0, 0, 1), 44818);
        let item = id.list_identity_item(a);
        assert_eq!(
            Identity::parse_list_identity_item(&item).unwrap(),
            (id.clone(), a)
        );
        assert_eq!(id.attribute(7).unwrap()[0], 10);
        assert_eq!(id.attribute(9), None);
        assert!(Identity::parse_list_identity_item(&item[..20]).is_err());
    }
}
