//! The POWERLINK frame after the Ethernet header (EPSG DS 301 §4.6.1.1; BU 0620 §2.4.3 figure
//! 8): a 3-byte header — message type, destination node, source node — and the body of its
//! type.
//!
//! | type | bytes after the header (offsets from the message-type byte) |
//! |---|---|
//! | SoC 01h | 3 reserved; 4 flags MC 80h, PS 40h; 5 reserved; 6–13 NetTime; 14–21 RelativeTime |
//! | PReq 03h | 3 reserved; 4 flags MS 20h, EA 04h, RD 01h; 5 reserved; 6 PDOVersion; 7 reserved; 8–9 size; 10.. payload |
//! | PRes 04h | 3 NMTStatus; 4 flags MS 20h, EN 10h, RD 01h; 5 PR (bits 3–5), RS (bits 0–2); 6 PDOVersion; 7 reserved; 8–9 size; 10.. payload |
//! | SoA 05h | 3 NMTStatus; 4 flags EA 04h, ER 02h; 5 reserved; 6 RequestedServiceID; 7 RequestedServiceTarget; 8 EPLVersion |
//! | ASnd 06h | 3 ServiceID; 4.. the service's payload |
//!
//! A received frame is padded to the Ethernet minimum: the PReq/PRes size field, not the
//! buffer, bounds their payload, and bytes after a fixed body are padding.

use std::fmt;

use super::nmt::{NmtState, RequestedService, ServiceId};
use super::HEADER_LEN;
use crate::wire::{Error, Reader};

/// The message type (DS 301 §4.6.1.1.1; BU 0620 §2.4.3 table; the top bit is reserved).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct MessageType(pub u8);

impl MessageType {
    /// Start of Cycle (multicast).
    pub const SOC: MessageType = MessageType(0x01);
    /// Poll Request (unicast, MN to CN).
    pub const PREQ: MessageType = MessageType(0x03);
    /// Poll Response (multicast).
    pub const PRES: MessageType = MessageType(0x04);
    /// Start of Asynchronous (multicast).
    pub const SOA: MessageType = MessageType(0x05);
    /// Asynchronous Send (multicast).
    pub const ASND: MessageType = MessageType(0x06);

    /// The type's short name, if defined.
    pub fn name(self) -> Option<&'static str> {
        Some(match self {
            MessageType::SOC => "SoC",
            MessageType::PREQ => "PReq",
            MessageType::PRES => "PRes",
            MessageType::SOA => "SoA",
            MessageType::ASND => "ASnd",
            _ => return None,
        })
    }
}

impl fmt::Debug for MessageType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.name() {
            Some(n) => write!(f, "{n}"),
            None => write!(f, "MessageType({:02X}h)", self.0),
        }
    }
}

/// The fixed lengths of the SoC, the SoA and the ASnd header, from the message-type byte.
const SOC_LEN: usize = 22;
const SOA_LEN: usize = 9;
const ASND_HEADER: usize = 4;

/// A checked view of a POWERLINK frame (from the message-type byte): at least the 3-byte
/// header. Only [`EplRepr::parse`] looks at the body.
#[derive(Debug, Clone)]
pub struct EplFrame<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> EplFrame<T> {
    /// Checks the header is there.
    pub fn new_checked(buffer: T) -> Result<Self, Error> {
        let got = buffer.as_ref().len();
        if got < HEADER_LEN {
            return Err(Error::Truncated {
                what: "POWERLINK header",
                need: HEADER_LEN,
                got,
            });
        }
        Ok(EplFrame { buffer })
    }

    /// The message type (reserved top bit masked off).
    pub fn message_type(&self) -> MessageType {
        MessageType(self.buffer.as_ref()[0] & 0x7F)
    }

    /// The destination node id.
    pub fn dst(&self) -> u8 {
        self.buffer.as_ref()[1]
    }

    /// The source node id.
    pub fn src(&self) -> u8 {
        self.buffer.as_ref()[2]
    }

    /// The bytes after the header.
    pub fn body(&self) -> &[u8] {
        &self.buffer.as_ref()[HEADER_LEN..]
    }
}

/// SoC body.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Soc {
    /// MC: multiplexed cycle completed.
    pub mc: bool,
    /// PS: prescaled slot.
    pub ps: bool,
    /// NetTime (IEEE 1588 seconds and nanoseconds, as 8 little-endian bytes).
    pub net_time: u64,
    /// RelativeTime (µs since the first SoC).
    pub relative_time: u64,
}

/// PReq body.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Preq {
    /// MS: multiplexed slot.
    pub ms: bool,
    /// EA: exception acknowledge.
    pub ea: bool,
    /// RD: the payload is valid (ready).
    pub rd: bool,
    /// PDOVersion (major in the high nibble).
    pub pdo_version: u8,
    /// The output process data.
    pub payload: Vec<u8>,
}

