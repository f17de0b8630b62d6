//! Ethernet II (DIX) frames, as the real-time Ethernets without IP carry them: EtherCAT
//! (EtherType 88A4h), POWERLINK (88ABh) and PROFINET RT (8892h).
//!
//! | bytes | field |
//! |---|---|
//! | 0–5 | destination MAC |
//! | 6–11 | source MAC |
//! | 12–13 | EtherType (big-endian), or 8100h followed by a 2-byte tag (TCI) and the EtherType |
//! | 14.. | payload, padded to a 60-byte frame (64 with the FCS the NIC adds) |
//!
//! IEEE 802.3 clause 3 (MAC frame format, length/type field) and clause 4 (minimum frame size:
//! 64 bytes including the 4-byte FCS, so 60 bytes as a NIC hands them over); IEEE 802.1Q (the
//! VLAN tag). The FCS is never part of these buffers.
//!
//! [`EthernetFrame`] is a checked view (it never panics on any buffer it accepted);
//! [`EthernetRepr`] parses and emits the header.

use std::fmt;

use crate::wire::Error;

/// EtherCAT (ETG.1000.4 §5.3). BU 0620 §2.2.3 figure 3 prints 88ABh, which is POWERLINK's: an
/// erratum of the manual.
pub const ETHERTYPE_ECAT: u16 = 0x88A4;
/// POWERLINK (EPSG DS 301).
pub const ETHERTYPE_POWERLINK: u16 = 0x88AB;
/// PROFINET real-time (IEC 61158-6-10).
pub const ETHERTYPE_PROFINET: u16 = 0x8892;
/// IPv4.
pub const ETHERTYPE_IPV4: u16 = 0x0800;
/// ARP.
pub const ETHERTYPE_ARP: u16 = 0x0806;
/// IEEE 802.1Q VLAN tag (the real EtherType follows the 2-byte tag control information).
pub const ETHERTYPE_VLAN: u16 = 0x8100;
/// LLDP (IEEE 802.1AB).
pub const ETHERTYPE_LLDP: u16 = 0x88CC;

/// Length of the untagged header.
pub const HEADER_LEN: usize = 14;
/// Length of a header with one 802.1Q tag.
pub const TAGGED_HEADER_LEN: usize = 18;
/// The shortest frame on the wire without its FCS (IEEE 802.3: 64 bytes with the FCS).
/// [`EthernetRepr::emit`] pads to it.
pub const MIN_FRAME_LEN: usize = 60;
/// The longest untagged frame without its FCS (1500 bytes of payload).
pub const MAX_FRAME_LEN: usize = 1514;

/// The name of an EtherType this crate knows, for transcripts.
pub fn ethertype_name(ethertype: u16) -> Option<&'static str> {
    Some(match ethertype {
        ETHERTYPE_ECAT => "EtherCAT",
        ETHERTYPE_POWERLINK => "POWERLINK",
        ETHERTYPE_PROFINET => "PROFINET",
        ETHERTYPE_IPV4 => "IPv4",
        ETHERTYPE_ARP => "ARP",
        ETHERTYPE_VLAN => "802.1Q",
        ETHERTYPE_LLDP => "LLDP",
        _ => return None,
    })
}

/// A MAC address (IEEE 802).
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct MacAddr(pub [u8; 6]);

impl MacAddr {
    /// FF:FF:FF:FF:FF:FF.
    pub const BROADCAST: MacAddr = MacAddr([0xFF; 6]);
    /// 00:00:00:00:00:00.
    pub const ZERO: MacAddr = MacAddr([0; 6]);

    /// Group (multicast or broadcast) address: bit 0 of the first byte (I/G bit).
    pub fn is_multicast(self) -> bool {
        self.0[0] & 0x01 != 0
    }

    /// The broadcast address.
    pub fn is_broadcast(self) -> bool {
        self == MacAddr::BROADCAST
    }

    /// Locally administered: bit 1 of the first byte (U/L bit). An EtherCAT slave controller
    /// sets it in the source address of every frame it processes, so a master sees its frames
    /// came back through a slave (ESC datasheet section I, frame processing).
    pub fn is_locally_administered(self) -> bool {
        self.0[0] & 0x02 != 0
    }

    /// The same address with the locally-administered bit set.
    pub fn with_locally_administered(self) -> MacAddr {
        let mut a = self.0;
        a[0] |= 0x02;
        MacAddr(a)
    }

