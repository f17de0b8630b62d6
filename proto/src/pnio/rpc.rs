//! Connectionless DCE/RPC as PROFINET IO context management uses it (UDP port 34964,
//! [`super::RPC_PORT`]): the 80-byte header of DCE 1.1 RPC (The Open Group C706 §12.5
//! "Connectionless RPC PDUs"), the NDR layer of the PNIO calls (IEC 61158-6-10 "IPNIO_Connect,
//! _Release, _Read, _Write, _Control, _ReadImplicit"), and the status of a reject or fault.
//!
//! | bytes | header field |
//! |---|---|
//! | 0 | rpc_vers (4) |
//! | 1 | ptype ([`PacketType`]) |
//! | 2 | flags1 ([`Flags1`]) |
//! | 3 | flags2 |
//! | 4–6 | drep ([`Drep`]): byte 0 high nibble 1 little-endian / 0 big-endian, low nibble ASCII; byte 1 IEEE float |
//! | 7 | serial_hi |
//! | 8–23 | object UUID |
//! | 24–39 | interface UUID |
//! | 40–55 | activity UUID |
//! | 56–59 | server boot time |
//! | 60–63 | interface version |
//! | 64–67 | sequence number |
//! | 68–69 | opnum ([`Opnum`]) |
//! | 70–71 | interface hint |
//! | 72–73 | activity hint |
//! | 74–75 | fragment length (the body's) |
//! | 76–77 | fragment number |
//! | 78 | auth_proto |
//! | 79 | serial_lo |
//! | 80.. | body |
//!
//! Integers and the first three fields of each UUID (time_low u32, time_mid u16,
//! time_hi_and_version u16) are in the byte order drep names; the last 8 UUID bytes are a byte
//! string. Every parser takes either order and emits the order its [`Drep`] gives.
//!
//! The PNIO body (NDR, C706 §14 "conformant varying array of bytes"): a request is ArgsMaximum,
//! ArgsLength, MaximumCount, Offset, ActualCount (u32 each, drep order) and ActualCount bytes
//! of PNIO blocks ([`NdrRequest`]); a response starts with the PNIOStatus instead of
//! ArgsMaximum ([`NdrResponse`]). The PNIOStatus there is a u32 in drep order too, so a
//! little-endian response carries ErrorCode2 first (Wireshark's packet-dcerpc-pn-io.c
//! reverses the four bytes for a little-endian drep). The blocks themselves are always
//! big-endian ([`super::block`]).
//!
//! A reject or fault carries one u32 status in drep order ([`NcaStatus`], C706 appendix E):
//! a device refuses a call to an interface it does not serve with a reject
//! [`NcaStatus::UNK_IF`], an opnum it does not know with [`NcaStatus::OP_RNG_ERROR`].
//!
//! Every parser returns `Err` on malformed input and never panics.

use std::fmt;

use crate::wire::{Error, Reader};

/// Defines an open code: a newtype over an integer with named constants, whose Debug and
/// Display print the name or the hex value.
macro_rules! open_code {
    ($(#[$m:meta])* $name:ident($repr:ty, $digits:literal) {
        $($(#[$cm:meta])* $c:ident = $v:expr, $text:expr;)*
    }) => {
        $(#[$m])*
        #[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
        pub struct $name(pub $repr);

        impl $name {
            $($(#[$cm])* pub const $c: $name = $name($v);)*

            /// Every defined code.
            pub const ALL: &'static [$name] = &[$($name::$c),*];

            /// The code's name as the standard prints it, if defined.
            pub fn name(self) -> Option<&'static str> {
                match self {
                    $($name::$c => Some($text),)*
                    _ => None,
                }
            }
        }

        impl std::fmt::Debug for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                match self.name() {
                    Some(n) => write!(f, "{n}({:0w$X}h)", self.0, w = $digits),
                    None => write!(f, "{}({:0w$X}h)", stringify!($name), self.0, w = $digits),
                }
            }
        }

        impl std::fmt::Display for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                match self.name() {
                    Some(n) => f.write_str(n),
                    None => write!(f, "{:0w$X}h", self.0, w = $digits),
                }
            }
        }
    };
}
pub(crate) use open_code;

mod ndr;
mod uuid;

pub use ndr::{NdrRequest, NdrResponse, NDR_REQUEST_LEN, NDR_RESPONSE_LEN};
pub use uuid::Uuid;

