//! The SDO command byte (CiA 301 "SDO protocol", the protocol descriptions of "Initiate SDO
//! download" through "End SDO block upload") and the 8-byte SDO frame that starts with it.
//! CoE (`ecat::coe`) carries the same command byte, so its codec uses these too.
//!
//! | bits | client (ccs) / server (scs) command byte |
//! |---|---|
//! | 7–5 | command specifier ([`ClientCommand`], [`ServerCommand`]) |
//! | 4 | initiate: not used; segment: toggle t ([`TOGGLE`]) |
//! | 3–2 | initiate: n, bytes of d without data (e = 1, s = 1) |
//! | 3–1 | segment: n, bytes of the 7 without data |
//! | 1 | initiate: e, expedited ([`EXPEDITED`]) |
//! | 0 | initiate: s, size indicated ([`SIZE`]); segment: c, no more segments ([`LAST`]) |
//!
//! Block transfers use bits 4–0 differently ([`super::block`]). Bits CiA 301 marks "x" (not
//! used, always 0) are ignored on parse and written 0.

use std::fmt;

use crate::wire::{Error, Reader};

/// The toggle bit t of segments (bit 4).
pub const TOGGLE: u8 = 0x10;
/// e: expedited transfer (bit 1 of an initiate command).
pub const EXPEDITED: u8 = 0x02;
/// s: the data set size is indicated (bit 0 of an initiate command).
pub const SIZE: u8 = 0x01;
/// c: no more segments to follow (bit 0 of a segment command).
pub const LAST: u8 = 0x01;
/// The command byte of "Abort SDO transfer" (cs = 4, bits 4–0 not used).
pub const ABORT: u8 = 0x80;
/// Data bytes of a segment (CiA 301: seg-data, 7 bytes).
pub const SEGMENT_DATA: usize = 7;
/// Length of every SDO frame on CAN.
pub const FRAME_LEN: usize = 8;

/// Defines an open newtype for a command specifier (bits 5–7 of the command byte) whose
/// names stand in `$names`, indexed by value.
macro_rules! specifier {
    ($(#[$m:meta])* $name:ident, $names:ident) => {
        $(#[$m])*
        #[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
        pub struct $name(pub u8);

        impl $name {
            /// The specifier in bits 5–7 of `command`.
            pub fn of(command: u8) -> $name {
                $name(command >> 5)
            }

            /// The specifier placed in bits 5–7.
            pub fn bits(self) -> u8 {
                self.0 << 5
            }

            /// Its name in CiA 301, if defined.
            pub fn name(self) -> Option<&'static str> {
                $names.get(usize::from(self.0)).copied()
            }
        }

        impl fmt::Debug for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                let name = self.name().unwrap_or("undefined");
                write!(f, "{}({} {name})", stringify!($name), self.0)
            }
        }
    };
}

specifier!(
    /// The client command specifier, ccs (client → server; open).
    ClientCommand,
    CLIENT_NAMES
);
specifier!(
    /// The server command specifier, scs (server → client; open).
    ServerCommand,
    SERVER_NAMES
);

