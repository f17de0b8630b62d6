//! The EtherNet/IP encapsulation layer: a 24-byte header and the command's data.
//!
//! | bytes | field |
//! |---|---|
//! | 0–1 | command |
//! | 2–3 | length of the data after the header |
//! | 4–7 | session handle |
//! | 8–11 | status |
//! | 12–19 | sender context (echoed) |
//! | 20–23 | options (0) |
//!
//! All little-endian. On TCP the header's length field is the only framing: [`frame_len`] tells
//! a reader how many bytes the next message needs.

use std::fmt;

use super::wire::{len16, Put};
use crate::wire::{Error, Reader};

/// Length of the encapsulation header.
pub const HEADER_LEN: usize = 24;

/// The largest data part this stack accepts or sends (a TCP message's header length field is
/// 16 bits; CIP's explicit messages stay far below).
pub const MAX_DATA_LEN: usize = 65_511;

/// An encapsulation command.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Command(pub u16);

impl Command {
    /// NOP (TCP only, no reply).
    pub const NOP: Command = Command(0x0000);
    /// ListServices.
    pub const LIST_SERVICES: Command = Command(0x0004);
    /// ListIdentity.
    pub const LIST_IDENTITY: Command = Command(0x0063);
    /// ListInterfaces.
    pub const LIST_INTERFACES: Command = Command(0x0064);
    /// RegisterSession.
    pub const REGISTER_SESSION: Command = Command(0x0065);
    /// UnRegisterSession.
    pub const UNREGISTER_SESSION: Command = Command(0x0066);
    /// SendRRData: unconnected (UCMM) request/reply.
    pub const SEND_RR_DATA: Command = Command(0x006F);
    /// SendUnitData: connected explicit messages.
    pub const SEND_UNIT_DATA: Command = Command(0x0070);

    /// The command's name, if it is one.
    pub fn name(self) -> Option<&'static str> {
        Some(match self {
            Command::NOP => "NOP",
            Command::LIST_SERVICES => "ListServices",
            Command::LIST_IDENTITY => "ListIdentity",
            Command::LIST_INTERFACES => "ListInterfaces",
            Command::REGISTER_SESSION => "RegisterSession",
            Command::UNREGISTER_SESSION => "UnRegisterSession",
            Command::SEND_RR_DATA => "SendRRData",
            Command::SEND_UNIT_DATA => "SendUnitData",
            _ => return None,
        })
    }
}

impl fmt::Display for Command {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.name() {
            Some(n) => write!(f, "{n}"),
            None => write!(f, "command {:04X}h", self.0),
        }
    }
}

/// An encapsulation status (the header's status field).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct EncapStatus(pub u32);

impl EncapStatus {
    /// Success.
    pub const SUCCESS: EncapStatus = EncapStatus(0x0000);
    /// The sender issued an invalid or unsupported encapsulation command.
    pub const INVALID_COMMAND: EncapStatus = EncapStatus(0x0001);
    /// Insufficient memory resources in the receiver.
    pub const INSUFFICIENT_MEMORY: EncapStatus = EncapStatus(0x0002);
    /// Poorly formed or incorrect data in the data portion.
    pub const INCORRECT_DATA: EncapStatus = EncapStatus(0x0003);
    /// An invalid session handle.
    pub const INVALID_SESSION: EncapStatus = EncapStatus(0x0064);
    /// A message of invalid length.
    pub const INVALID_LENGTH: EncapStatus = EncapStatus(0x0065);
    /// Unsupported encapsulation protocol revision.
    pub const UNSUPPORTED_PROTOCOL: EncapStatus = EncapStatus(0x0069);

    /// The status's meaning.
    pub fn name(self) -> &'static str {
        match self {
            EncapStatus::SUCCESS => "success",
            EncapStatus::INVALID_COMMAND => "invalid or unsupported command",
            EncapStatus::INSUFFICIENT_MEMORY => "insufficient memory",
            EncapStatus::INCORRECT_DATA => "incorrect data",
            EncapStatus::INVALID_SESSION => "invalid session handle",
            EncapStatus::INVALID_LENGTH => "invalid length",
            EncapStatus::UNSUPPORTED_PROTOCOL => "unsupported protocol revision",
            _ => "unknown status",
        }
    }
}

impl fmt::Display for EncapStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:04X}h ({})", self.0, self.name())
    }
}

/// Checked view over an encapsulation message: header plus exactly `length` data bytes.
#[derive(Debug, Clone)]
pub struct EncapFrame<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> EncapFrame<T> {
    /// Wraps a buffer holding one whole message (header and the data its length field names).
    pub fn new_checked(buffer: T) -> Result<Self, Error> {
        let b = buffer.as_ref();
        if b.len() < HEADER_LEN {
            return Err(Error::Truncated {
                what: "encapsulation header",
                need: HEADER_LEN,
                got: b.len(),
            });
        }
        let declared = usize::from(u16::from_le_bytes([b[2], b[3]]));
        let actual = b.len() - HEADER_LEN;
        if declared != actual {
            return Err(Error::Length {
                field: "encapsulation length",
                value: declared,
                available: actual,
            });
        }
        Ok(EncapFrame { buffer })
    }