/// Length of the connectionless header.
pub const HEADER_LEN: usize = 80;
/// rpc_vers of connectionless RPC (C706 §12.5.2.1).
pub const RPC_VERSION: u8 = 4;
/// The interface version of the four PNIO interfaces: major 1, minor 0 (u32 1).
pub const PNIO_INTERFACE_VERSION: u32 = 1;
/// The interface version of the endpoint mapper (3.0).
pub const EPM_INTERFACE_VERSION: u32 = 3;
/// "No hint" in the interface and activity hint fields (C706 §12.5.2.9).
pub const NO_HINT: u16 = 0xFFFF;

open_code! {
    /// The PDU type (C706 §12.5.2.2; the low 5 bits of byte 1).
    PacketType(u8, 2) {
        /// A call (client → server).
        REQUEST = 0, "Request";
        /// Is the call still running? (client → server).
        PING = 1, "Ping";
        /// The call's result (server → client).
        RESPONSE = 2, "Response";
        /// The call failed in the server (server → client).
        FAULT = 3, "Fault";
        /// Answer to a ping: still working.
        WORKING = 4, "Working";
        /// Answer to a ping: no such call.
        NOCALL = 5, "Nocall";
        /// The call was refused (server → client).
        REJECT = 6, "Reject";
        /// The client got the response (client → server).
        ACK = 7, "Ack";
        /// Cancel the call (client → server).
        CL_CANCEL = 8, "Cl_cancel";
        /// Fragment acknowledge.
        FACK = 9, "Fack";
        /// Answer to a cancel.
        CANCEL_ACK = 10, "Cancel_ack";
    }
}

open_code! {
    /// The operations of the PNIO interfaces (IEC 61158-6-10 "IPNIO" opnums). The endpoint
    /// mapper numbers its own (Lookup 2, LookupHandleFree 4).
    Opnum(u16, 4) {
        /// IPNIO_Connect: establish an AR.
        CONNECT = 0, "Connect";
        /// IPNIO_Release: end an AR.
        RELEASE = 1, "Release";
        /// IPNIO_Read: read a record.
        READ = 2, "Read";
        /// IPNIO_Write: write a record.
        WRITE = 3, "Write";
        /// IPNIO_Control: PrmEnd, ApplicationReady.
        CONTROL = 4, "Control";
        /// IPNIO_ReadImplicit: read a record without an AR.
        READ_IMPLICIT = 5, "ReadImplicit";
    }
}

open_code! {
    /// The status of a reject or fault body (C706 appendix E "Reject status codes").
    NcaStatus(u32, 8) {
        /// nca_rpc_version_mismatch.
        RPC_VERSION_MISMATCH = 0x1C00_0008, "nca_rpc_version_mismatch";
        /// nca_unspec_reject.
        UNSPEC_REJECT = 0x1C00_0009, "nca_unspec_reject";
        /// nca_s_bad_actid.
        BAD_ACTID = 0x1C00_000A, "nca_s_bad_actid";
        /// nca_who_are_you_failed.
        WHO_ARE_YOU_FAILED = 0x1C00_000B, "nca_who_are_you_failed";
        /// nca_manager_not_entered.
        MANAGER_NOT_ENTERED = 0x1C00_000C, "nca_manager_not_entered";
        /// nca_op_rng_error: the opnum is out of the interface's range.
        OP_RNG_ERROR = 0x1C01_0002, "nca_op_rng_error";
        /// nca_unk_if: the server does not serve the interface.
        UNK_IF = 0x1C01_0003, "nca_unk_if";
        /// nca_wrong_boot_time.
        WRONG_BOOT_TIME = 0x1C01_0006, "nca_wrong_boot_time";
        /// nca_s_you_crashed.
        YOU_CRASHED = 0x1C01_0009, "nca_s_you_crashed";
        /// nca_proto_error.
        PROTO_ERROR = 0x1C01_000B, "nca_proto_error";
        /// nca_out_args_too_big.
        OUT_ARGS_TOO_BIG = 0x1C01_0013, "nca_out_args_too_big";
        /// nca_server_too_busy.
        SERVER_TOO_BUSY = 0x1C01_0014, "nca_server_too_busy";
        /// nca_unsupported_type.
        UNSUPPORTED_TYPE = 0x1C01_0017, "nca_unsupported_type";
    }
}

impl NcaStatus {
    /// The status of a reject or fault body: its first 4 bytes in the drep's order (bytes after
    /// them are ignored, as stacks differ in what they append).
    pub fn parse(body: &[u8], drep: Drep) -> Result<NcaStatus, Error> {
        let mut r = Reader::new(body);
        Ok(NcaStatus(u32d(&mut r, drep, "reject/fault status")?))
    }