/// PRes body.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Pres {
    /// The sender's NMT state.
    pub state: NmtState,
    /// MS: multiplexed slot.
    pub ms: bool,
    /// EN: exception new (a new error entry to report).
    pub en: bool,
    /// RD: the payload is valid.
    pub rd: bool,
    /// PR: priority of the pending asynchronous request (0..7).
    pub pr: u8,
    /// RS: number of pending asynchronous requests (0..7).
    pub rs: u8,
    /// PDOVersion.
    pub pdo_version: u8,
    /// The input process data.
    pub payload: Vec<u8>,
}

/// SoA body.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Soa {
    /// The MN's NMT state.
    pub state: NmtState,
    /// EA: exception acknowledge.
    pub ea: bool,
    /// ER: exception reset.
    pub er: bool,
    /// The service asked for.
    pub service: RequestedService,
    /// The node asked.
    pub target: u8,
    /// EPLVersion (20h = V2.0).
    pub epl_version: u8,
}

/// ASnd body: the service id and its payload (see [`super::asnd`], [`super::sdo`]).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Asnd {
    /// ServiceID.
    pub service: ServiceId,
    /// The bytes after it (padding included on a received frame).
    pub payload: Vec<u8>,
}

/// A POWERLINK frame's body by type.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Body {
    /// Start of Cycle.
    Soc(Soc),
    /// Poll Request.
    Preq(Preq),
    /// Poll Response.
    Pres(Pres),
    /// Start of Asynchronous.
    Soa(Soa),
    /// Asynchronous Send.
    Asnd(Asnd),
}

/// A whole POWERLINK frame (from the message-type byte).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EplRepr {
    /// Destination node id.
    pub dst: u8,
    /// Source node id.
    pub src: u8,
    /// The body.
    pub body: Body,
}

fn poll_payload<'a>(r: &mut Reader<'a>, what: &'static str) -> Result<&'a [u8], Error> {
    let size = usize::from(r.u16(what)?);
    if size > r.remaining() {
        return Err(Error::Length {
            field: what,
            value: size,
            available: r.remaining(),
        });
    }
    r.bytes(size, what)
}

impl EplRepr {
    /// Parses a frame; the message type must be one of the five.
    pub fn parse<T: AsRef<[u8]>>(frame: &EplFrame<T>) -> Result<EplRepr, Error> {
        let mut r = Reader::new(frame.body());
        let body = match frame.message_type() {
            MessageType::SOC => {
                r.u8("SoC reserved")?;
                let flags = r.u8("SoC flags")?;
                r.u8("SoC reserved")?;
                let t = r.bytes(16, "SoC NetTime/RelativeTime")?;
                let u64le = |b: &[u8]| {
                    let mut a = [0u8; 8];
                    a.copy_from_slice(b);
                    u64::from_le_bytes(a)
                };
                Body::Soc(Soc {
                    mc: flags & 0x80 != 0,
                    ps: flags & 0x40 != 0,
                    net_time: u64le(&t[..8]),
                    relative_time: u64le(&t[8..]),
                })
            }
            MessageType::PREQ => {
                r.u8("PReq reserved")?;
                let flags = r.u8("PReq flags")?;
                r.u8("PReq reserved")?;
                let pdo_version = r.u8("PReq PDOVersion")?;
                r.u8("PReq reserved")?;
                let payload = poll_payload(&mut r, "PReq size")?.to_vec();
                Body::Preq(Preq {
                    ms: flags & 0x20 != 0,
                    ea: flags & 0x04 != 0,
                    rd: flags & 0x01 != 0,
                    pdo_version,
                    payload,
                })
            }
            MessageType::PRES => {
                let state = NmtState(r.u8("PRes NMTStatus")?);
                let flags = r.u8("PRes flags")?;
                let prrs = r.u8("PRes PR/RS")?;
                let pdo_version = r.u8("PRes PDOVersion")?;
                r.u8("PRes reserved")?;
                let payload = poll_payload(&mut r, "PRes size")?.to_vec();
                Body::Pres(Pres {
                    state,
                    ms: flags & 0x20 != 0,
                    en: flags & 0x10 != 0,
                    rd: flags & 0x01 != 0,
                    pr: (prrs >> 3) & 0x07,
                    rs: prrs & 0x07,
                    pdo_version,
                    payload,
                })
            }
            MessageType::SOA => {
                let state = NmtState(r.u8("SoA NMTStatus")?);
                let flags = r.u8("SoA flags")?;
                r.u8("SoA reserved")?;
                let service = RequestedService(r.u8("SoA RequestedServiceID")?);
                let target = r.u8("SoA RequestedServiceTarget")?;
                let epl_version = r.u8("SoA EPLVersion")?;
                Body::Soa(Soa {
                    state,
                    ea: flags & 0x04 != 0,
                    er: flags & 0x02 != 0,
                    service,
                    target,
                    epl_version,
                })
            }
            MessageType::ASND => Body::Asnd(Asnd {
                service: ServiceId(r.u8("ASnd ServiceID")?),
                payload: r.rest().to_vec(),
            }),
            other => {
                return Err(Error::Unknown {
                    field: "POWERLINK MessageType",
                    value: u32::from(other.0),
                })
            }
        };
        Ok(EplRepr {
            dst: frame.dst(),
            src: frame.src(),
            body,
        })
    }

