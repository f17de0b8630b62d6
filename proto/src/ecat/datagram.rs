//! EtherCAT datagrams (ETG.1000.4 "EtherCAT DLPDU structure" / "EtherCAT datagram"; ETG.1000.3
//! for the commands' services).
//!
//! | bytes | field |
//! |---|---|
//! | 0 | command ([`Command`]) |
//! | 1 | index (the master's tag, returned unchanged) |
//! | 2–5 | address: ADP (2–3) and ADO (4–5) for position/fixed/broadcast commands, or one 32-bit logical address |
//! | 6–7 | bits 0–10 data length, 11–13 reserved, 14 circulating frame, 15 more datagrams follow |
//! | 8–9 | IRQ (event request of the slaves, ORed) |
//! | 10.. | data (length bytes) |
//! | last 2 | working counter |
//!
//! All little-endian. A slave processes datagrams in place, so [`Datagram`] has setters for
//! every field and a writable [`Datagram::data_mut`].

use std::fmt;

use super::wire::{fit, le16, le32};
use crate::wire::{Error, Reader};

/// Datagram header length (command .. IRQ).
pub const HEADER_LEN: usize = 10;
/// Working counter length.
pub const WKC_LEN: usize = 2;
/// The largest data length the 11-bit length field holds.
pub const MAX_DATA_LEN: usize = 0x07FF;

/// How a command addresses slaves (ETG.1000.4 "Addressing modes").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Addressing {
    /// Auto-increment ("position") addressing: each slave increments ADP; the one that sees 0
    /// is addressed (APxx, ARMW).
    Position,
    /// Configured station address (register 0010h) or alias (0012h) in ADP (FPxx, FRMW).
    Fixed,
    /// Every slave (BRD/BWR/BRW); each increments ADP.
    Broadcast,
    /// 32-bit logical address mapped by the FMMUs (LRD/LWR/LRW).
    Logical,
}

/// What a command does with the addressed memory.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Access {
    /// No operation.
    None,
    /// Read: slave data into the datagram.
    Read,
    /// Write: datagram data into the slave.
    Write,
    /// Read and write (exchange).
    ReadWrite,
    /// Read at one slave, write at all others (ARMW/FRMW).
    ReadMultipleWrite,
}

/// A datagram command (ETG.1000.4 "EtherCAT datagram" command codes, ETG.1000.3; open:
/// unknown codes are kept).
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct Command(pub u8);

impl Command {
    /// No operation.
    pub const NOP: Command = Command(0);
    /// Auto-increment physical read.
    pub const APRD: Command = Command(1);
    /// Auto-increment physical write.
    pub const APWR: Command = Command(2);
    /// Auto-increment physical read/write.
    pub const APRW: Command = Command(3);
    /// Configured address physical read.
    pub const FPRD: Command = Command(4);
    /// Configured address physical write.
    pub const FPWR: Command = Command(5);
    /// Configured address physical read/write.
    pub const FPRW: Command = Command(6);
    /// Broadcast read.
    pub const BRD: Command = Command(7);
    /// Broadcast write.
    pub const BWR: Command = Command(8);
    /// Broadcast read/write.
    pub const BRW: Command = Command(9);
    /// Logical memory read.
    pub const LRD: Command = Command(10);
    /// Logical memory write.
    pub const LWR: Command = Command(11);
    /// Logical memory read/write.
    pub const LRW: Command = Command(12);
    /// Auto-increment physical read, multiple write.
    pub const ARMW: Command = Command(13);
    /// Configured address physical read, multiple write.
    pub const FRMW: Command = Command(14);

    /// Every defined command.
    pub const ALL: [Command; 15] = [
        Command::NOP,
        Command::APRD,
        Command::APWR,
        Command::APRW,
        Command::FPRD,
        Command::FPWR,
        Command::FPRW,
        Command::BRD,
        Command::BWR,
        Command::BRW,
        Command::LRD,
        Command::LWR,
        Command::LRW,
        Command::ARMW,
        Command::FRMW,
    ];