    /// The 4 bytes of a reject or fault body.
    pub fn emit(self, drep: Drep) -> [u8; 4] {
        if drep.is_little_endian() {
            self.0.to_le_bytes()
        } else {
            self.0.to_be_bytes()
        }
    }
}

/// flags1 of the header (C706 §12.5.2.3). Open: any bits round-trip.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Flags1(pub u8);

impl Flags1 {
    /// Last fragment of a fragmented PDU.
    pub const LAST_FRAG: Flags1 = Flags1(0x02);
    /// A fragment.
    pub const FRAG: Flags1 = Flags1(0x04);
    /// No fragment acknowledge wanted.
    pub const NO_FACK: Flags1 = Flags1(0x08);
    /// Maybe semantics (no response).
    pub const MAYBE: Flags1 = Flags1(0x10);
    /// Idempotent call.
    pub const IDEMPOTENT: Flags1 = Flags1(0x20);
    /// Broadcast call.
    pub const BROADCAST: Flags1 = Flags1(0x40);

    /// Whether every bit of `other` is set.
    pub fn contains(self, other: Flags1) -> bool {
        self.0 & other.0 == other.0
    }
}

impl std::ops::BitOr for Flags1 {
    type Output = Flags1;
    fn bitor(self, rhs: Flags1) -> Flags1 {
        Flags1(self.0 | rhs.0)
    }
}

impl fmt::Debug for Flags1 {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const NAMES: [(u8, &str); 6] = [
            (0x02, "LastFrag"),
            (0x04, "Frag"),
            (0x08, "NoFack"),
            (0x10, "Maybe"),
            (0x20, "Idempotent"),
            (0x40, "Broadcast"),
        ];
        write!(f, "Flags1({:02X}h", self.0)?;
        for (bit, name) in NAMES {
            if self.0 & bit != 0 {
                write!(f, " {name}")?;
            }
        }
        f.write_str(")")
    }
}

/// flags2 bit "cancel pending" (C706 §12.5.2.4).
pub const FLAGS2_CANCEL_PENDING: u8 = 0x02;

/// The data representation (C706 §14.1 "format label"): byte 0 integer order (high nibble) and
/// character set (low nibble), byte 1 floating point, byte 2 reserved.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Drep(pub [u8; 3]);

impl Drep {
    /// Little-endian integers, ASCII, IEEE floats: what PC-based controllers send.
    pub const LITTLE_ENDIAN: Drep = Drep([0x10, 0x00, 0x00]);
    /// Big-endian integers, ASCII, IEEE floats.
    pub const BIG_ENDIAN: Drep = Drep([0x00, 0x00, 0x00]);

    /// Whether integers are little-endian (high nibble of byte 0 is 1).
    pub fn is_little_endian(self) -> bool {
        self.0[0] & 0xF0 == 0x10
    }

    fn u16(self, v: u16) -> [u8; 2] {
        if self.is_little_endian() {
            v.to_le_bytes()
        } else {
            v.to_be_bytes()
        }
    }

    fn u32(self, v: u32) -> [u8; 4] {
        if self.is_little_endian() {
            v.to_le_bytes()
        } else {
            v.to_be_bytes()
        }
    }
}

impl Default for Drep {
    fn default() -> Drep {
        Drep::LITTLE_ENDIAN
    }
}

impl fmt::Debug for Drep {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let order = if self.is_little_endian() { "LE" } else { "BE" };
        write!(
            f,
            "Drep({order} {:02X} {:02X} {:02X})",
            self.0[0], self.0[1], self.0[2]
        )
    }
}

fn u16d(r: &mut Reader<'_>, drep: Drep, what: &'static str) -> Result<u16, Error> {
    if drep.is_little_endian() {
        r.u16(what)
    } else {
        r.u16_be(what)
    }
}

fn u32d(r: &mut Reader<'_>, drep: Drep, what: &'static str) -> Result<u32, Error> {
    if drep.is_little_endian() {
        r.u32(what)
    } else {
        r.u32_be(what)
    }
}

/// Field offsets of the header.
mod field {
    pub(super) const VERSION: usize = 0;
    pub(super) const PTYPE: usize = 1;
    pub(super) const FLAGS1: usize = 2;
    pub(super) const DREP: usize = 4;
    pub(super) const OBJECT: usize = 8;
    pub(super) const INTERFACE: usize = 24;
    pub(super) const ACTIVITY: usize = 40;
    pub(super) const SEQNUM: usize = 64;
    pub(super) const OPNUM: usize = 68;
    pub(super) const FRAG_LEN: usize = 74;
}