    fn b(&self) -> &[u8] {
        self.buffer.as_ref()
    }

    fn u32_at(&self, at: usize) -> u32 {
        let b = self.b();
        u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
    }

    /// The command.
    pub fn command(&self) -> Command {
        Command(u16::from_le_bytes([self.b()[0], self.b()[1]]))
    }
    /// The session handle.
    pub fn session(&self) -> u32 {
        self.u32_at(4)
    }
    /// The status.
    pub fn status(&self) -> EncapStatus {
        EncapStatus(self.u32_at(8))
    }
    /// The sender context.
    pub fn context(&self) -> [u8; 8] {
        let mut c = [0; 8];
        c.copy_from_slice(&self.b()[12..20]);
        c
    }
    /// The options field.
    pub fn options(&self) -> u32 {
        self.u32_at(20)
    }
    /// The data after the header.
    pub fn data(&self) -> &[u8] {
        &self.b()[HEADER_LEN..]
    }
    /// The header's length field (the data's length, once checked).
    pub fn length(&self) -> u16 {
        u16::from_le_bytes([self.b()[2], self.b()[3]])
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> EncapFrame<T> {
    /// Sets the header's length field, for a message that lies about its length (a negative
    /// test, a misbehaving device): on TCP it moves where a reader takes the next message to
    /// begin.
    pub fn set_length(&mut self, length: u16) {
        self.buffer.as_mut()[2..4].copy_from_slice(&length.to_le_bytes());
    }
}

/// How long the message at the front of `buf` is, once its header has arrived (TCP framing).
pub fn frame_len(buf: &[u8]) -> Option<usize> {
    (buf.len() >= HEADER_LEN)
        .then(|| HEADER_LEN + usize::from(u16::from_le_bytes([buf[2], buf[3]])))
}

/// An encapsulation message.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct EncapRepr {
    /// Command.
    pub command: u16,
    /// Session handle.
    pub session: u32,
    /// Status.
    pub status: u32,
    /// Sender context, echoed in the reply.
    pub context: [u8; 8],
    /// Options (must be 0).
    pub options: u32,
    /// The command's data.
    pub data: Vec<u8>,
}

impl EncapRepr {
    /// Parses one whole message.
    pub fn parse(bytes: &[u8]) -> Result<EncapRepr, Error> {
        let f = EncapFrame::new_checked(bytes)?;
        Ok(EncapRepr {
            command: f.command().0,
            session: f.session(),
            status: f.status().0,
            context: f.context(),
            options: f.options(),
            data: f.data().to_vec(),
        })
    }

    /// The reply to this message: same command, session and context, with `status` and `data`.
    pub fn reply(&self, status: EncapStatus, data: Vec<u8>) -> EncapRepr {
        EncapRepr {
            command: self.command,
            session: self.session,
            status: status.0,
            context: self.context,
            options: 0,
            data,
        }
    }

    /// The message's bytes.
    pub fn emit(&self) -> Result<Vec<u8>, Error> {
        let len = len16("encapsulation data", self.data.len())?;
        let mut out = Vec::with_capacity(HEADER_LEN + self.data.len());
        out.put_u16(self.command);
        out.put_u16(len);
        out.put_u32(self.session);
        out.put_u32(self.status);
        out.extend_from_slice(&self.context);
        out.put_u32(self.options);
        out.extend_from_slice(&self.data);
        Ok(out)
    }
}

/// RegisterSession's data: protocol version (1) and options (0).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RegisterSession {
    /// Protocol version.
    pub version: u16,
    /// Option flags.
    pub options: u16,
}

impl RegisterSession {
    /// The only version there is.
    pub const V1: RegisterSession = RegisterSession {
        version: 1,
        options: 0,
    };

    /// Parses the 4 data bytes.
    pub fn parse(data: &[u8]) -> Result<RegisterSession, Error> {
        let mut r = Reader::new(data);
        let rs = RegisterSession {
            version: r.u16("RegisterSession protocol version")?,
            options: r.u16("RegisterSession options")?,
        };
        r.finish("RegisterSession data")?;
        Ok(rs)
    }

    /// The 4 data bytes.
    pub fn emit(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(4);
        out.put_u16(self.version);
        out.put_u16(self.options);
        out
    }
}

/// The data of SendRRData and SendUnitData: interface handle (0 = CIP), timeout, and a common
/// packet format list.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SendData {
    /// Interface handle; 0 for CIP.
    pub interface: u32,
    /// Timeout in seconds (SendRRData; 0 for SendUnitData).
    pub timeout: u16,
    /// The items.
    pub cpf: super::cpf::Cpf,
}

