//! The Slave Information Interface: the master reads the slave's SII EEPROM through the ESC's
//! EEPROM interface (registers 0500h–050Fh, ETG.1000.4 §6.4) and takes what it needs from the
//! contents (ETG.2010): identity, mailbox offsets and sizes, SyncManagers, PDOs.
//!
//! The interface: the master takes the EEPROM (0500h = 0), writes the command "read" (0502h
//! bits 8–10 = 001b) together with the word address (0504h), waits while the busy bit (0502h
//! bit 15) is set, checks the error bits (13 "missing acknowledge / invalid command", 14
//! "write enable error") and reads 4 or 8 bytes from 0508h (0502h bit 6: 8-byte reads).

use proto::ecat::register::{SiiControl, SII_CONFIG, SII_CONTROL};

use super::engine::Master;
use super::error::{Awaited, ProtocolError, Result};
use super::segment::Segment;
use super::wire;
use proto::ecat::Command;

/// The error bits that fail a read: 13 missing acknowledge / invalid command, 14 write enable
/// error (a checksum or load error of the configuration area does not stop reading).
const READ_ERRORS: u16 = SiiControl::ACK_ERROR | SiiControl::WRITE_ENABLE_ERROR;

/// Word address where the categories start (ETG.2010 table 1).
const CATEGORIES: usize = 0x40;
/// The end marker of the categories.
const END: u16 = 0xFFFF;
/// Words read at most (a 64 Kbit EEPROM), whatever the contents claim.
const MAX_WORDS: usize = 4096;

/// What a SyncManager of the SII's SyncM category is for (ETG.2010 table 7).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum SmKind {
    /// Not used (0).
    Unused,
    /// Mailbox out, written by the master (1).
    MailboxOut,
    /// Mailbox in, read by the master (2).
    MailboxIn,
    /// Process data outputs (3).
    Outputs,
    /// Process data inputs (4).
    Inputs,
    /// Any other code.
    Other(u8),
}

impl SmKind {
    fn of(code: u8) -> SmKind {
        match code {
            0 => SmKind::Unused,
            1 => SmKind::MailboxOut,
            2 => SmKind::MailboxIn,
            3 => SmKind::Outputs,
            4 => SmKind::Inputs,
            c => SmKind::Other(c),
        }
    }
}

/// One SyncManager of the SyncM category.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct SiiSm {
    /// Physical start address.
    pub(crate) start: u16,
    /// Length.
    pub(crate) len: u16,
    /// Control byte.
    pub(crate) control: u8,
    /// Enable byte (bit 0 enabled).
    pub(crate) enable: u8,
    /// Its use.
    pub(crate) kind: SmKind,
}

/// One PDO entry of a TxPDO/RxPDO category.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct SiiPdoEntry {
    /// Object index mapped.
    pub(crate) index: u16,
    /// Sub-index mapped.
    pub(crate) sub: u8,
    /// Bits.
    pub(crate) bits: u8,
}

/// One PDO of a TxPDO/RxPDO category.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct SiiPdo {
    /// PDO index (1600h…, 1A00h…).
    pub(crate) index: u16,
    /// SyncManager it is assigned to.
    pub(crate) sm: u8,
    /// Its entries.
    pub(crate) entries: Vec<SiiPdoEntry>,
}

/// A mailbox area: receive (written by the master) and send (read by the master) offsets and
/// sizes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) struct MailboxArea {
    /// Receive mailbox offset (master → slave).
    pub(crate) out_start: u16,
    /// Receive mailbox size.
    pub(crate) out_len: u16,
    /// Send mailbox offset (slave → master).
    pub(crate) in_start: u16,
    /// Send mailbox size.
    pub(crate) in_len: u16,
}

/// What the master takes from a slave's SII.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub(crate) struct SiiInfo {
    /// Vendor ID (word 08h).
    pub(crate) vendor: u32,
    /// Product code (0Ah).
    pub(crate) product: u32,
    /// Revision number (0Ch).
    pub(crate) revision: u32,
    /// Serial number (0Eh).
    pub(crate) serial: u32,
    /// Configured station alias (04h).
    pub(crate) alias: u16,
    /// Bootstrap mailbox (14h–17h).
    pub(crate) boot_mailbox: MailboxArea,
    /// Standard mailbox (18h–1Bh).
    pub(crate) mailbox: MailboxArea,
    /// Mailbox protocols (1Ch): bit 2 CoE.
    pub(crate) protocols: u16,
    /// The device name (the general category's name string).
    pub(crate) name: Option<String>,
    /// The strings category.
    pub(crate) strings: Vec<String>,
    /// FMMU uses (FMMU category).
    pub(crate) fmmus: Vec<u8>,
    /// SyncManagers (SyncM category).
    pub(crate) sync_managers: Vec<SiiSm>,
    /// TxPDOs (inputs).
    pub(crate) tx_pdos: Vec<SiiPdo>,
    /// RxPDOs (outputs).
    pub(crate) rx_pdos: Vec<SiiPdo>,
    /// The words read, as bytes.
    pub(crate) raw: Vec<u8>,
}