/// A checked view of a connectionless RPC PDU: the 80-byte header is there and the fragment
/// length does not pass the buffer. Only [`RpcRepr::parse`] checks the rest.
#[derive(Debug, Clone)]
pub struct RpcPacket<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> RpcPacket<T> {
    /// Checks the header and the fragment length.
    pub fn new_checked(buffer: T) -> Result<Self, Error> {
        let got = buffer.as_ref().len();
        if got < HEADER_LEN {
            return Err(Error::Truncated {
                what: "RPC header",
                need: HEADER_LEN,
                got,
            });
        }
        let p = RpcPacket { buffer };
        let len = usize::from(p.fragment_length());
        if len > got - HEADER_LEN {
            return Err(Error::Length {
                field: "RPC fragment length",
                value: len,
                available: got - HEADER_LEN,
            });
        }
        Ok(p)
    }

    fn b(&self) -> &[u8] {
        self.buffer.as_ref()
    }

    fn u16_at(&self, at: usize) -> u16 {
        let b = [self.b()[at], self.b()[at + 1]];
        if self.drep().is_little_endian() {
            u16::from_le_bytes(b)
        } else {
            u16::from_be_bytes(b)
        }
    }

    fn uuid_at(&self, at: usize) -> Uuid {
        let mut b = [0u8; 16];
        b.copy_from_slice(&self.b()[at..at + 16]);
        Uuid::from_wire(b, self.drep().is_little_endian())
    }

    /// rpc_vers.
    pub fn version(&self) -> u8 {
        self.b()[field::VERSION]
    }

    /// The PDU type (low 5 bits).
    pub fn packet_type(&self) -> PacketType {
        PacketType(self.b()[field::PTYPE] & 0x1F)
    }

    /// flags1.
    pub fn flags1(&self) -> Flags1 {
        Flags1(self.b()[field::FLAGS1])
    }

    /// The data representation.
    pub fn drep(&self) -> Drep {
        let b = self.b();
        Drep([b[field::DREP], b[field::DREP + 1], b[field::DREP + 2]])
    }

    /// The object UUID.
    pub fn object(&self) -> Uuid {
        self.uuid_at(field::OBJECT)
    }

    /// The interface UUID.
    pub fn interface(&self) -> Uuid {
        self.uuid_at(field::INTERFACE)
    }

    /// The activity UUID.
    pub fn activity(&self) -> Uuid {
        self.uuid_at(field::ACTIVITY)
    }

    /// The sequence number.
    pub fn sequence_number(&self) -> u32 {
        let b = &self.b()[field::SEQNUM..field::SEQNUM + 4];
        let a = [b[0], b[1], b[2], b[3]];
        if self.drep().is_little_endian() {
            u32::from_le_bytes(a)
        } else {
            u32::from_be_bytes(a)
        }
    }

    /// The opnum.
    pub fn opnum(&self) -> Opnum {
        Opnum(self.u16_at(field::OPNUM))
    }

    /// The fragment (body) length.
    pub fn fragment_length(&self) -> u16 {
        self.u16_at(field::FRAG_LEN)
    }

