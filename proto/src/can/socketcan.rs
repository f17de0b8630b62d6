//! The Linux SocketCAN `struct can_frame` (`linux/can.h`, CAN_MTU = 16 bytes), as a raw CAN
//! socket (`CAN_RAW`) reads and writes it:
//!
//! | bytes | field |
//! |---|---|
//! | 0–3 | `can_id`: identifier and flags, host byte order (little-endian on the x86 and ARM hosts this project runs on) |
//! | 4 | `len` (formerly `can_dlc`): data length 0..8 |
//! | 5, 6 | `__pad`, `__res0` |
//! | 7 | `len8_dlc`: DLC 9..15 of an 8-byte frame, if the driver reports it (ignored here) |
//! | 8–15 | `data[8]` |
//!
//! `can_id` bits: 31 [`EFF_FLAG`] extended frame, 30 [`RTR_FLAG`] remote frame, 29
//! [`ERR_FLAG`] error frame; bits 0–10 the base identifier ([`SFF_MASK`]), bits 0–28 an
//! extended one ([`EFF_MASK`]). An error frame (`linux/can/error.h`) carries its error class
//! in bits 0–28 and details in the data ([`ErrorFrame`]).
//!
//! The system bus is CAN 2.0A: an extended frame parses to [`Error::CanExtended`].

use std::fmt;

use super::frame::{check_id, check_len, CanFrame};
use crate::wire::{Error, Reader};

/// Offsets of `struct can_frame`.
mod field {
    use std::ops::Range;

    pub(super) const CAN_ID: Range<usize> = 0..4;
    pub(super) const LEN: usize = 4;
    pub(super) const DATA: Range<usize> = 8..16;
}

/// Size of `struct can_frame` (CAN_MTU).
pub const FRAME_LEN: usize = 16;
/// `CAN_EFF_FLAG`: extended frame format (29-bit identifier).
pub const EFF_FLAG: u32 = 0x8000_0000;
/// `CAN_RTR_FLAG`: remote transmission request.
pub const RTR_FLAG: u32 = 0x4000_0000;
/// `CAN_ERR_FLAG`: error message frame.
pub const ERR_FLAG: u32 = 0x2000_0000;
/// `CAN_SFF_MASK`: the 11-bit identifier.
pub const SFF_MASK: u32 = 0x0000_07FF;
/// `CAN_EFF_MASK`: the 29-bit identifier (and `CAN_ERR_MASK`: the error class).
pub const EFF_MASK: u32 = 0x1FFF_FFFF;

/// A checked view of a `struct can_frame`: exactly [`FRAME_LEN`] bytes. The accessors do not
/// look at what the flags mean; [`SocketCanRepr::parse`] does.
#[derive(Debug, Clone)]
pub struct SocketCanFrame<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> SocketCanFrame<T> {
    /// Wraps `buffer` without checking its length (for [`SocketCanRepr::emit`] into a zeroed
    /// buffer; the accessors of a short buffer panic, so parse with [`Self::new_checked`]).
    pub fn new_unchecked(buffer: T) -> Self {
        SocketCanFrame { buffer }
    }

    /// Wraps `buffer` after checking it is exactly [`FRAME_LEN`] bytes (a 72-byte CAN FD
    /// frame is left over bytes).
    pub fn new_checked(buffer: T) -> Result<Self, Error> {
        let mut r = Reader::new(buffer.as_ref());
        r.bytes(FRAME_LEN, "struct can_frame")?;
        r.finish("struct can_frame")?;
        Ok(SocketCanFrame { buffer })
    }

    /// The buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// `can_id` with its flags.
    pub fn can_id(&self) -> u32 {
        let b = &self.buffer.as_ref()[field::CAN_ID];
        u32::from_le_bytes([b[0], b[1], b[2], b[3]])
    }

    /// `len` (formerly `can_dlc`).
    pub fn data_len(&self) -> u8 {
        self.buffer.as_ref()[field::LEN]
    }

