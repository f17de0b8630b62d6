//! The Slave Information Interface: the master reads the slave's SII EEPROM through the ESC's
//! EEPROM interface (registers 0500h–050Fh, ETG.1000.4 §6.4) and takes it apart with
//! `proto::ecat::sii` (ETG.2010): identity, mailbox offsets and sizes, SyncManagers, PDOs.
//!
//! The interface: the master takes the EEPROM (0500h = 0), writes the command "read" (0502h
//! bits 8–10 = 001b) together with the word address (0504h), waits while the busy bit (0502h
//! bit 15) is set, checks the error bits (13 "missing acknowledge / invalid command", 14
//! "write enable error") and reads 4 or 8 bytes from 0508h (0502h bit 6: 8-byte reads).

use proto::ecat::register::{SiiControl, SII_CONFIG, SII_CONTROL};
use proto::ecat::sii::{self, CategoryType, SiiRepr};
use proto::ecat::Command;

use super::engine::Master;
use super::error::{Awaited, ProtocolError, Result};
use super::segment::Segment;
use super::wire;

/// The error bits that fail a read: 13 missing acknowledge / invalid command, 14 write enable
/// error (a checksum or load error of the configuration area does not stop reading).
const READ_ERRORS: u16 = SiiControl::ACK_ERROR | SiiControl::WRITE_ENABLE_ERROR;

/// Word address where the categories start (ETG.2010 table 1).
const CATEGORIES: usize = sii::word::CATEGORIES as usize;
/// Words read at most (a 64 Kbit EEPROM), whatever the contents claim.
const MAX_WORDS: usize = 4096;

impl<S: Segment> Master<S> {
    /// Reads `words` SII words from word address `word` of `station`.
    pub(crate) fn read_sii(&mut self, station: u16, word: u16, words: u16) -> Result<Vec<u8>> {
        self.write_register(station, SII_CONFIG, &[0])?;
        let mut out = Vec::with_capacity(2 * usize::from(words));
        let mut at = u32::from(word);
        let mut idle = None;
        while out.len() < 2 * usize::from(words) {
            let chunk = self.sii_chunk(station, at, &mut idle)?;
            at += (chunk.len() / 2) as u32;
            out.extend(chunk);
        }
        out.truncate(2 * usize::from(words));
        Ok(out)
    }

    /// One read command at word `address`: 4 or 8 bytes. `idle` is the status the last
    /// command of this master ended with, if it just read one: then the interface is known
    /// to be idle and is not polled first.
    fn sii_chunk(&mut self, station: u16, address: u32, idle: &mut Option<u16>) -> Result<Vec<u8>> {
        let timeout = self.config.eeprom_timeout;
        // Wait for a command still running (another master's, or one before this read).
        let mut status = match idle.take() {
            Some(s) => s,
            None => self.poll(timeout, Awaited::Eeprom, |m| {
                let s = m.read_u16(station, SII_CONTROL)?;
                Ok((s & SiiControl::BUSY == 0).then_some(s))
            })?,
        };
        let mut command = SiiControl::CMD_READ.to_le_bytes().to_vec();
        command.extend(address.to_le_bytes());
        // The command, and at once the status and the data (a fast ESC is done by then).
        let write = wire::write(Command::FPWR, station, SII_CONTROL, command);
        let access = wire::Access::of(&write);
        let r = self.exchange(&[write, wire::read(Command::FPRD, station, SII_CONTROL, 14)])?;
        super::port::check_wkc(access, &r[0], 1)?;
        let mut data = r[1].data.clone();
        if r[1].wkc == 1 {
            status = u16::from_le_bytes([data[0], data[1]]);
        }
        if r[1].wkc != 1 || status & SiiControl::BUSY != 0 {
            status = self.poll(timeout, Awaited::Eeprom, |m| {
                let s = m.read_u16(station, SII_CONTROL)?;
                Ok((s & SiiControl::BUSY == 0).then_some(s))
            })?;
            data = self.read_register(station, SII_CONTROL, 14)?;
        }
        if status & READ_ERRORS != 0 {
            return Err(ProtocolError::Eeprom { status }.into());
        }
        *idle = Some(status);
        let n = if status & SiiControl::READ_8_BYTES != 0 {
            8
        } else {
            4
        };
        Ok(data[6..6 + n].to_vec())
    }

    /// Reads the whole SII of `station` (the header and the categories up to the end marker):
    /// the image's bytes and their parse.
    pub(crate) fn read_sii_image(&mut self, station: u16) -> Result<(Vec<u8>, SiiRepr)> {
        self.write_register(station, SII_CONFIG, &[0])?;
        let mut words: Vec<u16> = Vec::new();
        let mut need = CATEGORIES + 2;
        let mut at = CATEGORIES;
        let mut idle = None;
        loop {
            while words.len() < need {
                if words.len() >= MAX_WORDS {
                    return Err(ProtocolError::SiiEnd { words: MAX_WORDS }.into());
                }
                let chunk = self.sii_chunk(station, words.len() as u32, &mut idle)?;
                words.extend(
                    chunk
                        .chunks_exact(2)
                        .map(|c| u16::from_le_bytes([c[0], c[1]])),
                );
            }
            if words[at] == CategoryType::END.0 {
                break;
            }
            let len = usize::from(words[at + 1]);
            at += 2 + len;
            need = at + 2;
        }
        words.truncate(at + 1);
        let raw: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
        let repr = SiiRepr::parse(&raw).map_err(ProtocolError::Sii)?;
        Ok((raw, repr))
    }
}