    /// The body: fragment-length bytes after the header.
    pub fn body(&self) -> &[u8] {
        &self.b()[HEADER_LEN..HEADER_LEN + usize::from(self.fragment_length())]
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> RpcPacket<T> {
    /// Sets rpc_vers (to make a malformed PDU).
    pub fn set_version(&mut self, v: u8) {
        self.buffer.as_mut()[field::VERSION] = v;
    }

    /// Sets the PDU type.
    pub fn set_packet_type(&mut self, t: PacketType) {
        self.buffer.as_mut()[field::PTYPE] = t.0;
    }

    /// Sets the fragment length in the packet's byte order (a value past the buffer makes a
    /// malformed PDU, which [`RpcPacket::new_checked`] then refuses).
    pub fn set_fragment_length(&mut self, len: u16) {
        let b = self.drep().u16(len);
        self.buffer.as_mut()[field::FRAG_LEN..field::FRAG_LEN + 2].copy_from_slice(&b);
    }

    /// Sets the interface UUID in the packet's byte order.
    pub fn set_interface(&mut self, u: Uuid) {
        let w = u.to_wire(self.drep().is_little_endian());
        self.buffer.as_mut()[field::INTERFACE..field::INTERFACE + 16].copy_from_slice(&w);
    }

    /// Sets the opnum in the packet's byte order.
    pub fn set_opnum(&mut self, op: Opnum) {
        let b = self.drep().u16(op.0);
        self.buffer.as_mut()[field::OPNUM..field::OPNUM + 2].copy_from_slice(&b);
    }
}

/// A whole connectionless RPC PDU.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RpcRepr {
    /// ptype.
    pub packet_type: PacketType,
    /// flags1.
    pub flags1: Flags1,
    /// flags2 ([`FLAGS2_CANCEL_PENDING`]).
    pub flags2: u8,
    /// The data representation: the byte order of the header's integers and UUID fields and
    /// of the NDR layer.
    pub drep: Drep,
    /// The serial number: serial_hi (byte 7) in the high byte, serial_lo (byte 79) in the low.
    pub serial: u16,
    /// The object UUID (a PNIO object: [`Uuid::pnio_object`]).
    pub object: Uuid,
    /// The interface UUID ([`Uuid::PNIO_DEVICE_INTERFACE`] …).
    pub interface: Uuid,
    /// The activity UUID: one per client activity (AR), the same for its calls.
    pub activity: Uuid,
    /// The server boot time (0 from a client that does not know it).
    pub server_boot_time: u32,
    /// The interface version ([`PNIO_INTERFACE_VERSION`]).
    pub interface_version: u32,
    /// The sequence number: a client counts its calls; a response carries its request's.
    pub sequence_number: u32,
    /// The operation.
    pub opnum: Opnum,
    /// Interface hint ([`NO_HINT`]).
    pub interface_hint: u16,
    /// Activity hint ([`NO_HINT`]).
    pub activity_hint: u16,
    /// The fragment number.
    pub fragment_number: u16,
    /// auth_proto (0: none).
    pub auth_proto: u8,
    /// The body (its length is the header's fragment length).
    pub body: Vec<u8>,
}

impl RpcRepr {
    /// A PNIO request, little-endian, idempotent, no hints, fragment 0.
    pub fn request(
        object: Uuid,
        interface: Uuid,
        activity: Uuid,
        sequence_number: u32,
        opnum: Opnum,
        body: Vec<u8>,
    ) -> RpcRepr {
        RpcRepr {
            packet_type: PacketType::REQUEST,
            flags1: Flags1::IDEMPOTENT,
            flags2: 0,
            drep: Drep::LITTLE_ENDIAN,
            serial: 0,
            object,
            interface,
            activity,
            server_boot_time: 0,
            interface_version: PNIO_INTERFACE_VERSION,
            sequence_number,
            opnum,
            interface_hint: NO_HINT,
            activity_hint: NO_HINT,
            fragment_number: 0,
            auth_proto: 0,
            body,
        }
    }

    /// The answer of type `packet_type` to this request: its object, interface, activity,
    /// boot time, version, sequence number, opnum and hints, in its byte order, flags no-fack
    /// and idempotent (as p-net answers).
    pub fn reply(&self, packet_type: PacketType, body: Vec<u8>) -> RpcRepr {
        RpcRepr {
            packet_type,
            flags1: Flags1::NO_FACK | Flags1::IDEMPOTENT,
            flags2: 0,
            serial: 0,
            fragment_number: 0,
            auth_proto: 0,
            body,
            ..self.clone()
        }
    }

    /// A reject of this request with `status` ([`NcaStatus::UNK_IF`] for an interface the
    /// server does not serve).
    pub fn reject(&self, status: NcaStatus) -> RpcRepr {
        self.reply(PacketType::REJECT, status.emit(self.drep).to_vec())
    }

    /// A fault answer to this request with `status`.
    pub fn fault(&self, status: NcaStatus) -> RpcRepr {
        self.reply(PacketType::FAULT, status.emit(self.drep).to_vec())
    }

    /// The status of a reject or fault.
    pub fn nca_status(&self) -> Result<NcaStatus, Error> {
        NcaStatus::parse(&self.body, self.drep)
    }

