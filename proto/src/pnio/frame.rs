//! The frame id that opens every PROFINET frame after the EtherType 8892h, and [`PnRepr`], the
//! frame parsed by its id (IEC 61158-6-10 §4.2.2 "FrameID" table; BU 0620 §2.5.3: "a PROFINET
//! IO frame is identified with the label 8892h and a frame ID").
//!
//! | FrameID | use |
//! |---|---|
//! | 0000h–00FFh | time synchronisation (PTCP) and reserved |
//! | 0100h–0FFFh | RT_CLASS_3 (isochronous, IRT) |
//! | 1000h–7FFFh | reserved (RT_CLASS_STREAM with time-aware networks) |
//! | 8000h–BFFFh | RT_CLASS_2 in edition 2 of the standard; RT_CLASS_1 in later editions — unicast 8000h–BBFFh, multicast BC00h–BFFFh |
//! | C000h–FBFFh | RT_CLASS_1 (edition 2, still used by many controllers) and RT_CLASS_UDP — unicast C000h–F7FFh, multicast F800h–FBFFh |
//! | FC01h | alarm high priority (RTA-PDU) |
//! | FE01h | alarm low priority (RTA-PDU) |
//! | FEFCh | DCP Hello |
//! | FEFDh | DCP Get / Set (requests and responses) |
//! | FEFEh | DCP Identify request (multicast) |
//! | FEFFh | DCP Identify response |
//! | FF00h–FF43h | PTCP announce / follow-up / delay |
//! | FF80h–FF8Fh | fragmentation |
//!
//! RT_CLASS_UDP uses the frame ids of RT_CLASS_1 (C000h–FBFFh) inside UDP datagrams to port
//! 34962 (8892h); on Ethernet those ids are RT_CLASS_1 frames. (The issue brief placed
//! RT_CLASS_UDP at F800h–FBFFh only: that range is the multicast half of both.)
//!
//! Every `Repr` of this folder starts at the frame id: [`super::dcp::DcpRepr`],
//! [`super::rt::RtRepr`] and [`super::alarm::AlarmRepr`] parse from it and emit it.

use std::fmt;
use std::ops::RangeInclusive;

use super::alarm::AlarmRepr;
use super::dcp::DcpRepr;
use super::rt::RtRepr;
use crate::wire::Error;

/// A PROFINET frame id (big-endian, the first two bytes after the EtherType). Open: any value
/// round-trips; [`FrameId::kind`] says what this crate makes of it.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default, PartialOrd, Ord)]
pub struct FrameId(pub u16);

/// What a frame id carries, as far as this crate parses it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FrameKind {
    /// Cyclic real-time data: C_SDU, cycle counter, data status, transfer status
    /// (RT_CLASS_1/2/3 and RT_CLASS_UDP ids).
    Rt,
    /// An alarm (RTA-PDU), high (FC01h) or low (FE01h) priority.
    Alarm {
        /// High priority (FC01h).
        high: bool,
    },
    /// DCP (FEFCh–FEFFh).
    Dcp,
    /// Anything else (PTCP, fragmentation, reserved).
    Other,
}

impl FrameId {
    /// RT_CLASS_3 (IRT), 0100h–0FFFh.
    pub const RT_CLASS_3: RangeInclusive<u16> = 0x0100..=0x0FFF;
    /// RT_CLASS_2 as edition 2 names 8000h–BFFFh (later editions: RT_CLASS_1 unicast
    /// 8000h–BBFFh and multicast BC00h–BFFFh).
    pub const RT_CLASS_2: RangeInclusive<u16> = 0x8000..=0xBFFF;
    /// Unicast half of 8000h–BFFFh.
    pub const RT_CLASS_2_UNICAST: RangeInclusive<u16> = 0x8000..=0xBBFF;
    /// Multicast half of 8000h–BFFFh.
    pub const RT_CLASS_2_MULTICAST: RangeInclusive<u16> = 0xBC00..=0xBFFF;
    /// RT_CLASS_1 (edition 2 numbering), C000h–FBFFh.
    pub const RT_CLASS_1: RangeInclusive<u16> = 0xC000..=0xFBFF;
    /// RT_CLASS_1 unicast, C000h–F7FFh.
    pub const RT_CLASS_1_UNICAST: RangeInclusive<u16> = 0xC000..=0xF7FF;
    /// RT_CLASS_1 multicast, F800h–FBFFh.
    pub const RT_CLASS_1_MULTICAST: RangeInclusive<u16> = 0xF800..=0xFBFF;
    /// RT_CLASS_UDP: the RT_CLASS_1 ids inside UDP datagrams (port 34962).
    pub const RT_CLASS_UDP: RangeInclusive<u16> = 0xC000..=0xFBFF;
    /// Alarm, high priority.
    pub const ALARM_HIGH: FrameId = FrameId(0xFC01);
    /// Alarm, low priority.
    pub const ALARM_LOW: FrameId = FrameId(0xFE01);
    /// DCP Hello request.
    pub const DCP_HELLO: FrameId = FrameId(0xFEFC);
    /// DCP Get and Set, requests and responses.
    pub const DCP_GET_SET: FrameId = FrameId(0xFEFD);
    /// DCP Identify request (to [`super::MULTICAST_DCP_IDENTIFY`]).
    pub const DCP_IDENTIFY_REQ: FrameId = FrameId(0xFEFE);
    /// DCP Identify response (unicast).
    pub const DCP_IDENTIFY_RES: FrameId = FrameId(0xFEFF);