impl SiiInfo {
    /// Whether the slave has a mailbox (sizes of both standard mailboxes not 0).
    pub(crate) fn has_mailbox(&self) -> bool {
        self.mailbox.out_len > 0 && self.mailbox.in_len > 0
    }
}

impl<S: Segment> Master<S> {
    /// Reads `words` SII words from word address `word` of `station`.
    pub(crate) fn read_sii(&mut self, station: u16, word: u16, words: u16) -> Result<Vec<u8>> {
        self.write_register(station, SII_CONFIG, &[0])?;
        let mut out = Vec::with_capacity(2 * usize::from(words));
        let mut at = u32::from(word);
        while out.len() < 2 * usize::from(words) {
            let chunk = self.sii_chunk(station, at)?;
            at += (chunk.len() / 2) as u32;
            out.extend(chunk);
        }
        out.truncate(2 * usize::from(words));
        Ok(out)
    }

    /// One read command at word `address`: 4 or 8 bytes.
    fn sii_chunk(&mut self, station: u16, address: u32) -> Result<Vec<u8>> {
        let timeout = self.config.eeprom_timeout;
        // Wait for a command still running.
        let mut status = self.poll(timeout, Awaited::Eeprom, |m| {
            let s = m.read_u16(station, SII_CONTROL)?;
            Ok((s & SiiControl::BUSY == 0).then_some(s))
        })?;
        let mut command = SiiControl::CMD_READ.to_le_bytes().to_vec();
        command.extend(address.to_le_bytes());
        // The command, and at once the status and the data (a fast ESC is done by then).
        let r = self.exchange(&[
            wire::write(Command::FPWR, station, SII_CONTROL, command),
            wire::read(Command::FPRD, station, SII_CONTROL, 14),
        ])?;
        let access = format!("FPWR {station:04X}h:{SII_CONTROL:04X}h");
        super::port::check_wkc(&access, &r[0], 1)?;
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
        let n = if status & SiiControl::READ_8_BYTES != 0 {
            8
        } else {
            4
        };
        Ok(data[6..6 + n].to_vec())
    }

    /// Reads the whole SII of `station` (the header and the categories up to the end marker)
    /// and takes its contents apart.
    pub(crate) fn read_sii_info(&mut self, station: u16) -> Result<SiiInfo> {
        self.write_register(station, SII_CONFIG, &[0])?;
        let mut words: Vec<u16> = Vec::new();
        let mut need = CATEGORIES + 2;
        let mut at = CATEGORIES;
        loop {
            while words.len() < need {
                if words.len() >= MAX_WORDS {
                    return Err(ProtocolError::Sii(format!(
                        "no end marker within {MAX_WORDS} words"
                    ))
                    .into());
                }
                let chunk = self.sii_chunk(station, words.len() as u32)?;
                words.extend(
                    chunk
                        .chunks_exact(2)
                        .map(|c| u16::from_le_bytes([c[0], c[1]])),
                );
            }
            if words[at] == END {
                break;
            }
            let len = usize::from(words[at + 1]);
            at += 2 + len;
            need = at + 2;
        }
        words.truncate(at + 1);
        let raw: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
        parse(&raw).map_err(|e| ProtocolError::Sii(e).into())
    }
}