    /// Parses the bytes after the Ethernet header.
    pub fn parse_bytes(bytes: &[u8]) -> Result<EplRepr, Error> {
        EplRepr::parse(&EplFrame::new_checked(bytes)?)
    }

    /// The message type of the body.
    pub fn message_type(&self) -> MessageType {
        match self.body {
            Body::Soc(_) => MessageType::SOC,
            Body::Preq(_) => MessageType::PREQ,
            Body::Pres(_) => MessageType::PRES,
            Body::Soa(_) => MessageType::SOA,
            Body::Asnd(_) => MessageType::ASND,
        }
    }

    /// The bytes (from the message-type byte; the Ethernet layer pads). A PReq/PRes payload
    /// longer than the 16-bit size field is [`Error::TooLong`].
    pub fn emit(&self) -> Result<Vec<u8>, Error> {
        let mut b = vec![self.message_type().0, self.dst, self.src];
        let bit = |on: bool, mask: u8| if on { mask } else { 0 };
        let sized = |b: &mut Vec<u8>, payload: &[u8]| -> Result<(), Error> {
            let n = u16::try_from(payload.len()).map_err(|_| Error::TooLong {
                what: "PReq/PRes payload",
                len: payload.len(),
                max: usize::from(u16::MAX),
            })?;
            b.extend(n.to_le_bytes());
            b.extend(payload);
            Ok(())
        };
        match &self.body {
            Body::Soc(s) => {
                b.extend([0, bit(s.mc, 0x80) | bit(s.ps, 0x40), 0]);
                b.extend(s.net_time.to_le_bytes());
                b.extend(s.relative_time.to_le_bytes());
                debug_assert_eq!(b.len(), SOC_LEN);
            }
            Body::Preq(p) => {
                b.extend([
                    0,
                    bit(p.ms, 0x20) | bit(p.ea, 0x04) | bit(p.rd, 0x01),
                    0,
                    p.pdo_version,
                    0,
                ]);
                sized(&mut b, &p.payload)?;
            }
            Body::Pres(p) => {
                b.extend([
                    p.state.0,
                    bit(p.ms, 0x20) | bit(p.en, 0x10) | bit(p.rd, 0x01),
                    ((p.pr & 0x07) << 3) | (p.rs & 0x07),
                    p.pdo_version,
                    0,
                ]);
                sized(&mut b, &p.payload)?;
            }
            Body::Soa(s) => {
                b.extend([
                    s.state.0,
                    bit(s.ea, 0x04) | bit(s.er, 0x02),
                    0,
                    s.service.0,
                    s.target,
                    s.epl_version,
                ]);
                debug_assert_eq!(b.len(), SOA_LEN);
            }
            Body::Asnd(a) => {
                b.push(a.service.0);
                debug_assert_eq!(b.len(), ASND_HEADER);
                b.extend(&a.payload);
            }
        }
        Ok(b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn soc_round_trip() {
        // 01 SoC, FF broadcast, F0 from the MN; reserved; flags MC; reserved;
        // NetTime 8 bytes; RelativeTime 8 bytes.
        let bytes = [
            0x01, 0xFF, 0xF0, 0x00, 0x80, 0x00, 1, 0, 0, 0, 0, 0, 0, 0, 0xE8, 0x03, 0, 0, 0, 0, 0,
            0,
        ];
        let r = EplRepr::parse_bytes(&bytes).unwrap();
        assert_eq!(r.dst, 0xFF);
        assert_eq!(
            r.body,
            Body::Soc(Soc {
                mc: true,
                ps: false,
                net_time: 1,
                relative_time: 1000
            })
        );
        assert_eq!(r.emit().unwrap(), bytes);
    }

    #[test]
    fn pres_fields_and_size_bound_the_payload() {
        // 04 PRes to FF from node 1: NMTStatus FD (OPERATIONAL), flags EN|RD, PR 7 RS 1,
        // PDOVersion 20h, reserved, size 2, payload 37 06, then padding.
        let bytes = [
            0x04, 0xFF, 0x01, 0xFD, 0x11, 0x39, 0x20, 0x00, 0x02, 0x00, 0x37, 0x06, 0, 0, 0,
        ];
        let r = EplRepr::parse_bytes(&bytes).unwrap();
        let Body::Pres(p) = &r.body else {
            panic!("{r:?}")
        };
        assert_eq!(p.state, NmtState::OPERATIONAL);
        assert!(p.en && p.rd && !p.ms);
        assert_eq!((p.pr, p.rs, p.pdo_version), (7, 1, 0x20));
        assert_eq!(p.payload, [0x37, 0x06]);
        assert_eq!(r.emit().unwrap(), &bytes[..12]);
    }

    #[test]
    fn preq_size_beyond_the_frame_is_bad_length() {
        // PReq to node 1 claiming 100 payload bytes with 2 present.
        let bytes = [0x03, 0x01, 0xF0, 0, 0x01, 0, 0x20, 0, 100, 0, 1, 2];
        assert_eq!(
            EplRepr::parse_bytes(&bytes),
            Err(Error::Length {
                field: "PReq size",
                value: 100,
                available: 2
            })
        );
    }

    #[test]
    fn soa_round_trip_and_unknown_type() {
        // 05 SoA to FF from F0: NMTStatus 5D, flags ER, reserved, IdentRequest to node 1,
        // EPLVersion 20h.
        let bytes = [0x05, 0xFF, 0xF0, 0x5D, 0x02, 0x00, 0x01, 0x01, 0x20];
        let r = EplRepr::parse_bytes(&bytes).unwrap();
        let Body::Soa(s) = r.body else { panic!() };
        assert_eq!(s.service, RequestedService::IDENT_REQUEST);
        assert!(s.er && !s.ea);
        assert_eq!(r.emit().unwrap(), bytes);
        assert_eq!(
            EplRepr::parse_bytes(&[0x02, 1, 2]),
            Err(Error::Unknown {
                field: "POWERLINK MessageType",
                value: 2
            })
        );
        assert!(matches!(
            EplRepr::parse_bytes(&[0x05, 1, 2, 3]),
            Err(Error::Truncated { .. })
        ));
        assert!(matches!(
            EplFrame::new_checked(&[0x01u8, 2][..]),
            Err(Error::Truncated {
                need: 3,
                got: 2,
                ..
            })
        ));
    }

    mod properties {
        use super::*;
        use proptest::collection::vec;
        use proptest::prelude::*;

        fn body() -> impl Strategy<Value = Body> {
            prop_oneof![
                any::<(bool, bool, u64, u64)>().prop_map(|(mc, ps, net_time, relative_time)| {
                    Body::Soc(Soc {
                        mc,
                        ps,
                        net_time,
                        relative_time,
                    })
                }),
                (any::<(bool, bool, bool, u8)>(), vec(any::<u8>(), 0..=48)).prop_map(
                    |((ms, ea, rd, pdo_version), payload)| Body::Preq(Preq {
                        ms,
                        ea,
                        rd,
                        pdo_version,
                        payload
                    })
                ),
                (
                    any::<(u8, bool, bool, bool, u8)>(),
                    0u8..=7,
                    0u8..=7,
                    vec(any::<u8>(), 0..=48)
                )
                    .prop_map(
                        |((state, ms, en, rd, pdo_version), pr, rs, payload)| {
                            Body::Pres(Pres {
                                state: NmtState(state),
                                ms,
                                en,
                                rd,
                                pr,
                                rs,
                                pdo_version,
                                payload,
                            })
                        }
                    ),
                any::<(u8, bool, bool, u8, u8, u8)>().prop_map(
                    |(state, ea, er, service, target, epl_version)| Body::Soa(Soa {
                        state: NmtState(state),
                        ea,
                        er,
                        service: RequestedService(service),
                        target,
                        epl_version,
                    })
                ),
                (any::<u8>(), vec(any::<u8>(), 0..=48)).prop_map(|(service, payload)| {
                    Body::Asnd(Asnd {
                        service: ServiceId(service),
                        payload,
                    })
                }),
            ]
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn emit_then_parse_round_trips(dst in any::<u8>(), src in any::<u8>(), body in body()) {
                let r = EplRepr { dst, src, body };
                let b = r.emit().unwrap();
                prop_assert_eq!(EplRepr::parse_bytes(&b), Ok(r));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in vec(any::<u8>(), 0..48)) {
                let _ = EplRepr::parse_bytes(&bytes);
            }
        }
    }
}