    /// The mnemonic (`"FPRD"`), if the code is defined.
    pub fn name(self) -> Option<&'static str> {
        const NAMES: [&str; 15] = [
            "NOP", "APRD", "APWR", "APRW", "FPRD", "FPWR", "FPRW", "BRD", "BWR", "BRW", "LRD",
            "LWR", "LRW", "ARMW", "FRMW",
        ];
        NAMES.get(usize::from(self.0)).copied()
    }

    /// Parses a mnemonic (case-insensitive).
    pub fn from_name(s: &str) -> Option<Command> {
        Command::ALL
            .into_iter()
            .find(|c| c.name().is_some_and(|n| n.eq_ignore_ascii_case(s)))
    }

    /// The addressing mode; `None` for NOP and undefined codes.
    pub fn addressing(self) -> Option<Addressing> {
        Some(match self.0 {
            1..=3 | 13 => Addressing::Position,
            4..=6 | 14 => Addressing::Fixed,
            7..=9 => Addressing::Broadcast,
            10..=12 => Addressing::Logical,
            _ => return None,
        })
    }

    /// What the command does (`None` for NOP and undefined codes).
    pub fn access(self) -> Access {
        match self.0 {
            1 | 4 | 7 | 10 => Access::Read,
            2 | 5 | 8 | 11 => Access::Write,
            3 | 6 | 9 | 12 => Access::ReadWrite,
            13 | 14 => Access::ReadMultipleWrite,
            _ => Access::None,
        }
    }

    /// Whether the command reads slave memory into the datagram.
    pub fn reads(self) -> bool {
        matches!(
            self.access(),
            Access::Read | Access::ReadWrite | Access::ReadMultipleWrite
        )
    }

    /// Whether the command writes datagram data into slave memory.
    pub fn writes(self) -> bool {
        matches!(
            self.access(),
            Access::Write | Access::ReadWrite | Access::ReadMultipleWrite
        )
    }

    /// How much a slave adds to the working counter (ETG.1000.4 "Working counter"):
    /// `read`/`write` say whether it performed that part of the command. A read or a write
    /// counts 1; in a read/write command the read counts 1 and the write 2 (3 for both); ARMW
    /// and FRMW count 1 for the read at the addressed slave and 1 for a write elsewhere. NOP and
    /// undefined commands count nothing.
    pub fn wkc_increment(self, read: bool, write: bool) -> u16 {
        let (r, w) = match self.access() {
            Access::None => (0, 0),
            Access::Read => (1, 0),
            Access::Write => (0, 1),
            Access::ReadWrite => (1, 2),
            Access::ReadMultipleWrite => (1, 1),
        };
        u16::from(read) * r + u16::from(write) * w
    }

    /// Whether the address field is one 32-bit logical address rather than ADP/ADO.
    pub fn is_logical(self) -> bool {
        self.addressing() == Some(Addressing::Logical)
    }
}

impl fmt::Display for Command {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.name() {
            Some(n) => f.write_str(n),
            None => write!(f, "command {:02X}h", self.0),
        }
    }
}

impl fmt::Debug for Command {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.name() {
            Some(n) => write!(f, "Command::{n}"),
            None => write!(f, "Command({:02X}h)", self.0),
        }
    }
}

/// The address field of a position/fixed/broadcast command from its ADP and ADO.
pub const fn physical_address(adp: u16, ado: u16) -> u32 {
    (adp as u32) | ((ado as u32) << 16)
}

mod field {
    pub(super) const CMD: usize = 0;
    pub(super) const IDX: usize = 1;
    pub(super) const ADP: usize = 2;
    pub(super) const ADO: usize = 4;
    pub(super) const LEN: usize = 6;
    pub(super) const IRQ: usize = 8;
    pub(super) const DATA: usize = 10;
    pub(super) const LEN_MASK: u16 = 0x07FF;
    pub(super) const CIRCULATING: u16 = 0x4000;
    pub(super) const MORE: u16 = 0x8000;
}

/// Checked view over exactly one datagram: header, data, working counter.
///
/// `new_checked` requires the buffer to be `10 + length + 2` bytes; the data and working
/// counter accessors use the buffer's length, so a length field changed by a setter afterwards
/// cannot make them panic.
#[derive(Debug, Clone)]
pub struct Datagram<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> Datagram<T> {
    /// Wraps a buffer without checking; accessors panic if it is shorter than 12 bytes.
    pub fn new_unchecked(buffer: T) -> Self {
        Datagram { buffer }
    }

    /// Wraps a buffer holding exactly one datagram.
    pub fn new_checked(buffer: T) -> Result<Self, Error> {
        let d = Datagram { buffer };
        d.check_len()?;
        Ok(d)
    }