    /// All 8 data bytes, whatever `len` says.
    pub fn data(&self) -> &[u8] {
        &self.buffer.as_ref()[field::DATA]
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> SocketCanFrame<T> {
    /// Sets `can_id` with its flags.
    pub fn set_can_id(&mut self, can_id: u32) {
        self.buffer.as_mut()[field::CAN_ID].copy_from_slice(&can_id.to_le_bytes());
    }

    /// Sets `len`.
    pub fn set_data_len(&mut self, len: u8) {
        self.buffer.as_mut()[field::LEN] = len;
    }

    /// The 8 data bytes.
    pub fn data_mut(&mut self) -> &mut [u8] {
        &mut self.buffer.as_mut()[field::DATA]
    }
}

/// The error class of an error frame: bits 0–28 of its `can_id` (`linux/can/error.h`, "error
/// class (mask) in can_id"). Several bits may be set; open (unknown bits are kept).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct ErrorClass(pub u32);

impl ErrorClass {
    /// `CAN_ERR_TX_TIMEOUT`: TX timeout (by the netdevice driver).
    pub const TX_TIMEOUT: ErrorClass = ErrorClass(0x001);
    /// `CAN_ERR_LOSTARB`: lost arbitration; data\[0\] says in which bit.
    pub const LOSTARB: ErrorClass = ErrorClass(0x002);
    /// `CAN_ERR_CRTL`: controller problems; data\[1\] says which ([`ErrorFrame::controller`]).
    pub const CRTL: ErrorClass = ErrorClass(0x004);
    /// `CAN_ERR_PROT`: protocol violation; data\[2\] type, data\[3\] location.
    pub const PROT: ErrorClass = ErrorClass(0x008);
    /// `CAN_ERR_TRX`: transceiver status in data\[4\].
    pub const TRX: ErrorClass = ErrorClass(0x010);
    /// `CAN_ERR_ACK`: no ACK received on transmission.
    pub const ACK: ErrorClass = ErrorClass(0x020);
    /// `CAN_ERR_BUSOFF`: bus off.
    pub const BUSOFF: ErrorClass = ErrorClass(0x040);
    /// `CAN_ERR_BUSERROR`: bus error (may flood).
    pub const BUSERROR: ErrorClass = ErrorClass(0x080);
    /// `CAN_ERR_RESTARTED`: controller restarted.
    pub const RESTARTED: ErrorClass = ErrorClass(0x100);
    /// `CAN_ERR_CNT`: TX and RX error counters in data\[6\] and data\[7\].
    pub const CNT: ErrorClass = ErrorClass(0x200);

    /// Every named class bit with its `linux/can/error.h` name.
    pub const NAMED: &'static [(ErrorClass, &'static str)] = &[
        (ErrorClass::TX_TIMEOUT, "CAN_ERR_TX_TIMEOUT"),
        (ErrorClass::LOSTARB, "CAN_ERR_LOSTARB"),
        (ErrorClass::CRTL, "CAN_ERR_CRTL"),
        (ErrorClass::PROT, "CAN_ERR_PROT"),
        (ErrorClass::TRX, "CAN_ERR_TRX"),
        (ErrorClass::ACK, "CAN_ERR_ACK"),
        (ErrorClass::BUSOFF, "CAN_ERR_BUSOFF"),
        (ErrorClass::BUSERROR, "CAN_ERR_BUSERROR"),
        (ErrorClass::RESTARTED, "CAN_ERR_RESTARTED"),
        (ErrorClass::CNT, "CAN_ERR_CNT"),
    ];

    /// Whether every bit of `other` is set.
    pub fn contains(self, other: ErrorClass) -> bool {
        self.0 & other.0 == other.0
    }
}

impl fmt::Debug for ErrorClass {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "ErrorClass({:03X}h", self.0)?;
        for (c, name) in ErrorClass::NAMED {
            if self.contains(*c) {
                write!(f, " {name}")?;
            }
        }
        write!(f, ")")
    }
}

/// Controller status bits in data\[1\] of a [`ErrorClass::CRTL`] error frame
/// (`linux/can/error.h`, `CAN_ERR_CRTL_*`).
pub mod crtl {
    /// RX buffer overflow.
    pub const RX_OVERFLOW: u8 = 0x01;
    /// TX buffer overflow.
    pub const TX_OVERFLOW: u8 = 0x02;
    /// Reached the warning level for RX errors.
    pub const RX_WARNING: u8 = 0x04;
    /// Reached the warning level for TX errors.
    pub const TX_WARNING: u8 = 0x08;
    /// Reached error-passive status (RX).
    pub const RX_PASSIVE: u8 = 0x10;
    /// Reached error-passive status (TX).
    pub const TX_PASSIVE: u8 = 0x20;
    /// Recovered to error-active state.
    pub const ACTIVE: u8 = 0x40;
}