    /// Reads six bytes; `None` when `b` is not six bytes long.
    pub fn from_bytes(b: &[u8]) -> Option<MacAddr> {
        <[u8; 6]>::try_from(b).ok().map(MacAddr)
    }
}

impl fmt::Display for MacAddr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let a = self.0;
        write!(
            f,
            "{:02x}:{:02x}:{:02x}:{:02x}:{:02x}:{:02x}",
            a[0], a[1], a[2], a[3], a[4], a[5]
        )
    }
}

impl fmt::Debug for MacAddr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "MacAddr({self})")
    }
}

mod field {
    use std::ops::Range;
    pub(super) const DST: Range<usize> = 0..6;
    pub(super) const SRC: Range<usize> = 6..12;
    pub(super) const ETHERTYPE: Range<usize> = 12..14;
    pub(super) const TCI: Range<usize> = 14..16;
    pub(super) const INNER_ETHERTYPE: Range<usize> = 16..18;
}

/// Checked view over an Ethernet II frame (without FCS). A frame whose EtherType is 8100h
/// must hold the whole tag.
#[derive(Debug, Clone)]
pub struct EthernetFrame<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> EthernetFrame<T> {
    /// Wraps a buffer without checking it; the accessors may then panic on a short buffer.
    /// Use [`EthernetFrame::new_checked`] for anything received.
    pub fn new_unchecked(buffer: T) -> Self {
        EthernetFrame { buffer }
    }

    /// Wraps a buffer after checking that it holds the header (and the VLAN tag if there is
    /// one).
    pub fn new_checked(buffer: T) -> Result<Self, Error> {
        let f = EthernetFrame { buffer };
        f.check_len()?;
        Ok(f)
    }

    /// Checks the header length.
    pub fn check_len(&self) -> Result<(), Error> {
        let got = self.buffer.as_ref().len();
        if got < HEADER_LEN {
            return Err(Error::Truncated {
                what: "Ethernet header",
                need: HEADER_LEN,
                got,
            });
        }
        if self.ethertype() == ETHERTYPE_VLAN && got < TAGGED_HEADER_LEN {
            return Err(Error::Truncated {
                what: "Ethernet header",
                need: TAGGED_HEADER_LEN,
                got,
            });
        }
        Ok(())
    }

    /// The buffer back.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    fn b(&self) -> &[u8] {
        self.buffer.as_ref()
    }

    /// Destination address.
    pub fn dst(&self) -> MacAddr {
        let mut a = [0; 6];
        a.copy_from_slice(&self.b()[field::DST]);
        MacAddr(a)
    }

    /// Source address.
    pub fn src(&self) -> MacAddr {
        let mut a = [0; 6];
        a.copy_from_slice(&self.b()[field::SRC]);
        MacAddr(a)
    }

    /// The outer EtherType (8100h for a tagged frame).
    pub fn ethertype(&self) -> u16 {
        let b = &self.b()[field::ETHERTYPE];
        u16::from_be_bytes([b[0], b[1]])
    }

    /// The VLAN tag control information (priority, DEI, VLAN id), if the frame is tagged.
    pub fn vlan_tci(&self) -> Option<u16> {
        (self.ethertype() == ETHERTYPE_VLAN).then(|| {
            let b = &self.b()[field::TCI];
            u16::from_be_bytes([b[0], b[1]])
        })
    }

    /// The EtherType of the payload: after one 802.1Q tag if there is one.
    pub fn inner_ethertype(&self) -> u16 {
        if self.vlan_tci().is_some() {
            let b = &self.b()[field::INNER_ETHERTYPE];
            u16::from_be_bytes([b[0], b[1]])
        } else {
            self.ethertype()
        }
    }

    /// Length of the header (14, or 18 with a VLAN tag).
    pub fn header_len(&self) -> usize {
        if self.vlan_tci().is_some() {
            TAGGED_HEADER_LEN
        } else {
            HEADER_LEN
        }
    }

    /// Everything after the outer EtherType (the tag included for a tagged frame), padding
    /// included.
    pub fn payload(&self) -> &[u8] {
        &self.b()[HEADER_LEN..]
    }

    /// Everything after the header and the VLAN tag, padding included.
    pub fn inner_payload(&self) -> &[u8] {
        &self.b()[self.header_len()..]
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> EthernetFrame<T> {
    fn bm(&mut self) -> &mut [u8] {
        self.buffer.as_mut()
    }

    /// Sets the destination address.
    pub fn set_dst(&mut self, a: MacAddr) {
        self.bm()[field::DST].copy_from_slice(&a.0);
    }

    /// Sets the source address.
    pub fn set_src(&mut self, a: MacAddr) {
        self.bm()[field::SRC].copy_from_slice(&a.0);
    }

    /// Sets the outer EtherType.
    pub fn set_ethertype(&mut self, t: u16) {
        self.bm()[field::ETHERTYPE].copy_from_slice(&t.to_be_bytes());
    }

    /// The payload after the outer EtherType, writable.
    pub fn payload_mut(&mut self) -> &mut [u8] {
        &mut self.bm()[HEADER_LEN..]
    }

    /// The payload after the header and the VLAN tag, writable.
    pub fn inner_payload_mut(&mut self) -> &mut [u8] {
        let at = self.header_len();
        &mut self.bm()[at..]
    }
}

/// An untagged Ethernet II header.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct EthernetRepr {
    /// Destination address.
    pub dst: MacAddr,
    /// Source address.
    pub src: MacAddr,
    /// EtherType.
    pub ethertype: u16,
}