impl SendData {
    /// Parses the data of a SendRRData/SendUnitData message.
    pub fn parse(data: &[u8]) -> Result<SendData, Error> {
        let mut r = Reader::new(data);
        let interface = r.u32("interface handle")?;
        let timeout = r.u16("timeout")?;
        let cpf = super::cpf::Cpf::parse(r.rest())?;
        Ok(SendData {
            interface,
            timeout,
            cpf,
        })
    }

    /// The bytes.
    pub fn emit(&self) -> Result<Vec<u8>, Error> {
        let mut out = Vec::with_capacity(64);
        out.put_u32(self.interface);
        out.put_u16(self.timeout);
        self.cpf.emit_into(&mut out)?;
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// RegisterSession as every scanner sends it.
    const REGISTER: [u8; 28] = [
        0x65, 0x00, 0x04, 0x00, 0, 0, 0, 0, 0, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 0, 0, 0, 0, 0x01,
        0x00, 0x00, 0x00,
    ];

    #[test]
    fn register_session_round_trips() {
        let m = EncapRepr::parse(&REGISTER).unwrap();
        assert_eq!(Command(m.command), Command::REGISTER_SESSION);
        assert_eq!(m.context, [1, 2, 3, 4, 5, 6, 7, 8]);
        assert_eq!(
            RegisterSession::parse(&m.data).unwrap(),
            RegisterSession::V1
        );
        assert_eq!(m.emit().unwrap(), REGISTER);
        assert_eq!(frame_len(&REGISTER[..24]), Some(28));
        assert_eq!(frame_len(&REGISTER[..23]), None);
    }

    #[test]
    fn the_length_field_is_read_and_set_through_the_view() {
        let mut b = REGISTER;
        let mut f = EncapFrame::new_checked(&mut b[..]).unwrap();
        assert_eq!(f.length(), 4);
        f.set_length(516);
        // Bytes 2–3, little-endian; nothing else moves.
        assert_eq!(b[2..4], [0x04, 0x02]);
        assert_eq!(b[..2], REGISTER[..2]);
        assert_eq!(b[4..], REGISTER[4..]);
        assert_eq!(frame_len(&b), Some(24 + 516));
        assert!(matches!(
            EncapFrame::new_checked(&b[..]),
            Err(Error::Length {
                value: 516,
                available: 4,
                ..
            })
        ));
    }

    #[test]
    fn a_lying_length_is_an_error() {
        let mut b = REGISTER;
        b[2] = 5;
        assert_eq!(
            EncapRepr::parse(&b),
            Err(Error::Length {
                field: "encapsulation length",
                value: 5,
                available: 4
            })
        );
        assert!(matches!(
            EncapRepr::parse(&REGISTER[..10]),
            Err(Error::Truncated {
                need: 24,
                got: 10,
                ..
            })
        ));
    }

    #[test]
    fn names() {
        assert_eq!(Command(0x6F).to_string(), "SendRRData");
        assert_eq!(Command(0x99).to_string(), "command 0099h");
        assert_eq!(
            EncapStatus::INVALID_SESSION.to_string(),
            "0064h (invalid session handle)"
        );
    }

    mod properties {
        use super::*;
        use crate::enip::cpf::tests::properties::cpf;
        use proptest::collection::vec;
        use proptest::prelude::*;

        fn encap() -> impl Strategy<Value = EncapRepr> {
            (
                any::<u16>(),
                any::<u32>(),
                any::<u32>(),
                any::<[u8; 8]>(),
                any::<u32>(),
                vec(any::<u8>(), 0..=64),
            )
                .prop_map(|(command, session, status, context, options, data)| {
                    EncapRepr {
                        command,
                        session,
                        status,
                        context,
                        options,
                        data,
                    }
                })
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn emit_then_parse_round_trips(e in encap()) {
                let b = e.emit().unwrap();
                prop_assert_eq!(frame_len(&b), Some(b.len()));
                prop_assert_eq!(EncapRepr::parse(&b), Ok(e));
            }

            #[test]
            fn register_session_round_trips(version in any::<u16>(), options in any::<u16>()) {
                let r = RegisterSession { version, options };
                prop_assert_eq!(RegisterSession::parse(&r.emit()), Ok(r));
            }

            #[test]
            fn send_data_round_trips(interface in any::<u32>(), timeout in any::<u16>(), cpf in cpf()) {
                let s = SendData { interface, timeout, cpf };
                prop_assert_eq!(SendData::parse(&s.emit().unwrap()), Ok(s));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in vec(any::<u8>(), 0..48)) {
                let _ = EncapRepr::parse(&bytes);
                let _ = frame_len(&bytes);
                let _ = RegisterSession::parse(&bytes);
                let _ = SendData::parse(&bytes);
            }
        }
    }
}