/// The specifiers of CiA 301's SDO protocol, one row a value: what it means in a client's
/// command (ccs) and in a server's (scs).
macro_rules! specifiers {
    ($($v:literal: $c:ident $ct:literal, $s:ident $st:literal;)*) => {
        impl ClientCommand {
            $(#[doc = concat!("ccs ", $v, ": ", $ct, ".")] pub const $c: ClientCommand = ClientCommand($v);)*
        }
        impl ServerCommand {
            $(#[doc = concat!("scs ", $v, ": ", $st, ".")] pub const $s: ServerCommand = ServerCommand($v);)*
        }
        const CLIENT_NAMES: &[&str] = &[$($ct),*];
        const SERVER_NAMES: &[&str] = &[$($st),*];
    };
}

specifiers! {
    0: DOWNLOAD_SEGMENT "download segment", UPLOAD_SEGMENT "upload segment";
    1: INITIATE_DOWNLOAD "initiate download", DOWNLOAD_SEGMENT "download segment";
    2: INITIATE_UPLOAD "initiate upload", INITIATE_UPLOAD "initiate upload";
    3: UPLOAD_SEGMENT "upload segment", INITIATE_DOWNLOAD "initiate download";
    4: ABORT "abort", ABORT "abort";
    5: BLOCK_UPLOAD "block upload", BLOCK_DOWNLOAD "block download";
    6: BLOCK_DOWNLOAD "block download", BLOCK_UPLOAD "block upload";
}

/// The length of expedited data an initiate command announces: 4 − n with s = 1, else 4.
pub(crate) fn expedited_len(command: u8) -> usize {
    if command & SIZE != 0 {
        4 - usize::from((command >> 2) & 0x03)
    } else {
        4
    }
}

/// The e, s and n bits for `len` (1..=4) expedited bytes with the size indicated.
pub(crate) fn expedited_bits(len: usize) -> u8 {
    EXPEDITED | SIZE | ((4 - len.clamp(1, 4)) as u8) << 2
}

/// The n bits of a segment command: how many of the 7 data bytes carry no data.
pub(crate) fn segment_unused(command: u8) -> usize {
    usize::from((command >> 1) & 0x07)
}

/// The t, n and c bits of a segment command carrying `len` (0..=7) bytes.
pub(crate) fn segment_bits(toggle: bool, len: usize, last: bool) -> u8 {
    let n = SEGMENT_DATA.saturating_sub(len) as u8;
    tg(toggle) | n << 1 | if last { LAST } else { 0 }
}

/// [`TOGGLE`] if `on`.
pub(crate) fn tg(on: bool) -> u8 {
    if on {
        TOGGLE
    } else {
        0
    }
}

/// A checked view of an SDO frame on CAN: exactly 8 bytes (CiA 301 lays out every SDO frame
/// in 8 bytes, unused ones reserved rather than left out; CANopen stacks ignore SDO frames of
/// another length). The accessors read bytes; [`super::SdoRequest`] and
/// [`super::SdoResponse`] say what they mean.
#[derive(Debug, Clone)]
pub struct SdoFrame<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> SdoFrame<T> {
    /// Checks the length: 8 bytes.
    pub fn new_checked(buffer: T) -> Result<Self, Error> {
        let mut r = Reader::new(buffer.as_ref());
        r.bytes(FRAME_LEN, "SDO frame")?;
        r.finish("SDO frame")?;
        Ok(SdoFrame { buffer })
    }

    /// The buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    /// Byte 0, the command byte.
    pub fn command(&self) -> u8 {
        self.buffer.as_ref()[0]
    }

    /// Bytes 1–2, the object index (initiate and abort frames).
    pub fn index(&self) -> u16 {
        let b = self.buffer.as_ref();
        u16::from_le_bytes([b[1], b[2]])
    }

    /// Byte 3, the sub-index.
    pub fn sub(&self) -> u8 {
        self.buffer.as_ref()[3]
    }

    /// Bytes 4–7: expedited data, size, abort code, block size.
    pub fn data(&self) -> [u8; 4] {
        let b = self.buffer.as_ref();
        [b[4], b[5], b[6], b[7]]
    }

    /// Bytes 4–7 as a little-endian u32.
    pub fn data_u32(&self) -> u32 {
        u32::from_le_bytes(self.data())
    }

    /// Byte `i` (0..8; taken modulo 8).
    pub fn byte(&self, i: usize) -> u8 {
        self.buffer.as_ref()[i % FRAME_LEN]
    }

    /// Bytes 1–7, the data of a segment.
    pub fn segment(&self) -> &[u8] {
        &self.buffer.as_ref()[1..FRAME_LEN]
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> SdoFrame<T> {
    /// Sets the command byte.
    pub fn set_command(&mut self, command: u8) {
        self.buffer.as_mut()[0] = command;
    }

    /// Sets byte `i` (0..8; taken modulo 8).
    pub fn set_byte(&mut self, i: usize, value: u8) {
        self.buffer.as_mut()[i % FRAME_LEN] = value;
    }
}

/// Writes the command byte, the index and the sub-index of an initiate or abort frame.
pub(crate) fn head(command: u8, index: u16, sub: u8) -> [u8; FRAME_LEN] {
    let i = index.to_le_bytes();
    [command, i[0], i[1], sub, 0, 0, 0, 0]
}

/// The toggle bit a segmented transfer expects next: 0 for the first segment, then
/// alternating (CiA 301 "Download SDO segment" / "Upload SDO segment": t alternates for each
/// subsequent segment; the response echoes it). A mismatch is [`Error::SdoToggle`]; the peer
/// answers it with abort code 0503_0000h ([`super::SdoAbortCode::TOGGLE_BIT`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Toggle {
    next: bool,
}

impl Toggle {
    /// A transfer's first segment: t = 0.
    pub fn new() -> Toggle {
        Toggle::default()
    }

    /// The toggle bit the next segment must carry.
    pub fn expected(self) -> bool {
        self.next
    }

    /// Checks a segment's toggle bit and, if right, moves on to the next segment.
    pub fn check(&mut self, got: bool) -> Result<(), Error> {
        if got != self.next {
            return Err(Error::SdoToggle {
                expected: self.next,
                got,
            });
        }
        self.next = !self.next;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn specifiers_and_bits() {
        assert_eq!(ClientCommand::of(0x23), ClientCommand::INITIATE_DOWNLOAD);
        assert_eq!(ServerCommand::of(0x60), ServerCommand::INITIATE_DOWNLOAD);
        assert_eq!(ClientCommand::BLOCK_DOWNLOAD.bits(), 0xC0);
        assert_eq!(
            format!("{:?}", ServerCommand::BLOCK_UPLOAD),
            "ServerCommand(6 block upload)"
        );
        assert_eq!(
            format!("{:?}", ClientCommand(7)),
            "ClientCommand(7 undefined)"
        );
        // 4Fh: expedited, size indicated, n = 3 → 1 byte; 43h: n = 0 → 4 bytes; 42h: 4.
        assert_eq!(expedited_len(0x4F), 1);
        assert_eq!(expedited_len(0x43), 4);
        assert_eq!(expedited_len(0x42), 4);
        assert_eq!(expedited_bits(2), 0x0B);
        // 0Bh: t = 0, n = 5, c = 1 → 2 bytes, last; 10h: t = 1, 7 bytes.
        assert_eq!(segment_unused(0x0B), 5);
        assert_eq!(segment_bits(false, 2, true), 0x0B);
        assert_eq!(segment_bits(true, 7, false), 0x10);
    }

    #[test]
    fn the_frame_is_eight_bytes() {
        let mut f = SdoFrame::new_checked(head(0x40, 0x1018, 1)).unwrap();
        assert_eq!((f.command(), f.index(), f.sub()), (0x40, 0x1018, 1));
        f.set_byte(4, 0x11);
        f.set_command(0x4F);
        assert_eq!((f.command(), f.data_u32(), f.byte(4)), (0x4F, 0x11, 0x11));
        assert_eq!(f.segment(), [0x18, 0x10, 1, 0x11, 0, 0, 0]);
        for n in 0..8 {
            assert_eq!(
                SdoFrame::new_checked(&[0u8; 8][..n]).unwrap_err(),
                Error::Truncated {
                    what: "SDO frame",
                    need: 8,
                    got: n
                }
            );
        }
        assert_eq!(
            SdoFrame::new_checked(&[0u8; 9][..]).unwrap_err(),
            Error::Trailing {
                what: "SDO frame",
                extra: 1
            }
        );
    }

    #[test]
    fn toggle_alternates_from_zero() {
        let mut t = Toggle::new();
        assert_eq!(t.check(false), Ok(()));
        assert_eq!(t.check(true), Ok(()));
        assert_eq!(
            t.check(true),
            Err(Error::SdoToggle {
                expected: false,
                got: true
            })
        );
        // A wrong bit does not move on.
        assert!(!t.expected());
        assert_eq!(t.check(false), Ok(()));
    }
}