impl EthernetRepr {
    /// Reads the header of a checked frame (the outer EtherType; see
    /// [`EthernetFrame::inner_ethertype`] for tagged frames).
    pub fn parse<T: AsRef<[u8]>>(frame: &EthernetFrame<T>) -> Result<EthernetRepr, Error> {
        frame.check_len()?;
        Ok(EthernetRepr {
            dst: frame.dst(),
            src: frame.src(),
            ethertype: frame.ethertype(),
        })
    }

    /// Length of the header.
    pub const fn header_len(&self) -> usize {
        HEADER_LEN
    }

    /// Length of a frame carrying `payload_len` bytes: header plus payload, at least
    /// [`MIN_FRAME_LEN`].
    pub fn buffer_len(&self, payload_len: usize) -> usize {
        (HEADER_LEN + payload_len).max(MIN_FRAME_LEN)
    }

    /// Writes the header into the first 14 bytes of `buffer`.
    pub fn emit_header(&self, buffer: &mut [u8]) -> Result<(), Error> {
        if buffer.len() < HEADER_LEN {
            return Err(Error::TooLong {
                what: "Ethernet header",
                len: HEADER_LEN,
                max: buffer.len(),
            });
        }
        let mut f = EthernetFrame::new_unchecked(buffer);
        f.set_dst(self.dst);
        f.set_src(self.src);
        f.set_ethertype(self.ethertype);
        Ok(())
    }

