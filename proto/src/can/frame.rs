//! The classical CAN frame in base format (CAN 2.0A; ISO 11898-1 "base frame format"): an
//! 11-bit identifier, the RTR bit, a data length code and 0..8 data bytes. A remote frame
//! (RTR = 1) carries no data; its DLC says how many bytes it asks for. DLC codes 9..15, which
//! ISO 11898-1 lets mean 8 bytes, are not represented: the Linux `len` field and the CANopen
//! services this project uses stop at 8.

use std::fmt;

use crate::wire::Error;

/// The largest base-format identifier (11 bits).
pub const MAX_ID: u16 = 0x7FF;
/// The largest data length of a classical CAN frame.
pub const MAX_LEN: usize = 8;

/// The most bits a base-format data frame of `len` bytes (a remote frame: 0) takes on the
/// wire, interframe space and worst-case stuffing included (see [`CanFrame::max_bits`]).
pub fn max_bits(len: usize) -> u32 {
    let n = 8 * len.min(MAX_LEN) as u32;
    47 + n + (34 + n - 1) / 4
}

/// A CAN 2.0A data or remote frame. The constructors check the identifier (≤ 7FFh) and the
/// length (≤ 8), so every value of this type can go on the bus.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct CanFrame {
    id: u16,
    remote: bool,
    dlc: u8,
    data: [u8; MAX_LEN],
}

impl CanFrame {
    /// A data frame with identifier `id` carrying `data` (0..8 bytes).
    pub fn new(id: u16, data: &[u8]) -> Result<CanFrame, Error> {
        check_id(u32::from(id))?;
        let dlc = check_len(data.len())?;
        let mut buf = [0; MAX_LEN];
        buf[..data.len()].copy_from_slice(data);
        Ok(CanFrame {
            id,
            remote: false,
            dlc,
            data: buf,
        })
    }

    /// A remote frame with identifier `id` asking for `dlc` (0..8) bytes (CiA 301 node
    /// guarding sends one with DLC 1 on 700h + node).
    pub fn remote(id: u16, dlc: u8) -> Result<CanFrame, Error> {
        check_id(u32::from(id))?;
        check_len(usize::from(dlc))?;
        Ok(CanFrame {
            id,
            remote: true,
            dlc,
            data: [0; MAX_LEN],
        })
    }

    /// The 11-bit identifier.
    pub fn id(&self) -> u16 {
        self.id
    }

    /// Whether this is a remote frame (RTR = 1).
    pub fn is_remote(&self) -> bool {
        self.remote
    }

    /// The data length code (0..8): the data's length, or the length a remote frame asks for.
    pub fn dlc(&self) -> u8 {
        self.dlc
    }

    /// The frame's length on the wire in bits at the most: start of frame to the end of the
    /// interframe space (47 bits of a base frame plus 8 per data byte), with the most stuff
    /// bits its 34 + 8·n stuffed bits can need, ⌊(34 + 8·n − 1) / 4⌋ (ISO 11898-1 bit
    /// stuffing: one after five equal bits, and a stuff bit starts the next run). What a bus
    /// load calculation must assume, as the data decides the stuffing.
    pub fn max_bits(&self) -> u32 {
        max_bits(if self.remote {
            0
        } else {
            usize::from(self.dlc)
        })
    }

    /// The data bytes (none for a remote frame).
    pub fn data(&self) -> &[u8] {
        if self.remote {
            &[]
        } else {
            &self.data[..usize::from(self.dlc)]
        }
    }
}

impl fmt::Debug for CanFrame {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "CanFrame({:03X}h", self.id)?;
        if self.remote {
            write!(f, " remote")?;
        }
        write!(f, " [{}]", self.dlc)?;
        for b in self.data() {
            write!(f, " {b:02X}")?;
        }
        write!(f, ")")
    }
}

/// `id` as a base-format identifier.
pub(crate) fn check_id(id: u32) -> Result<u16, Error> {
    u16::try_from(id)
        .ok()
        .filter(|&i| i <= MAX_ID)
        .ok_or(Error::CanIdentifier { id })
}

/// `len` as a classical CAN data length.
pub(crate) fn check_len(len: usize) -> Result<u8, Error> {
    u8::try_from(len)
        .ok()
        .filter(|&l| usize::from(l) <= MAX_LEN)
        .ok_or(Error::CanDataLength { len })
}

#[cfg(test)]
mod tests {

    #[test]
    fn the_longest_frames_with_worst_case_stuffing() {
        // 8 data bytes: 111 bits and 24 stuff bits; SYNC (no data): 47 and 8.
        assert_eq!(CanFrame::new(0x181, &[0; 8]).unwrap().max_bits(), 135);
        assert_eq!(CanFrame::new(0x080, &[]).unwrap().max_bits(), 55);
        assert_eq!(CanFrame::remote(0x724, 1).unwrap().max_bits(), 55);
    }

    use super::*;

    #[test]
    fn data_and_remote_frames() {
        // 605h: SDO rx of node 5; an initiate upload of 1000h:00.
        let f = CanFrame::new(0x605, &[0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0]).unwrap();
        assert_eq!((f.id(), f.dlc(), f.is_remote()), (0x605, 8, false));
        assert_eq!(f.data(), [0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0]);
        assert_eq!(
            format!("{f:?}"),
            "CanFrame(605h [8] 40 00 10 00 00 00 00 00)"
        );
        // 705h remote, DLC 1: a node-guarding request.
        let r = CanFrame::remote(0x705, 1).unwrap();
        assert_eq!((r.dlc(), r.is_remote(), r.data()), (1, true, &[][..]));
        assert_eq!(format!("{r:?}"), "CanFrame(705h remote [1])");
        // An empty data frame (SYNC without counter) is not a remote frame.
        let s = CanFrame::new(0x080, &[]).unwrap();
        assert_ne!(s, CanFrame::remote(0x080, 0).unwrap());
    }

    #[test]
    fn identifier_and_length_are_checked() {
        assert_eq!(
            CanFrame::new(0x800, &[]),
            Err(Error::CanIdentifier { id: 0x800 })
        );
        assert_eq!(
            CanFrame::new(0x7FF, &[0; 9]),
            Err(Error::CanDataLength { len: 9 })
        );
        assert_eq!(
            CanFrame::remote(0xFFFF, 0),
            Err(Error::CanIdentifier { id: 0xFFFF })
        );
        assert_eq!(CanFrame::remote(0, 9), Err(Error::CanDataLength { len: 9 }));
        assert_eq!(check_id(0x7FF), Ok(0x7FF));
        assert_eq!(
            check_id(0x1234_5678),
            Err(Error::CanIdentifier { id: 0x1234_5678 })
        );
        assert_eq!(check_len(300), Err(Error::CanDataLength { len: 300 }));
    }
}