    /// Checks that the buffer is exactly header + length field + working counter.
    pub fn check_len(&self) -> Result<(), Error> {
        let got = self.buffer.as_ref().len();
        if got < HEADER_LEN + WKC_LEN {
            return Err(Error::Truncated {
                what: "datagram",
                need: HEADER_LEN + WKC_LEN,
                got,
            });
        }
        let len = self.len();
        if HEADER_LEN + len + WKC_LEN != got {
            return Err(Error::Length {
                field: "datagram length",
                value: len,
                available: got - HEADER_LEN - WKC_LEN,
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

    /// The whole datagram's bytes.
    pub fn as_bytes(&self) -> &[u8] {
        self.b()
    }

    /// The command.
    pub fn command(&self) -> Command {
        Command(self.b()[field::CMD])
    }
    /// The index (master's tag).
    pub fn index(&self) -> u8 {
        self.b()[field::IDX]
    }
    /// ADP: position (auto-increment, negative for the n-th slave), station address or
    /// broadcast counter.
    pub fn adp(&self) -> u16 {
        le16(self.b(), field::ADP)
    }
    /// ADO: the register/memory offset in the slave.
    pub fn ado(&self) -> u16 {
        le16(self.b(), field::ADO)
    }
    /// The address field as one 32-bit value (the logical address of LRD/LWR/LRW).
    pub fn address(&self) -> u32 {
        le32(self.b(), field::ADP)
    }
    /// The raw length/flags word.
    pub fn len_flags(&self) -> u16 {
        le16(self.b(), field::LEN)
    }
    /// Data length from the 11-bit length field.
    pub fn len(&self) -> usize {
        usize::from(self.len_flags() & field::LEN_MASK)
    }
    /// Whether the length field says 0.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Bits 11–13 of the length word (reserved, 0).
    pub fn reserved(&self) -> u8 {
        ((self.len_flags() >> 11) & 0x7) as u8
    }
    /// Circulating frame bit (set by a slave that closes the loop on a frame that has passed
    /// it once, ETG.1000.4 "EtherCAT datagram").
    pub fn circulating(&self) -> bool {
        self.len_flags() & field::CIRCULATING != 0
    }
    /// More datagrams follow.
    pub fn more(&self) -> bool {
        self.len_flags() & field::MORE != 0
    }
    /// IRQ field.
    pub fn irq(&self) -> u16 {
        le16(self.b(), field::IRQ)
    }
    /// The data (between header and working counter).
    pub fn data(&self) -> &[u8] {
        let end = self.b().len() - WKC_LEN;
        &self.b()[field::DATA..end]
    }
    /// The working counter.
    pub fn wkc(&self) -> u16 {
        le16(self.b(), self.b().len() - WKC_LEN)
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> Datagram<T> {
    fn bm(&mut self) -> &mut [u8] {
        self.buffer.as_mut()
    }
    fn put16(&mut self, at: usize, v: u16) {
        self.bm()[at..at + 2].copy_from_slice(&v.to_le_bytes());
    }
    fn set_flag(&mut self, mask: u16, on: bool) {
        let w = self.len_flags();
        self.put16(field::LEN, if on { w | mask } else { w & !mask });
    }

    /// Sets the command.
    pub fn set_command(&mut self, c: Command) {
        self.bm()[field::CMD] = c.0;
    }
    /// Sets the index.
    pub fn set_index(&mut self, i: u8) {
        self.bm()[field::IDX] = i;
    }
    /// Sets ADP (a slave increments it for position and broadcast commands).
    pub fn set_adp(&mut self, v: u16) {
        self.put16(field::ADP, v);
    }
    /// Sets ADO.
    pub fn set_ado(&mut self, v: u16) {
        self.put16(field::ADO, v);
    }
    /// Sets the 32-bit address field.
    pub fn set_address(&mut self, v: u32) {
        self.bm()[field::ADP..field::ADP + 4].copy_from_slice(&v.to_le_bytes());
    }
    /// Sets the whole length/flags word (negative tests: a lying length).
    pub fn set_len_flags(&mut self, w: u16) {
        self.put16(field::LEN, w);
    }
    /// Sets the 11-bit length field, keeping the flags (only the low 11 bits of `len` count).
    pub fn set_len(&mut self, len: u16) {
        let w = self.len_flags() & !field::LEN_MASK | len & field::LEN_MASK;
        self.put16(field::LEN, w);
    }
    /// Sets the circulating bit.
    pub fn set_circulating(&mut self, on: bool) {
        self.set_flag(field::CIRCULATING, on);
    }
    /// Sets the more-follows bit.
    pub fn set_more(&mut self, on: bool) {
        self.set_flag(field::MORE, on);
    }
    /// Sets the IRQ field.
    pub fn set_irq(&mut self, v: u16) {
        self.put16(field::IRQ, v);
    }
    /// The data, writable (a slave fills read data in place).
    pub fn data_mut(&mut self) -> &mut [u8] {
        let end = self.b().len() - WKC_LEN;
        &mut self.bm()[field::DATA..end]
    }
    /// Sets the working counter.
    pub fn set_wkc(&mut self, v: u16) {
        let at = self.b().len() - WKC_LEN;
        self.put16(at, v);
    }
    /// Adds to the working counter (wrapping, as the 16-bit counter of an ESC does).
    pub fn add_wkc(&mut self, n: u16) {
        let w = self.wkc().wrapping_add(n);
        self.set_wkc(w);
    }
}

/// A datagram.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Default)]
pub struct DatagramRepr {
    /// Command.
    pub command: Command,
    /// Index (the master's tag).
    pub index: u8,
    /// Address field: ADP | ADO << 16 ([`physical_address`]), or the logical address.
    pub address: u32,
    /// Circulating frame bit.
    pub circulating: bool,
    /// More datagrams follow ([`super::frame::EcatFrameRepr::emit`] sets it itself).
    pub more: bool,
    /// IRQ field.
    pub irq: u16,
    /// Data (for a read: as many zero bytes as are to be read).
    pub data: Vec<u8>,
    /// Working counter.
    pub wkc: u16,
}

impl DatagramRepr {
    /// A datagram of a position, fixed or broadcast command.
    pub fn physical(command: Command, index: u8, adp: u16, ado: u16, data: Vec<u8>) -> Self {
        DatagramRepr {
            command,
            index,
            address: physical_address(adp, ado),
            data,
            ..DatagramRepr::default()
        }
    }

    /// A datagram of a logical command.
    pub fn logical(command: Command, index: u8, address: u32, data: Vec<u8>) -> Self {
        DatagramRepr {
            command,
            index,
            address,
            data,
            ..DatagramRepr::default()
        }
    }

    /// ADP (low half of the address field).
    pub fn adp(&self) -> u16 {
        self.address as u16
    }

    /// ADO (high half of the address field).
    pub fn ado(&self) -> u16 {
        (self.address >> 16) as u16
    }

    /// Reads a checked datagram view.
    pub fn parse<T: AsRef<[u8]>>(d: &Datagram<T>) -> Result<DatagramRepr, Error> {
        d.check_len()?;
        Ok(DatagramRepr {
            command: d.command(),
            index: d.index(),
            address: d.address(),
            circulating: d.circulating(),
            more: d.more(),
            irq: d.irq(),
            data: d.data().to_vec(),
            wkc: d.wkc(),
        })
    }

    /// Parses one datagram that fills `bytes` exactly.
    pub fn parse_bytes(bytes: &[u8]) -> Result<DatagramRepr, Error> {
        let mut r = Reader::new(bytes);
        r.bytes(HEADER_LEN, "datagram header")?;
        DatagramRepr::parse(&Datagram::new_checked(bytes)?)
    }

    /// Bytes the datagram takes: header, data, working counter.
    pub fn buffer_len(&self) -> usize {
        HEADER_LEN + self.data.len() + WKC_LEN
    }

    /// Writes the datagram into `buf`, which must be exactly [`DatagramRepr::buffer_len`]
    /// bytes.
    pub fn emit_into(&self, buf: &mut [u8]) -> Result<(), Error> {
        let len = fit("datagram data", self.data.len(), MAX_DATA_LEN)?;
        if buf.len() != self.buffer_len() {
            return Err(Error::Length {
                field: "datagram buffer",
                value: buf.len(),
                available: self.buffer_len(),
            });
        }
        let mut d = Datagram::new_unchecked(buf);
        d.set_command(self.command);
        d.set_index(self.index);
        d.set_address(self.address);
        d.set_len_flags(len as u16);
        d.set_circulating(self.circulating);
        d.set_more(self.more);
        d.set_irq(self.irq);
        d.data_mut().copy_from_slice(&self.data);
        d.set_wkc(self.wkc);
        Ok(())
    }

    /// The datagram's bytes.
    pub fn emit(&self) -> Result<Vec<u8>, Error> {
        let mut out = vec![0; self.buffer_len()];
        self.emit_into(&mut out)?;
        Ok(out)
    }
}

impl fmt::Display for DatagramRepr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.command.is_logical() {
            write!(f, "{} #{} {:08X}h", self.command, self.index, self.address)?;
        } else {
            write!(
                f,
                "{} #{} {:04X}h:{:04X}h",
                self.command,
                self.index,
                self.adp(),
                self.ado()
            )?;
        }
        write!(f, " len {} wkc {}", self.data.len(), self.wkc)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// FPRD of the AL status (0130h, 2 bytes) at station 1001h, as a slave answers it.
    const FPRD_AL_STATUS: [u8; 14] = [
        0x04, // command FPRD
        0x2A, // index
        0x01, 0x10, // ADP: station 1001h
        0x30, 0x01, // ADO: 0130h AL status
        0x02, 0x80, // length 2, more follows
        0x00, 0x00, // IRQ
        0x08, 0x00, // data: OP
        0x01, 0x00, // working counter 1
    ];

    #[test]
    fn parses_field_by_field() {
        let d = Datagram::new_checked(&FPRD_AL_STATUS[..]).unwrap();
        assert_eq!(d.command(), Command::FPRD);
        assert_eq!((d.index(), d.adp(), d.ado()), (0x2A, 0x1001, 0x0130));
        assert_eq!(d.address(), 0x0130_1001);
        assert_eq!(
            (d.len(), d.more(), d.circulating(), d.reserved()),
            (2, true, false, 0)
        );
        assert_eq!((d.irq(), d.data(), d.wkc()), (0, &[8u8, 0][..], 1));
        let r = DatagramRepr::parse(&d).unwrap();
        assert_eq!(
            r,
            DatagramRepr {
                more: true,
                wkc: 1,
                ..DatagramRepr::physical(Command::FPRD, 0x2A, 0x1001, 0x0130, vec![8, 0])
            }
        );
        assert_eq!(r.emit().unwrap(), FPRD_AL_STATUS);
        assert_eq!(r.to_string(), "FPRD #42 1001h:0130h len 2 wkc 1");
    }

    #[test]
    fn logical_round_trip() {
        let r = DatagramRepr::logical(Command::LRW, 7, 0x0001_0000, vec![1, 2, 3]);
        let b = r.emit().unwrap();
        // LRW, index 7, address 00010000h little-endian, length 3, IRQ 0.
        assert_eq!(&b[..10], [12, 7, 0x00, 0x00, 0x01, 0x00, 3, 0, 0, 0]);
        assert_eq!(DatagramRepr::parse_bytes(&b).unwrap(), r);
        assert_eq!(r.to_string(), "LRW #7 00010000h len 3 wkc 0");
    }

    #[test]
    fn truncation_at_every_length_is_an_error() {
        for n in 0..FPRD_AL_STATUS.len() {
            let e = DatagramRepr::parse_bytes(&FPRD_AL_STATUS[..n]).unwrap_err();
            match n {
                0..=9 => assert_eq!(
                    e,
                    Error::Truncated {
                        what: "datagram header",
                        need: 10,
                        got: n
                    }
                ),
                10..=11 => assert_eq!(
                    e,
                    Error::Truncated {
                        what: "datagram",
                        need: 12,
                        got: n
                    }
                ),
                _ => assert_eq!(
                    e,
                    Error::Length {
                        field: "datagram length",
                        value: 2,
                        available: n - 12
                    }
                ),
            }
        }
    }

    #[test]
    fn a_slave_processes_in_place() {
        let mut b = FPRD_AL_STATUS;
        let mut d = Datagram::new_checked(&mut b[..]).unwrap();
        d.data_mut().copy_from_slice(&[0x02, 0x00]);
        d.add_wkc(1);
        d.set_adp(0x1002);
        d.set_circulating(true);
        d.set_more(false);
        d.set_irq(0x0004);
        assert_eq!((d.wkc(), d.adp(), d.ado()), (2, 0x1002, 0x0130));
        assert_eq!((d.len(), d.more(), d.circulating()), (2, false, true));
        d.set_len(0x7FF);
        // A lying length does not move data or working counter.
        assert_eq!((d.data().len(), d.wkc()), (2, 2));
        assert!(matches!(
            d.check_len(),
            Err(Error::Length { value: 0x7FF, .. })
        ));
        d.set_ado(0x0120);
        d.set_index(9);
        d.set_command(Command::FPWR);
        assert_eq!(&b[..6], [5, 9, 0x02, 0x10, 0x20, 0x01]);
    }

    #[test]
    fn commands() {
        assert_eq!(Command::ALL.len(), 15);
        for (i, c) in Command::ALL.iter().enumerate() {
            assert_eq!(c.0 as usize, i);
            assert_eq!(Command::from_name(c.name().unwrap()), Some(*c));
        }
        assert_eq!(Command(15).name(), None);
        assert_eq!(Command(15).to_string(), "command 0Fh");
        assert_eq!(format!("{:?}", Command::LRW), "Command::LRW");
        assert_eq!(Command::ARMW.addressing(), Some(Addressing::Position));
        assert_eq!(Command::FRMW.addressing(), Some(Addressing::Fixed));
        assert_eq!(Command::BRW.addressing(), Some(Addressing::Broadcast));
        assert_eq!(Command::NOP.addressing(), None);
        assert!(Command::LRW.reads() && Command::LRW.writes() && Command::LRW.is_logical());
        assert!(Command::APRD.reads() && !Command::APRD.writes());
        assert!(!Command::BWR.reads() && Command::BWR.writes());
        assert!(Command::FRMW.reads() && Command::FRMW.writes());
        assert_eq!(Command::NOP.access(), Access::None);
        assert_eq!(Command::FPRD.wkc_increment(true, false), 1);
        assert_eq!(Command::FPWR.wkc_increment(false, true), 1);
        assert_eq!(Command::LRW.wkc_increment(true, true), 3);
        assert_eq!(Command::LRW.wkc_increment(false, true), 2);
        assert_eq!(Command::BRW.wkc_increment(true, false), 1);
        assert_eq!(Command::ARMW.wkc_increment(false, true), 1);
        assert_eq!(Command::NOP.wkc_increment(true, true), 0);
        assert_eq!(Command::APRD.wkc_increment(false, true), 0);
        assert_eq!(Command(200).access(), Access::None);
    }

    #[test]
    fn too_long_data_cannot_be_emitted() {
        let r = DatagramRepr::logical(Command::LWR, 0, 0, vec![0; 2048]);
        assert_eq!(
            r.emit(),
            Err(Error::TooLong {
                what: "datagram data",
                len: 2048,
                max: 2047
            })
        );
        let ok = DatagramRepr::logical(Command::LWR, 0, 0, vec![0; 4]);
        assert!(matches!(
            ok.emit_into(&mut [0; 10]),
            Err(Error::Length { .. })
        ));
    }

    mod properties {
        use super::*;
        use proptest::collection::vec;
        use proptest::prelude::*;

        /// Any header, data of 0 to 64 bytes or the longest the length field holds.
        fn datagram() -> impl Strategy<Value = DatagramRepr> {
            let data = prop_oneof![
                4 => vec(any::<u8>(), 0..=64),
                1 => vec(any::<u8>(), MAX_DATA_LEN),
            ];
            (
                any::<u8>(),
                any::<u8>(),
                any::<u32>(),
                any::<bool>(),
                any::<bool>(),
                any::<u16>(),
                data,
                any::<u16>(),
            )
                .prop_map(
                    |(command, index, address, circulating, more, irq, data, wkc)| DatagramRepr {
                        command: Command(command),
                        index,
                        address,
                        circulating,
                        more,
                        irq,
                        data,
                        wkc,
                    },
                )
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn emit_then_parse_round_trips(r in datagram()) {
                let mut buf = vec![0u8; r.buffer_len()];
                r.emit_into(&mut buf).unwrap();
                prop_assert_eq!(DatagramRepr::parse_bytes(&buf), Ok(r.clone()));
                prop_assert_eq!(DatagramRepr::parse(&Datagram::new_checked(&buf[..]).unwrap()), Ok(r));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in vec(any::<u8>(), 0..40)) {
                let _ = DatagramRepr::parse_bytes(&bytes);
                if let Ok(d) = Datagram::new_checked(&bytes[..]) {
                    let _ = DatagramRepr::parse(&d);
                }
            }
        }
    }
}
