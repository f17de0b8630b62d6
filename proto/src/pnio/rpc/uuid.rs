//! UUIDs as DCE/RPC and PNIO carry them (C706 appendix A), and the PNIO interface and object
//! UUIDs (IEC 61158-6-10).

use std::fmt;
use std::str::FromStr;

use crate::wire::{Error, Reader};

/// A UUID (C706 appendix A) held in canonical order: the 16 bytes as the 8-4-4-4-12 text
/// reads them, i.e. time_low, time_mid and time_hi_and_version big-endian. On the wire of
/// DCE/RPC the first three fields follow the drep ([`Uuid::from_wire`], [`Uuid::to_wire`]); in
/// PNIO blocks they are big-endian, which is the canonical order.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct Uuid(pub [u8; 16]);

impl Uuid {
    /// The nil UUID (all zero): the ARUUID of an implicit read, "no AR".
    pub const NIL: Uuid = Uuid([0; 16]);

    /// IO device interface, the one an IO controller calls Connect, Read, Write, Control and
    /// Release on (IEC 61158-6-10 "PNIO interface UUIDs").
    pub const PNIO_DEVICE_INTERFACE: Uuid = Uuid::pnio_interface(1);
    /// IO controller interface, the one a device calls ApplicationReady on.
    pub const PNIO_CONTROLLER_INTERFACE: Uuid = Uuid::pnio_interface(2);
    /// IO supervisor interface.
    pub const PNIO_SUPERVISOR_INTERFACE: Uuid = Uuid::pnio_interface(3);
    /// Parameter server interface.
    pub const PNIO_PARAMETER_SERVER_INTERFACE: Uuid = Uuid::pnio_interface(4);
    /// The endpoint mapper (C706 appendix O: E1AF8308-5D1F-11C9-91A4-08002B14A0FA).
    pub const EPM_INTERFACE: Uuid = Uuid::from_fields(
        0xE1AF_8308,
        0x5D1F,
        0x11C9,
        [0x91, 0xA4, 0x08, 0x00, 0x2B, 0x14, 0xA0, 0xFA],
    );
    /// The NDR transfer syntax (8A885D04-1CEB-11C9-9FE8-08002B104860).
    pub const NDR_TRANSFER_SYNTAX: Uuid = Uuid::from_fields(
        0x8A88_5D04,
        0x1CEB,
        0x11C9,
        [0x9F, 0xE8, 0x08, 0x00, 0x2B, 0x10, 0x48, 0x60],
    );

    /// The first 10 bytes every PNIO object UUID shares: DEA00000-6C97-11D1-8271.
    const PNIO_OBJECT_PREFIX: [u8; 10] =
        [0xDE, 0xA0, 0x00, 0x00, 0x6C, 0x97, 0x11, 0xD1, 0x82, 0x71];

    /// A UUID unique to one sender and one of its calls, as a device or controller makes its
    /// activity and AR UUIDs: `tag` and `mid` in time_low and time_mid, version 1, the
    /// sender's MAC address and the call's number `n` in the node bytes.
    pub const fn of_sender(tag: u32, mid: u16, mac: crate::eth::MacAddr, n: u16) -> Uuid {
        let m = mac.0;
        let c = n.to_be_bytes();
        Uuid::from_fields(
            tag,
            mid,
            0x1000,
            [m[0], m[1], m[2], m[3], m[4], m[5], c[0], c[1]],
        )
    }

    /// A UUID from its fields: time_low, time_mid, time_hi_and_version and the 8 bytes of
    /// clock_seq and node.
    pub const fn from_fields(time_low: u32, time_mid: u16, time_hi: u16, rest: [u8; 8]) -> Uuid {
        let a = time_low.to_be_bytes();
        let b = time_mid.to_be_bytes();
        let c = time_hi.to_be_bytes();
        Uuid([
            a[0], a[1], a[2], a[3], b[0], b[1], c[0], c[1], rest[0], rest[1], rest[2], rest[3],
            rest[4], rest[5], rest[6], rest[7],
        ])
    }

    /// DEA0000n-6C97-11D1-8271-00A02442DF7D.
    const fn pnio_interface(n: u8) -> Uuid {
        Uuid::from_fields(
            0xDEA0_0000 | n as u32,
            0x6C97,
            0x11D1,
            [0x82, 0x71, 0x00, 0xA0, 0x24, 0x42, 0xDF, 0x7D],
        )
    }