/// Protocol violations in data\[2\] (type) and data\[3\] (location) of a [`ErrorClass::PROT`]
/// error frame (`linux/can/error.h`, `CAN_ERR_PROT_*` and `CAN_ERR_PROT_LOC_*`); the ones the
/// project names.
pub mod prot {
    /// data\[2\]: single bit error.
    pub const BIT: u8 = 0x01;
    /// data\[2\]: frame format error.
    pub const FORM: u8 = 0x02;
    /// data\[2\]: bit stuffing error.
    pub const STUFF: u8 = 0x04;
    /// data\[2\]: error occurred on transmission.
    pub const TX: u8 = 0x80;
    /// data\[3\]: in the CRC sequence.
    pub const LOC_CRC_SEQ: u8 = 0x08;
    /// data\[3\]: in the data field.
    pub const LOC_DATA: u8 = 0x0A;
    /// data\[3\]: in the ACK slot.
    pub const LOC_ACK: u8 = 0x19;
}

/// An error frame: the class from `can_id`, the 8 data bytes (`CAN_ERR_DLC` = 8) whose meaning
/// the class bits give.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct ErrorFrame {
    /// The class bits.
    pub class: ErrorClass,
    /// The details.
    pub data: [u8; 8],
}

impl ErrorFrame {
    /// data\[1\], the controller status ([`crtl`]) when the class has [`ErrorClass::CRTL`].
    pub fn controller(&self) -> Option<u8> {
        self.class
            .contains(ErrorClass::CRTL)
            .then_some(self.data[1])
    }

    /// data\[2\] and data\[3\], the protocol violation's type and location ([`prot`]), when
    /// the class has [`ErrorClass::PROT`].
    pub fn protocol(&self) -> Option<(u8, u8)> {
        self.class
            .contains(ErrorClass::PROT)
            .then_some((self.data[2], self.data[3]))
    }

    /// data\[6\] and data\[7\], the TX and RX error counters, when the class has
    /// [`ErrorClass::CNT`].
    pub fn counters(&self) -> Option<(u8, u8)> {
        self.class
            .contains(ErrorClass::CNT)
            .then_some((self.data[6], self.data[7]))
    }
}

/// What a raw CAN socket delivers on the system bus: a CAN 2.0A frame or an error frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SocketCanRepr {
    /// A data or remote frame.
    Frame(CanFrame),
    /// An error frame (`CAN_ERR_FLAG`), reported by the driver, not sent by a node.
    Error(ErrorFrame),
}

impl SocketCanRepr {
    /// Reads a checked frame. An error frame wins over the other flags; an extended frame is
    /// [`Error::CanExtended`]; a base frame with identifier bits above bit 10 is
    /// [`Error::CanIdentifier`]; `len` above 8 is [`Error::CanDataLength`].
    pub fn parse<T: AsRef<[u8]>>(f: &SocketCanFrame<T>) -> Result<SocketCanRepr, Error> {
        let can_id = f.can_id();
        if can_id & ERR_FLAG != 0 {
            let mut data = [0; 8];
            data.copy_from_slice(f.data());
            return Ok(SocketCanRepr::Error(ErrorFrame {
                class: ErrorClass(can_id & EFF_MASK),
                data,
            }));
        }
        if can_id & EFF_FLAG != 0 {
            return Err(Error::CanExtended {
                id: can_id & EFF_MASK,
            });
        }
        let id = check_id(can_id & EFF_MASK)?;
        let len = check_len(usize::from(f.data_len()))?;
        let frame = if can_id & RTR_FLAG != 0 {
            CanFrame::remote(id, len)?
        } else {
            CanFrame::new(id, &f.data()[..usize::from(len)])?
        };
        Ok(SocketCanRepr::Frame(frame))
    }

    /// Checks and reads `bytes`.
    pub fn parse_bytes(bytes: &[u8]) -> Result<SocketCanRepr, Error> {
        SocketCanRepr::parse(&SocketCanFrame::new_checked(bytes)?)
    }

    /// The bytes [`Self::emit`] writes.
    pub fn buffer_len(&self) -> usize {
        FRAME_LEN
    }

    /// Writes the frame into a view of [`FRAME_LEN`] bytes; padding and `len8_dlc` are zeroed.
    pub fn emit<T: AsRef<[u8]> + AsMut<[u8]>>(&self, f: &mut SocketCanFrame<T>) {
        f.buffer.as_mut()[..FRAME_LEN].fill(0);
        match self {
            SocketCanRepr::Frame(c) => {
                let rtr = if c.is_remote() { RTR_FLAG } else { 0 };
                f.set_can_id(u32::from(c.id()) | rtr);
                f.set_data_len(c.dlc());
                f.data_mut()[..c.data().len()].copy_from_slice(c.data());
            }
            SocketCanRepr::Error(e) => {
                f.set_can_id(ERR_FLAG | e.class.0 & EFF_MASK);
                f.set_data_len(8);
                f.data_mut().copy_from_slice(&e.data);
            }
        }
    }