    /// Parses a PDU; rpc_vers must be 4 and the body must fill the rest of the buffer.
    pub fn parse<T: AsRef<[u8]>>(packet: &RpcPacket<T>) -> Result<RpcRepr, Error> {
        let bytes = packet.b();
        if packet.version() != RPC_VERSION {
            return Err(Error::Invalid {
                field: "RPC version",
                value: u32::from(packet.version()),
                why: "must be 4",
            });
        }
        let drep = packet.drep();
        let le = drep.is_little_endian();
        let mut r = Reader::new(bytes);
        r.bytes(2, "RPC version/ptype")?;
        let flags1 = Flags1(r.u8("RPC flags1")?);
        let flags2 = r.u8("RPC flags2")?;
        r.bytes(3, "RPC drep")?;
        let serial_hi = r.u8("RPC serial_hi")?;
        let object = Uuid::read(&mut r, le, "RPC object UUID")?;
        let interface = Uuid::read(&mut r, le, "RPC interface UUID")?;
        let activity = Uuid::read(&mut r, le, "RPC activity UUID")?;
        let server_boot_time = u32d(&mut r, drep, "RPC server boot time")?;
        let interface_version = u32d(&mut r, drep, "RPC interface version")?;
        let sequence_number = u32d(&mut r, drep, "RPC sequence number")?;
        let opnum = Opnum(u16d(&mut r, drep, "RPC opnum")?);
        let interface_hint = u16d(&mut r, drep, "RPC interface hint")?;
        let activity_hint = u16d(&mut r, drep, "RPC activity hint")?;
        let len = usize::from(u16d(&mut r, drep, "RPC fragment length")?);
        let fragment_number = u16d(&mut r, drep, "RPC fragment number")?;
        let auth_proto = r.u8("RPC auth_proto")?;
        let serial_lo = r.u8("RPC serial_lo")?;
        let body = r.bytes(len, "RPC body")?.to_vec();
        r.finish("RPC PDU")?;
        Ok(RpcRepr {
            packet_type: packet.packet_type(),
            flags1,
            flags2,
            drep,
            serial: u16::from_be_bytes([serial_hi, serial_lo]),
            object,
            interface,
            activity,
            server_boot_time,
            interface_version,
            sequence_number,
            opnum,
            interface_hint,
            activity_hint,
            fragment_number,
            auth_proto,
            body,
        })
    }

    /// Parses a UDP payload.
    pub fn parse_bytes(bytes: &[u8]) -> Result<RpcRepr, Error> {
        RpcRepr::parse(&RpcPacket::new_checked(bytes)?)
    }

    /// Header and body length.
    pub fn buffer_len(&self) -> usize {
        HEADER_LEN + self.body.len()
    }