    /// The object UUID of a PNIO device or controller instance (IEC 61158-6-10 "PNIO object
    /// UUID"): DEA00000-6C97-11D1-8271-IIII-DDDD-VVVV with the instance, the device id and the
    /// vendor id big-endian in the node bytes (as Wireshark's packet-dcerpc-pn-io.c and p-net's
    /// endpoint mapper lay them out).
    pub const fn pnio_object(instance: u16, device_id: u16, vendor_id: u16) -> Uuid {
        let p = Uuid::PNIO_OBJECT_PREFIX;
        let i = instance.to_be_bytes();
        let d = device_id.to_be_bytes();
        let v = vendor_id.to_be_bytes();
        Uuid([
            p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8], p[9], i[0], i[1], d[0], d[1],
            v[0], v[1],
        ])
    }

    /// (instance, device id, vendor id) if this is a PNIO object UUID.
    pub fn pnio_object_parts(&self) -> Option<(u16, u16, u16)> {
        let b = &self.0;
        if b[..10] != Uuid::PNIO_OBJECT_PREFIX {
            return None;
        }
        let be = |i: usize| u16::from_be_bytes([b[i], b[i + 1]]);
        Some((be(10), be(12), be(14)))
    }

    /// Whether it is one of the four PNIO interfaces.
    pub fn is_pnio_interface(&self) -> bool {
        [
            Uuid::PNIO_DEVICE_INTERFACE,
            Uuid::PNIO_CONTROLLER_INTERFACE,
            Uuid::PNIO_SUPERVISOR_INTERFACE,
            Uuid::PNIO_PARAMETER_SERVER_INTERFACE,
        ]
        .contains(self)
    }

    /// Whether it is the nil UUID.
    pub fn is_nil(&self) -> bool {
        *self == Uuid::NIL
    }

    /// From 16 wire bytes whose first three fields are little-endian (`little_endian`) or
    /// big-endian.
    pub fn from_wire(b: [u8; 16], little_endian: bool) -> Uuid {
        let mut u = b;
        if little_endian {
            u[..4].reverse();
            u[4..6].reverse();
            u[6..8].reverse();
        }
        Uuid(u)
    }

    /// The 16 wire bytes in that byte order (the inverse of [`Uuid::from_wire`]).
    pub fn to_wire(&self, little_endian: bool) -> [u8; 16] {
        // The swap is its own inverse.
        Uuid::from_wire(self.0, little_endian).0
    }

    pub(super) fn read(
        r: &mut Reader<'_>,
        little_endian: bool,
        what: &'static str,
    ) -> Result<Uuid, Error> {
        let mut b = [0u8; 16];
        b.copy_from_slice(r.bytes(16, what)?);
        Ok(Uuid::from_wire(b, little_endian))
    }
}

impl fmt::Display for Uuid {
    /// The 8-4-4-4-12 form, lower case (dea00001-6c97-11d1-8271-00a02442df7d).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, byte) in self.0.iter().enumerate() {
            if matches!(i, 4 | 6 | 8 | 10) {
                f.write_str("-")?;
            }
            write!(f, "{byte:02x}")?;
        }
        Ok(())
    }
}

impl fmt::Debug for Uuid {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Uuid({self})")
    }
}

impl FromStr for Uuid {
    type Err = Error;

    /// Parses the 8-4-4-4-12 form (any case).
    fn from_str(s: &str) -> Result<Uuid, Error> {
        let bad = || Error::Invalid {
            field: "UUID text",
            value: s.len() as u32,
            why: "not the 8-4-4-4-12 hexadecimal form",
        };
        let groups: Vec<&str> = s.split('-').collect();
        if groups.iter().map(|g| g.len()).collect::<Vec<_>>() != [8, 4, 4, 4, 12] {
            return Err(bad());
        }
        let hex: String = groups.concat();
        let mut b = [0u8; 16];
        for (i, byte) in b.iter_mut().enumerate() {
            let pair = hex.get(2 * i..2 * i + 2).ok_or_else(bad)?;
            *byte = u8::from_str_radix(pair, 16).map_err(|_| bad())?;
        }
        Ok(Uuid(b))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uuid_text_wire_and_pnio_object() {
        let dev = Uuid::PNIO_DEVICE_INTERFACE;
        assert_eq!(dev.to_string(), "dea00001-6c97-11d1-8271-00a02442df7d");
        assert_eq!(
            "DEA00001-6C97-11D1-8271-00A02442DF7D".parse::<Uuid>(),
            Ok(dev)
        );
        assert!("dea00001-6c97-11d1-8271".parse::<Uuid>().is_err());
        assert!("dea0000g-6c97-11d1-8271-00a02442df7d"
            .parse::<Uuid>()
            .is_err());
        assert_eq!(
            Uuid::PNIO_CONTROLLER_INTERFACE.to_string(),
            "dea00002-6c97-11d1-8271-00a02442df7d"
        );
        assert_eq!(
            Uuid::EPM_INTERFACE.to_string(),
            "e1af8308-5d1f-11c9-91a4-08002b14a0fa"
        );
        // LE wire: 01 00 A0 DE | 97 6C | D1 11 | 82 71 00 A0 24 42 DF 7D.
        let w = dev.to_wire(true);
        assert_eq!(w[..8], [0x01, 0x00, 0xA0, 0xDE, 0x97, 0x6C, 0xD1, 0x11]);
        assert_eq!(w[8..], dev.0[8..]);
        assert_eq!(Uuid::from_wire(w, true), dev);
        assert_eq!(dev.to_wire(false), dev.0);
        let obj = Uuid::pnio_object(1, 0x0010, 0x002A);
        assert_eq!(obj.to_string(), "dea00000-6c97-11d1-8271-00010010002a");
        assert_eq!(obj.pnio_object_parts(), Some((1, 0x0010, 0x002A)));
        assert_eq!(dev.pnio_object_parts(), None);
        assert!(dev.is_pnio_interface() && !obj.is_pnio_interface());
        assert!(Uuid::NIL.is_nil());
    }
}