    /// What the id carries.
    pub fn kind(self) -> FrameKind {
        match self.0 {
            0x0100..=0x0FFF | 0x8000..=0xFBFF => FrameKind::Rt,
            0xFC01 => FrameKind::Alarm { high: true },
            0xFE01 => FrameKind::Alarm { high: false },
            0xFEFC..=0xFEFF => FrameKind::Dcp,
            _ => FrameKind::Other,
        }
    }

    /// A cyclic id of a multicast CR (BC00h–BFFFh, F800h–FBFFh).
    pub fn is_multicast_rt(self) -> bool {
        Self::RT_CLASS_2_MULTICAST.contains(&self.0) || Self::RT_CLASS_1_MULTICAST.contains(&self.0)
    }

    /// The name of a fixed id, or of the range of a cyclic one.
    pub fn name(self) -> Option<&'static str> {
        Some(match self {
            FrameId::ALARM_HIGH => "Alarm high",
            FrameId::ALARM_LOW => "Alarm low",
            FrameId::DCP_HELLO => "DCP Hello",
            FrameId::DCP_GET_SET => "DCP Get/Set",
            FrameId::DCP_IDENTIFY_REQ => "DCP Identify request",
            FrameId::DCP_IDENTIFY_RES => "DCP Identify response",
            FrameId(0x0100..=0x0FFF) => "RT_CLASS_3",
            FrameId(0x8000..=0xBFFF) => "RT_CLASS_2/1",
            FrameId(0xC000..=0xFBFF) => "RT_CLASS_1",
            _ => return None,
        })
    }
}

impl fmt::Debug for FrameId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.name() {
            Some(n) => write!(f, "FrameId({:04X}h {n})", self.0),
            None => write!(f, "FrameId({:04X}h)", self.0),
        }
    }
}

/// Reads the frame id at the start of `buf`.
pub(crate) fn read_frame_id(buf: &[u8]) -> Result<FrameId, Error> {
    match buf {
        [a, b, ..] => Ok(FrameId(u16::from_be_bytes([*a, *b]))),
        _ => Err(Error::Truncated {
            what: "FrameID",
            need: 2,
            got: buf.len(),
        }),
    }
}

/// A PROFINET frame after the EtherType, parsed by its frame id.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum PnRepr {
    /// A DCP telegram (FEFCh–FEFFh).
    Dcp(DcpRepr),
    /// A cyclic frame.
    Rt(RtRepr),
    /// An alarm RTA-PDU (FC01h / FE01h).
    Alarm(AlarmRepr),
}

impl PnRepr {
    /// Parses the bytes after the Ethernet (and VLAN) header. An RT frame is parsed with its
    /// status in the last four bytes ([`RtRepr::parse`] with `None`); a frame id of
    /// [`FrameKind::Other`] is [`Error::Unknown`].
    pub fn parse(buf: &[u8]) -> Result<PnRepr, Error> {
        let id = read_frame_id(buf)?;
        match id.kind() {
            FrameKind::Dcp => DcpRepr::parse(buf).map(PnRepr::Dcp),
            FrameKind::Rt => RtRepr::parse(buf, None).map(PnRepr::Rt),
            FrameKind::Alarm { .. } => AlarmRepr::parse(buf).map(PnRepr::Alarm),
            FrameKind::Other => Err(Error::Unknown {
                field: "FrameID",
                value: u32::from(id.0),
            }),
        }
    }

    /// The frame id.
    pub fn frame_id(&self) -> FrameId {
        match self {
            PnRepr::Dcp(d) => d.frame_id,
            PnRepr::Rt(r) => r.frame_id,
            PnRepr::Alarm(a) => a.frame_id,
        }
    }