    /// The 16 bytes of the frame.
    pub fn to_bytes(&self) -> [u8; FRAME_LEN] {
        let mut f = SocketCanFrame::new_unchecked([0; FRAME_LEN]);
        self.emit(&mut f);
        f.into_inner()
    }

    /// The frame as a capture file holds it under `LINKTYPE_CAN_SOCKETCAN` (227): the same 16
    /// bytes, but `can_id` in network byte order (big-endian), as libpcap writes it and
    /// Wireshark reads it, whatever the host's order.
    pub fn to_pcap_record(&self) -> [u8; FRAME_LEN] {
        let mut b = self.to_bytes();
        let can_id = SocketCanFrame::new_unchecked(&b[..]).can_id();
        b[field::CAN_ID].copy_from_slice(&can_id.to_be_bytes());
        b
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn data_frame_round_trip() {
        // SDO tx of node 5: 585h, len 8, an initiate download response for 6040h:00.
        let bytes = [
            0x85, 0x05, 0x00, 0x00, // can_id 00000585h
            0x08, // len
            0x00, 0x00, 0x00, // __pad, __res0, len8_dlc
            0x60, 0x40, 0x60, 0x00, 0x00, 0x00, 0x00, 0x00, // data
        ];
        let r = SocketCanRepr::parse_bytes(&bytes).unwrap();
        let f = CanFrame::new(0x585, &bytes[8..]).unwrap();
        assert_eq!(r, SocketCanRepr::Frame(f));
        assert_eq!(r.to_bytes(), bytes);
        assert_eq!(r.buffer_len(), 16);
    }

    #[test]
    fn a_capture_record_has_the_identifier_big_endian() {
        let r = SocketCanRepr::Frame(CanFrame::new(0x5A4, &[0x40, 0x66, 0x20, 0x01]).unwrap());
        assert_eq!(
            r.to_pcap_record(),
            [0, 0, 0x05, 0xA4, 4, 0, 0, 0, 0x40, 0x66, 0x20, 0x01, 0, 0, 0, 0]
        );
        let rtr = SocketCanRepr::Frame(CanFrame::remote(0x705, 1).unwrap());
        assert_eq!(rtr.to_pcap_record()[..5], [0x40, 0, 0x07, 0x05, 1]);
    }

    #[test]
    fn remote_frame_keeps_its_dlc() {
        // Node guarding request: 705h, RTR, len 1; data bytes are not part of a remote frame.
        let mut b = [0; 16];
        b[..4].copy_from_slice(&(0x705 | RTR_FLAG).to_le_bytes());
        b[4] = 1;
        b[8] = 0xEE;
        let r = SocketCanRepr::parse_bytes(&b).unwrap();
        assert_eq!(r, SocketCanRepr::Frame(CanFrame::remote(0x705, 1).unwrap()));
        b[8] = 0;
        assert_eq!(r.to_bytes(), b);
    }

    #[test]
    fn extended_frames_are_rejected() {
        let mut f = SocketCanFrame::new_unchecked(
            SocketCanRepr::Frame(CanFrame::new(0x123, &[1]).unwrap()).to_bytes(),
        );
        f.set_can_id(EFF_FLAG | 0x1AAA_AAAA);
        assert_eq!(
            SocketCanRepr::parse(&f),
            Err(Error::CanExtended { id: 0x1AAA_AAAA })
        );
        // Also when the extended identifier would fit 11 bits.
        f.set_can_id(EFF_FLAG | 0x123);
        assert_eq!(
            SocketCanRepr::parse(&f),
            Err(Error::CanExtended { id: 0x123 })
        );
        // A base frame with identifier bits above bit 10.
        f.set_can_id(0x923);
        assert_eq!(
            SocketCanRepr::parse(&f),
            Err(Error::CanIdentifier { id: 0x923 })
        );
        f.set_can_id(0x123);
        f.set_data_len(9);
        assert_eq!(
            SocketCanRepr::parse(&f),
            Err(Error::CanDataLength { len: 9 })
        );
    }

    #[test]
    fn error_frames_are_reported_as_such() {
        // Bus off with controller problems: can_id 20000044h, data[1] = TX passive.
        let mut b = [0; 16];
        b[..4].copy_from_slice(&(ERR_FLAG | 0x44).to_le_bytes());
        b[4] = 8;
        b[9] = crtl::TX_PASSIVE;
        let r = SocketCanRepr::parse_bytes(&b).unwrap();
        let SocketCanRepr::Error(e) = r else {
            panic!("{r:?}")
        };
        assert!(e.class.contains(ErrorClass::BUSOFF) && e.class.contains(ErrorClass::CRTL));
        assert!(!e.class.contains(ErrorClass::ACK));
        assert_eq!(e.controller(), Some(crtl::TX_PASSIVE));
        assert_eq!(e.counters(), None);
        assert_eq!(
            format!("{:?}", e.class),
            "ErrorClass(044h CAN_ERR_CRTL CAN_ERR_BUSOFF)"
        );
        assert_eq!(r.to_bytes(), b);
        // Error counters.
        let e = ErrorFrame {
            class: ErrorClass::CNT,
            data: [0, 0, 0, 0, 0, 0, 96, 128],
        };
        assert_eq!(e.counters(), Some((96, 128)));
        // A bus error: a stuff error in the data field, as a listener reports another node's
        // destroyed frame; can_id 20000088h, data[2] 04h, data[3] 0Ah.
        let bus = ErrorFrame {
            class: ErrorClass(ErrorClass::PROT.0 | ErrorClass::BUSERROR.0),
            data: [0, 0, prot::STUFF, prot::LOC_DATA, 0, 0, 0, 0],
        };
        let bytes = SocketCanRepr::Error(bus).to_bytes();
        assert_eq!(
            bytes,
            [0x88, 0, 0, 0x20, 8, 0, 0, 0, 0, 0, 0x04, 0x0A, 0, 0, 0, 0]
        );
        assert_eq!(
            SocketCanRepr::parse_bytes(&bytes),
            Ok(SocketCanRepr::Error(bus))
        );
        assert_eq!(bus.protocol(), Some((prot::STUFF, prot::LOC_DATA)));
        assert_eq!(e.protocol(), None);
        // The error flag wins over EFF and RTR.
        b[3] |= 0xC0;
        assert!(matches!(
            SocketCanRepr::parse_bytes(&b),
            Ok(SocketCanRepr::Error(_))
        ));
    }

    #[test]
    fn the_buffer_is_exactly_16_bytes() {
        let b = SocketCanRepr::Frame(CanFrame::new(0x80, &[]).unwrap()).to_bytes();
        for n in 0..FRAME_LEN {
            assert_eq!(
                SocketCanRepr::parse_bytes(&b[..n]),
                Err(Error::Truncated {
                    what: "struct can_frame",
                    need: 16,
                    got: n
                })
            );
        }
        // A CAN FD frame (CANFD_MTU 72) is not a classical frame.
        let mut fd = b.to_vec();
        fd.resize(72, 0);
        assert_eq!(
            SocketCanRepr::parse_bytes(&fd),
            Err(Error::Trailing {
                what: "struct can_frame",
                extra: 56
            })
        );
    }

    mod properties {
        use super::*;
        use crate::can::frame::{MAX_ID, MAX_LEN};
        use proptest::collection::vec;
        use proptest::prelude::*;

        /// Every CAN 2.0A frame: data frames of 0..8 bytes and remote frames.
        fn can_frame() -> impl Strategy<Value = CanFrame> {
            prop_oneof![
                (0..=MAX_ID, vec(any::<u8>(), 0..=MAX_LEN))
                    .prop_map(|(id, data)| CanFrame::new(id, &data).unwrap()),
                (0..=MAX_ID, 0..=MAX_LEN as u8)
                    .prop_map(|(id, dlc)| CanFrame::remote(id, dlc).unwrap()),
            ]
        }

        fn repr() -> impl Strategy<Value = SocketCanRepr> {
            prop_oneof![
                can_frame().prop_map(SocketCanRepr::Frame),
                (0..=EFF_MASK, any::<[u8; 8]>()).prop_map(|(class, data)| {
                    SocketCanRepr::Error(ErrorFrame {
                        class: ErrorClass(class),
                        data,
                    })
                }),
            ]
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn emit_then_parse_round_trips(r in repr()) {
                let mut buf = vec![0xAAu8; r.buffer_len()];
                r.emit(&mut SocketCanFrame::new_unchecked(&mut buf[..]));
                prop_assert_eq!(&buf[..], &r.to_bytes()[..]);
                prop_assert_eq!(SocketCanRepr::parse_bytes(&buf), Ok(r));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in vec(any::<u8>(), 0..24)) {
                let _ = SocketCanRepr::parse_bytes(&bytes);
            }
        }
    }
}