    /// The whole frame: header, `payload`, zero padding up to [`MIN_FRAME_LEN`].
    pub fn emit(&self, payload: &[u8]) -> Vec<u8> {
        let mut out = vec![0; self.buffer_len(payload.len())];
        // Cannot fail: the buffer is at least 60 bytes.
        let _ = self.emit_header(&mut out);
        out[HEADER_LEN..HEADER_LEN + payload.len()].copy_from_slice(payload);
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An EtherCAT frame as SOEM sends it: broadcast destination, source 01:01:01:01:01:01.
    const FRAME: [u8; 16] = [
        0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, // destination: broadcast
        0x01, 0x01, 0x01, 0x01, 0x01, 0x01, // source
        0x88, 0xA4, // EtherType: EtherCAT
        0xAB, 0xCD, // payload
    ];

    #[test]
    fn parses_the_header() {
        let f = EthernetFrame::new_checked(&FRAME[..]).unwrap();
        let r = EthernetRepr::parse(&f).unwrap();
        assert_eq!(r.dst, MacAddr::BROADCAST);
        assert_eq!(r.src, MacAddr([1; 6]));
        assert_eq!(r.ethertype, ETHERTYPE_ECAT);
        assert_eq!(f.payload(), [0xAB, 0xCD]);
        assert_eq!(f.inner_payload(), [0xAB, 0xCD]);
        assert_eq!(f.vlan_tci(), None);
        assert_eq!(ethertype_name(f.ethertype()), Some("EtherCAT"));
    }

    #[test]
    fn emit_pads_to_60_and_round_trips() {
        let r = EthernetRepr {
            dst: MacAddr::BROADCAST,
            src: MacAddr([1; 6]),
            ethertype: ETHERTYPE_ECAT,
        };
        let out = r.emit(&[0xAB, 0xCD]);
        assert_eq!(out.len(), 60);
        assert_eq!(&out[..16], FRAME);
        assert!(out[16..].iter().all(|b| *b == 0));
        let back = EthernetRepr::parse(&EthernetFrame::new_checked(&out).unwrap()).unwrap();
        assert_eq!(back, r);
        assert_eq!(r.emit(&[0; 100]).len(), 114);
        assert_eq!(
            r.emit_header(&mut [0; 13]),
            Err(Error::TooLong {
                what: "Ethernet header",
                len: 14,
                max: 13
            })
        );
    }

    #[test]
    fn truncation_at_every_length_is_an_error() {
        for n in 0..HEADER_LEN {
            assert_eq!(
                EthernetFrame::new_checked(&FRAME[..n]).unwrap_err(),
                Error::Truncated {
                    what: "Ethernet header",
                    need: 14,
                    got: n
                }
            );
        }
        assert!(EthernetFrame::new_checked(&FRAME[..14]).is_ok());
    }

    #[test]
    fn a_vlan_tag_is_skipped() {
        let tagged = [
            0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, // destination
            0x02, 0x01, 0x01, 0x01, 0x01, 0x01, // source, locally administered
            0x81, 0x00, // 802.1Q
            0xE0, 0x00, // TCI: priority 7, VLAN 0
            0x88, 0xA4, // EtherCAT
            0x55, // payload
        ];
        let f = EthernetFrame::new_checked(&tagged[..]).unwrap();
        assert_eq!(f.vlan_tci(), Some(0xE000));
        assert_eq!(f.inner_ethertype(), ETHERTYPE_ECAT);
        assert_eq!(f.inner_payload(), [0x55]);
        for n in 14..18 {
            assert_eq!(
                EthernetFrame::new_checked(&tagged[..n]).unwrap_err(),
                Error::Truncated {
                    what: "Ethernet header",
                    need: 18,
                    got: n
                }
            );
        }
    }

    #[test]
    fn setters_and_mac_bits() {
        let mut b = FRAME;
        let mut f = EthernetFrame::new_checked(&mut b[..]).unwrap();
        let src = f.src().with_locally_administered();
        f.set_src(src);
        f.payload_mut()[0] = 0x11;
        assert_eq!(f.src(), MacAddr([0x03, 1, 1, 1, 1, 1]));
        assert!(f.src().is_locally_administered() && f.src().is_multicast());
        assert!(!MacAddr([0x00, 1, 2, 3, 4, 5]).is_locally_administered());
        assert!(MacAddr::BROADCAST.is_broadcast());
        assert_eq!(b[14], 0x11);
        assert_eq!(
            MacAddr([0x02, 0, 0, 0, 0, 0xAB]).to_string(),
            "02:00:00:00:00:ab"
        );
        assert_eq!(MacAddr::from_bytes(&[1, 2, 3]), None);
    }

    mod properties {
        use super::*;
        use proptest::collection::vec;
        use proptest::prelude::*;

        fn header() -> impl Strategy<Value = EthernetRepr> {
            (any::<[u8; 6]>(), any::<[u8; 6]>(), any::<u16>()).prop_map(|(dst, src, ethertype)| {
                EthernetRepr {
                    dst: MacAddr(dst),
                    src: MacAddr(src),
                    ethertype,
                }
            })
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn emit_then_parse_round_trips(h in header(), payload in vec(any::<u8>(), 0..=100)) {
                let b = h.emit(&payload);
                prop_assert_eq!(b.len(), h.buffer_len(payload.len()));
                let f = EthernetFrame::new_checked(&b[..]).unwrap();
                prop_assert_eq!(EthernetRepr::parse(&f), Ok(h));
                prop_assert_eq!(&f.payload()[..payload.len()], &payload[..]);
                prop_assert!(f.payload()[payload.len()..].iter().all(|&x| x == 0));
            }

            #[test]
            fn emit_header_round_trips(h in header(), extra in 0usize..8) {
                let mut b = vec![0u8; HEADER_LEN + 4 + extra];
                h.emit_header(&mut b).unwrap();
                let f = EthernetFrame::new_checked(&b[..]).unwrap();
                prop_assert_eq!(EthernetRepr::parse(&f), Ok(h));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in vec(any::<u8>(), 0..40)) {
                if let Ok(f) = EthernetFrame::new_checked(&bytes[..]) {
                    let _ = EthernetRepr::parse(&f);
                    let _ = (f.vlan_tci(), f.inner_ethertype(), f.header_len());
                    let _ = (f.payload(), f.inner_payload());
                }
            }
        }
    }
}