    /// The UDP payload. A body longer than the 16-bit fragment length is [`Error::TooLong`].
    pub fn emit(&self) -> Result<Vec<u8>, Error> {
        let len = u16::try_from(self.body.len()).map_err(|_| Error::TooLong {
            what: "RPC body",
            len: self.body.len(),
            max: usize::from(u16::MAX),
        })?;
        let d = self.drep;
        let le = d.is_little_endian();
        let [serial_hi, serial_lo] = self.serial.to_be_bytes();
        let mut b = Vec::with_capacity(self.buffer_len());
        b.extend([RPC_VERSION, self.packet_type.0, self.flags1.0, self.flags2]);
        b.extend(d.0);
        b.push(serial_hi);
        b.extend(self.object.to_wire(le));
        b.extend(self.interface.to_wire(le));
        b.extend(self.activity.to_wire(le));
        b.extend(d.u32(self.server_boot_time));
        b.extend(d.u32(self.interface_version));
        b.extend(d.u32(self.sequence_number));
        b.extend(d.u16(self.opnum.0));
        b.extend(d.u16(self.interface_hint));
        b.extend(d.u16(self.activity_hint));
        b.extend(d.u16(len));
        b.extend(d.u16(self.fragment_number));
        b.extend([self.auth_proto, serial_lo]);
        debug_assert_eq!(b.len(), HEADER_LEN);
        b.extend(&self.body);
        Ok(b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn connect_bytes() -> Vec<u8> {
        let mut b = Vec::new();
        b.extend([0x04]); // rpc_vers 4
        b.extend([0x00]); // ptype Request
        b.extend([0x20]); // flags1 idempotent
        b.extend([0x00]); // flags2
        b.extend([0x10, 0x00, 0x00]); // drep: little-endian, ASCII, IEEE
        b.extend([0x00]); // serial_hi
                          // object DEA00000-6C97-11D1-8271-0001-0010-002A (instance 1, device 0010h, vendor
                          // 002Ah): time_low, time_mid, time_hi little-endian, the rest as is
        b.extend([0x00, 0x00, 0xA0, 0xDE, 0x97, 0x6C, 0xD1, 0x11]);
        b.extend([0x82, 0x71, 0x00, 0x01, 0x00, 0x10, 0x00, 0x2A]);
        // interface DEA00001-6C97-11D1-8271-00A02442DF7D
        b.extend([0x01, 0x00, 0xA0, 0xDE, 0x97, 0x6C, 0xD1, 0x11]);
        b.extend([0x82, 0x71, 0x00, 0xA0, 0x24, 0x42, 0xDF, 0x7D]);
        // activity 01020304-0506-0708-090A-0B0C0D0E0F10
        b.extend([0x04, 0x03, 0x02, 0x01, 0x06, 0x05, 0x08, 0x07]);
        b.extend([0x09, 0x0A, 0x0B, 0x0C, 0x0D, 0x0E, 0x0F, 0x10]);
        b.extend([0x00, 0x00, 0x00, 0x00]); // server boot time 0
        b.extend([0x01, 0x00, 0x00, 0x00]); // interface version 1
        b.extend([0x07, 0x00, 0x00, 0x00]); // sequence number 7
        b.extend([0x00, 0x00]); // opnum Connect
        b.extend([0xFF, 0xFF]); // interface hint: none
        b.extend([0xFF, 0xFF]); // activity hint: none
        b.extend([0x04, 0x00]); // fragment length 4
        b.extend([0x00, 0x00]); // fragment number 0
        b.extend([0x00]); // auth_proto: none
        b.extend([0x00]); // serial_lo
        b.extend([0xAA, 0xBB, 0xCC, 0xDD]); // body
        b
    }

    #[test]
    fn connect_request_header_parses_and_round_trips() {
        let bytes = connect_bytes();
        let p = RpcPacket::new_checked(&bytes[..]).unwrap();
        assert_eq!(p.packet_type(), PacketType::REQUEST);
        assert_eq!(p.opnum(), Opnum::CONNECT);
        assert_eq!(p.interface(), Uuid::PNIO_DEVICE_INTERFACE);
        assert_eq!(p.sequence_number(), 7);
        assert_eq!(p.body(), [0xAA, 0xBB, 0xCC, 0xDD]);
        let r = RpcRepr::parse(&p).unwrap();
        assert_eq!(r.object, Uuid::pnio_object(1, 0x10, 0x2A));
        assert_eq!(
            r.activity.to_string(),
            "01020304-0506-0708-090a-0b0c0d0e0f10"
        );
        assert_eq!(r.interface_version, PNIO_INTERFACE_VERSION);
        assert_eq!((r.interface_hint, r.activity_hint), (NO_HINT, NO_HINT));
        assert!(r.flags1.contains(Flags1::IDEMPOTENT));
        assert_eq!(r.emit().unwrap(), bytes);
        let built = RpcRepr::request(
            r.object,
            Uuid::PNIO_DEVICE_INTERFACE,
            r.activity,
            7,
            Opnum::CONNECT,
            vec![0xAA, 0xBB, 0xCC, 0xDD],
        );
        assert_eq!(built, r);
    }

    #[test]
    fn big_endian_header_round_trips() {
        let mut r = RpcRepr::parse_bytes(&connect_bytes()).unwrap();
        r.drep = Drep::BIG_ENDIAN;
        r.serial = 0x0102;
        let b = r.emit().unwrap();
        // drep 00 00 00; serial_hi 01 at byte 7 and serial_lo 02 at byte 79.
        assert_eq!(b[4..8], [0x00, 0x00, 0x00, 0x01]);
        assert_eq!(b[79], 0x02);
        // The interface UUID in canonical order, the sequence number and fragment length BE.
        assert_eq!(b[24..40], Uuid::PNIO_DEVICE_INTERFACE.0);
        assert_eq!(b[64..68], [0, 0, 0, 7]);
        assert_eq!(b[74..76], [0, 4]);
        assert_eq!(RpcRepr::parse_bytes(&b), Ok(r));
    }

    #[test]
    fn reject_of_an_unknown_interface() {
        let mut req = RpcRepr::parse_bytes(&connect_bytes()).unwrap();
        req.interface = Uuid::PNIO_SUPERVISOR_INTERFACE;
        let rej = req.reject(NcaStatus::UNK_IF);
        let b = rej.emit().unwrap();
        // ptype 6 Reject; flags1 no-fack | idempotent; body 1C010003h little-endian.
        assert_eq!(b[1..3], [0x06, 0x28]);
        assert_eq!(b[80..], [0x03, 0x00, 0x01, 0x1C]);
        let back = RpcRepr::parse_bytes(&b).unwrap();
        assert_eq!(back.nca_status(), Ok(NcaStatus::UNK_IF));
        assert_eq!(back.sequence_number, 7);
        assert_eq!(back.activity, req.activity);
        assert_eq!(format!("{:?}", NcaStatus::UNK_IF), "nca_unk_if(1C010003h)");
        assert_eq!(NcaStatus(0x1234).to_string(), "00001234h");
        assert_eq!(
            NcaStatus::parse(&[0x1C, 0x01, 0x00, 0x02], Drep::BIG_ENDIAN),
            Ok(NcaStatus::OP_RNG_ERROR)
        );
        assert!(matches!(
            NcaStatus::parse(&[0x1C], Drep::BIG_ENDIAN),
            Err(Error::Truncated {
                need: 4,
                got: 1,
                ..
            })
        ));
        let f = req.fault(NcaStatus::OP_RNG_ERROR);
        assert_eq!(f.packet_type, PacketType::FAULT);
    }

    #[test]
    fn malformed_headers_are_typed_errors() {
        let bytes = connect_bytes();
        assert_eq!(
            RpcRepr::parse_bytes(&bytes[..79]),
            Err(Error::Truncated {
                what: "RPC header",
                need: 80,
                got: 79
            })
        );
        // Fragment length 4 with 3 body bytes.
        assert_eq!(
            RpcRepr::parse_bytes(&bytes[..83]),
            Err(Error::Length {
                field: "RPC fragment length",
                value: 4,
                available: 3
            })
        );
        let mut extra = bytes.clone();
        extra.push(0);
        assert_eq!(
            RpcRepr::parse_bytes(&extra),
            Err(Error::Trailing {
                what: "RPC PDU",
                extra: 1
            })
        );
        let mut v5 = bytes.clone();
        let mut p = RpcPacket::new_checked(&mut v5[..]).unwrap();
        p.set_version(5);
        assert_eq!(
            RpcRepr::parse_bytes(&v5),
            Err(Error::Invalid {
                field: "RPC version",
                value: 5,
                why: "must be 4",
            })
        );
        let mut long = bytes.clone();
        let mut p = RpcPacket::new_checked(&mut long[..]).unwrap();
        p.set_fragment_length(100);
        assert!(matches!(
            RpcPacket::new_checked(&long[..]),
            Err(Error::Length { value: 100, .. })
        ));
        let mut other = bytes;
        let mut p = RpcPacket::new_checked(&mut other[..]).unwrap();
        p.set_interface(Uuid::EPM_INTERFACE);
        p.set_opnum(Opnum(9));
        p.set_packet_type(PacketType::PING);
        let r = RpcRepr::parse_bytes(&other).unwrap();
        assert_eq!(r.interface, Uuid::EPM_INTERFACE);
        assert_eq!(format!("{:?}", r.opnum), "Opnum(0009h)");
        assert_eq!(r.packet_type.to_string(), "Ping");
    }

    mod properties {
        use super::*;
        use proptest::collection::vec;
        use proptest::prelude::*;

        /// Any header the PDU carries: PTYPE 5 bits, any data representation (the integers
        /// and UUIDs follow its byte order), a body up to 64 bytes.
        fn repr() -> impl Strategy<Value = RpcRepr> {
            (
                (
                    0u8..=0x1F,
                    any::<u8>(),
                    any::<u8>(),
                    any::<[u8; 3]>(),
                    any::<u16>(),
                ),
                any::<([u8; 16], [u8; 16], [u8; 16])>(),
                any::<(u32, u32, u32, u16, u16, u16, u16, u8)>(),
                vec(any::<u8>(), 0..64),
            )
                .prop_map(|((ptype, f1, flags2, drep, serial), (o, i, a), n, body)| {
                    RpcRepr {
                        packet_type: PacketType(ptype),
                        flags1: Flags1(f1),
                        flags2,
                        drep: Drep(drep),
                        serial,
                        object: Uuid(o),
                        interface: Uuid(i),
                        activity: Uuid(a),
                        server_boot_time: n.0,
                        interface_version: n.1,
                        sequence_number: n.2,
                        opnum: Opnum(n.3),
                        interface_hint: n.4,
                        activity_hint: n.5,
                        fragment_number: n.6,
                        auth_proto: n.7,
                        body,
                    }
                })
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn emit_then_parse_round_trips(r in repr()) {
                let b = r.emit().unwrap();
                prop_assert_eq!(b.len(), r.buffer_len());
                prop_assert_eq!(RpcRepr::parse_bytes(&b), Ok(r));
            }

            #[test]
            fn nca_status_round_trips(v in any::<u32>(), le in any::<bool>()) {
                let drep = if le { Drep::LITTLE_ENDIAN } else { Drep::BIG_ENDIAN };
                let s = NcaStatus(v);
                prop_assert_eq!(NcaStatus::parse(&s.emit(drep), drep), Ok(s));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in vec(any::<u8>(), 0..120)) {
                let _ = RpcRepr::parse_bytes(&bytes);
            }

            #[test]
            fn parsing_an_arbitrary_header_never_panics(
                head in vec(any::<u8>(), HEADER_LEN - 1),
                body in vec(any::<u8>(), 0..16),
            ) {
                // rpc_vers 4 first, so the header fields are read.
                let mut b = vec![RPC_VERSION];
                b.extend(head);
                b.extend(body);
                let _ = RpcRepr::parse_bytes(&b);
            }
        }
    }
}