/// Takes the SII contents apart (ETG.2010). Stopgap until `proto::ecat::sii` lands.
pub(crate) fn parse(raw: &[u8]) -> std::result::Result<SiiInfo, String> {
    let w = |i: usize| -> std::result::Result<u16, String> {
        raw.get(2 * i..2 * i + 2)
            .map(|b| u16::from_le_bytes([b[0], b[1]]))
            .ok_or_else(|| format!("truncated at word {i:02X}h"))
    };
    let dw = |i: usize| -> std::result::Result<u32, String> {
        Ok(u32::from(w(i)?) | u32::from(w(i + 1)?) << 16)
    };
    let area = |i: usize| -> std::result::Result<MailboxArea, String> {
        Ok(MailboxArea {
            out_start: w(i)?,
            out_len: w(i + 1)?,
            in_start: w(i + 2)?,
            in_len: w(i + 3)?,
        })
    };
    let mut info = SiiInfo {
        vendor: dw(0x08)?,
        product: dw(0x0A)?,
        revision: dw(0x0C)?,
        serial: dw(0x0E)?,
        alias: w(0x04)?,
        boot_mailbox: area(0x14)?,
        mailbox: area(0x18)?,
        protocols: w(0x1C)?,
        raw: raw.to_vec(),
        ..SiiInfo::default()
    };
    let mut at = CATEGORIES;
    let mut name_index = None;
    loop {
        let kind = w(at)?;
        if kind == END {
            break;
        }
        let len = 2 * usize::from(w(at + 1)?);
        let start = 2 * (at + 2);
        let data = raw
            .get(start..start + len)
            .ok_or_else(|| format!("category {kind} at word {at:02X}h runs past the end"))?;
        match kind {
            10 => info.strings = strings(data)?,
            30 => name_index = data.get(3).copied(),
            40 => info.fmmus = data.iter().copied().filter(|b| *b != 0xFF).collect(),
            41 => {
                info.sync_managers = data
                    .chunks_exact(8)
                    .map(|c| SiiSm {
                        start: u16::from_le_bytes([c[0], c[1]]),
                        len: u16::from_le_bytes([c[2], c[3]]),
                        control: c[4],
                        enable: c[6],
                        kind: SmKind::of(c[7]),
                    })
                    .collect()
            }
            50 => info.tx_pdos = pdos(data)?,
            51 => info.rx_pdos = pdos(data)?,
            _ => {}
        }
        at += 2 + len / 2;
    }
    info.name = name_index
        .filter(|i| *i > 0)
        .and_then(|i| info.strings.get(usize::from(i) - 1).cloned());
    Ok(info)
}

fn strings(data: &[u8]) -> std::result::Result<Vec<String>, String> {
    let n = *data.first().ok_or("empty strings category")?;
    let mut out = Vec::new();
    let mut at = 1;
    for i in 0..n {
        let len = usize::from(*data.get(at).ok_or(format!("string {} truncated", i + 1))?);
        let s = data
            .get(at + 1..at + 1 + len)
            .ok_or(format!("string {} truncated", i + 1))?;
        out.push(String::from_utf8_lossy(s).into_owned());
        at += 1 + len;
    }
    Ok(out)
}

fn pdos(data: &[u8]) -> std::result::Result<Vec<SiiPdo>, String> {
    let mut out = Vec::new();
    let mut at = 0;
    while at + 8 <= data.len() {
        let h = &data[at..at + 8];
        let n = usize::from(h[2]);
        let mut entries = Vec::with_capacity(n);
        for e in 0..n {
            let b = at + 8 + 8 * e;
            let c = data.get(b..b + 8).ok_or_else(|| {
                format!(
                    "PDO {:04X}h entry {e} truncated",
                    u16::from_le_bytes([h[0], h[1]])
                )
            })?;
            entries.push(SiiPdoEntry {
                index: u16::from_le_bytes([c[0], c[1]]),
                sub: c[2],
                bits: c[5],
            });
        }
        out.push(SiiPdo {
            index: u16::from_le_bytes([h[0], h[1]]),
            sm: h[3],
            entries,
        });
        at += 8 + 8 * n;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small SII: identity, mailbox 1000h/128 and 1080h/128, CoE; strings ("X"), general
    /// (name = string 1), SyncM (SM2 1100h/12 bytes, control 64h, outputs), end.
    fn image() -> Vec<u8> {
        let mut w = vec![0u16; 0x40];
        w[0x08] = 0x0538; // vendor
        w[0x0A] = 0x0550; // product
        w[0x18..0x1C].copy_from_slice(&[0x1000, 128, 0x1080, 128]);
        w[0x1C] = 0x0004; // CoE
        w.extend([10, 2, 0x0101, 0x0058]); // strings: 1 string "X" (+ pad)
        w.extend([30, 2, 0x0000, 0x0100]); // general: name index 1 (byte 3)
        w.extend([41, 4, 0x1100, 12, 0x0064, 0x0301]); // SyncM: outputs
        w.push(0xFFFF);
        w.iter().flat_map(|x| x.to_le_bytes()).collect()
    }

    #[test]
    fn identity_mailbox_strings_and_sync_managers() {
        let i = parse(&image()).unwrap();
        assert_eq!((i.vendor, i.product), (0x538, 0x550));
        assert_eq!((i.mailbox.out_start, i.mailbox.in_len), (0x1000, 128));
        assert!(i.has_mailbox());
        assert_eq!(i.name.as_deref(), Some("X"));
        assert_eq!(
            i.sync_managers,
            [SiiSm {
                start: 0x1100,
                len: 12,
                control: 0x64,
                enable: 1,
                kind: SmKind::Outputs
            }]
        );
    }

    #[test]
    fn every_truncation_is_an_error_not_a_panic() {
        let img = image();
        for n in 0..img.len() {
            assert!(parse(&img[..n]).is_err(), "{n} bytes");
        }
    }
}