    /// The bytes from the frame id on (the Ethernet layer pads short frames).
    pub fn emit(&self) -> Result<Vec<u8>, Error> {
        match self {
            PnRepr::Dcp(d) => d.emit(),
            PnRepr::Rt(r) => Ok(r.emit()),
            PnRepr::Alarm(a) => a.emit(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kinds_follow_the_frame_id_table() {
        assert_eq!(FrameId(0x8001).kind(), FrameKind::Rt);
        assert_eq!(FrameId(0xC000).kind(), FrameKind::Rt);
        assert_eq!(FrameId(0xFBFF).kind(), FrameKind::Rt);
        assert_eq!(FrameId(0x0100).kind(), FrameKind::Rt);
        assert_eq!(FrameId::ALARM_HIGH.kind(), FrameKind::Alarm { high: true });
        assert_eq!(FrameId::ALARM_LOW.kind(), FrameKind::Alarm { high: false });
        for id in 0xFEFC..=0xFEFF {
            assert_eq!(FrameId(id).kind(), FrameKind::Dcp);
        }
        for id in [
            0x0000, 0x0020, 0x1000, 0x7FFF, 0xFC00, 0xFC02, 0xFE02, 0xFF00, 0xFFFF,
        ] {
            assert_eq!(FrameId(id).kind(), FrameKind::Other, "{id:04X}");
        }
        assert!(FrameId(0xF800).is_multicast_rt() && FrameId(0xBC00).is_multicast_rt());
        assert!(!FrameId(0xC001).is_multicast_rt() && !FrameId(0x8000).is_multicast_rt());
        assert_eq!(
            format!("{:?}", FrameId::DCP_HELLO),
            "FrameId(FEFCh DCP Hello)"
        );
        assert_eq!(format!("{:?}", FrameId(0x0022)), "FrameId(0022h)");
    }

    #[test]
    fn parse_dispatches_on_the_frame_id() {
        // FE FE Identify request: Identify 05, request 00, Xid 00000001, ResponseDelay 0001,
        // DCPDataLength 4; All selector FF FF length 0.
        let dcp = [
            0xFE, 0xFE, 0x05, 0x00, 0, 0, 0, 1, 0x00, 0x01, 0x00, 0x04, 0xFF, 0xFF, 0, 0,
        ];
        let r = PnRepr::parse(&dcp).unwrap();
        assert!(matches!(r, PnRepr::Dcp(_)));
        assert_eq!(r.frame_id(), FrameId::DCP_IDENTIFY_REQ);
        assert_eq!(r.emit().unwrap(), dcp);

        // C0 00 RT: 40 data bytes, cycle counter 0102, data status 35h, transfer status 00.
        let mut rt = vec![0xC0, 0x00];
        rt.extend([0xAA; 40]);
        rt.extend([0x01, 0x02, 0x35, 0x00]);
        let r = PnRepr::parse(&rt).unwrap();
        assert!(matches!(r, PnRepr::Rt(_)));
        assert_eq!(r.emit().unwrap(), rt);

        // FE 01 alarm low: ACK PDU from endpoint 2 to 1, seq 0 / ack 0, no var part.
        let alarm = [
            0xFE, 0x01, 0x00, 0x01, 0x00, 0x02, 0x13, 0x01, 0, 0, 0, 0, 0, 0,
        ];
        let r = PnRepr::parse(&alarm).unwrap();
        assert!(matches!(r, PnRepr::Alarm(_)));
        assert_eq!(r.emit().unwrap(), alarm);

        assert_eq!(
            PnRepr::parse(&[0xFF, 0x00, 1, 2]),
            Err(Error::Unknown {
                field: "FrameID",
                value: 0xFF00
            })
        );
        assert_eq!(
            PnRepr::parse(&[0xFE]),
            Err(Error::Truncated {
                what: "FrameID",
                need: 2,
                got: 1
            })
        );
    }

    mod properties {
        use super::*;
        use crate::pnio::rt::{DataStatus, MIN_C_SDU};
        use proptest::collection::vec;
        use proptest::prelude::*;

        /// Frames of each kind the dispatcher reads (the bodies' own properties sit beside
        /// their codecs): RT frames on RT frame ids, alarm ACKs on both alarm ids, Identify All.
        fn repr() -> impl Strategy<Value = PnRepr> {
            prop_oneof![
                (
                    any::<u16>()
                        .prop_filter("RT frame id", |id| FrameId(*id).kind() == FrameKind::Rt),
                    vec(any::<u8>(), MIN_C_SDU..=64),
                    any::<(u16, u8, u8)>(),
                )
                    .prop_map(|(id, data, (cycle_counter, s, transfer_status))| {
                        PnRepr::Rt(RtRepr {
                            frame_id: FrameId(id),
                            data,
                            cycle_counter,
                            data_status: DataStatus(s),
                            transfer_status,
                        })
                    }),
                (
                    prop_oneof![Just(FrameId::ALARM_HIGH), Just(FrameId::ALARM_LOW)],
                    any::<(u16, u16, u16, u16)>(),
                )
                    .prop_map(|(id, (dst, src, send, ack))| {
                        PnRepr::Alarm(AlarmRepr::ack(id, dst, src, send, ack))
                    }),
                (any::<u32>(), any::<u16>())
                    .prop_map(|(xid, delay)| PnRepr::Dcp(DcpRepr::identify_all(xid, delay))),
            ]
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn emit_then_parse_round_trips(r in repr()) {
                let b = r.emit().unwrap();
                prop_assert_eq!(PnRepr::parse(&b), Ok(r));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(
                id in prop_oneof![any::<u16>(), 0xFEFCu16..=0xFEFF, Just(0xFC01u16), Just(0xFE01u16), 0xC000u16..=0xFBFF],
                rest in vec(any::<u8>(), 0..64),
            ) {
                let mut b = id.to_be_bytes().to_vec();
                b.extend(rest);
                let _ = PnRepr::parse(&b);
            }
        }
    }
}
