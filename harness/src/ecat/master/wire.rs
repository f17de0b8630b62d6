//! The master's datagrams and their framing (ETG.1000.4 §5.3–§5.4).
//!
//! STOPGAP: `proto::ecat` (frame, datagram) was not in the tree when the master was written.
//! Only what the master needs to put its own datagrams into a frame and to match the frame
//! that comes back; it moves onto `proto::ecat`'s views when they land. Nothing here panics on
//! any input.

use std::fmt;

/// EtherType of EtherCAT (ETG.1000.4 §5.3; BU 0620 §2.2.3 figure 3 prints 88ABh, an erratum).
pub(crate) const ETHERTYPE: u16 = 0x88A4;
/// Ethernet II header bytes.
const ETH_HEADER: usize = 14;
/// EtherCAT frame header bytes.
const ECAT_HEADER: usize = 2;
/// Datagram header bytes (command .. IRQ).
const DG_HEADER: usize = 10;
/// Largest EtherCAT payload (a 1500-byte Ethernet payload less the frame header).
pub(crate) const MAX_PAYLOAD: usize = 1498;
/// Shortest Ethernet frame without FCS: shorter frames are padded.
const MIN_FRAME: usize = 60;

/// A datagram command (ETG.1000.4 table 13). Open: any byte can be sent.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) struct Command(pub(crate) u8);

impl Command {
    /// No operation.
    pub(crate) const NOP: Command = Command(0);
    /// Auto increment physical read.
    pub(crate) const APRD: Command = Command(1);
    /// Auto increment physical write.
    pub(crate) const APWR: Command = Command(2);
    /// Configured address physical read.
    pub(crate) const FPRD: Command = Command(4);
    /// Configured address physical write.
    pub(crate) const FPWR: Command = Command(5);
    /// Broadcast read.
    pub(crate) const BRD: Command = Command(7);
    /// Broadcast write.
    pub(crate) const BWR: Command = Command(8);
    /// Logical read/write.
    pub(crate) const LRW: Command = Command(12);

    /// Whether the address is logical (LRD, LWR, LRW).
    pub(crate) fn logical(self) -> bool {
        matches!(self.0, 10..=12)
    }
}

const NAMES: [&str; 15] = [
    "NOP", "APRD", "APWR", "APRW", "FPRD", "FPWR", "FPRW", "BRD", "BWR", "BRW", "LRD", "LWR",
    "LRW", "ARMW", "FRMW",
];

impl fmt::Display for Command {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match NAMES.get(usize::from(self.0)) {
            Some(n) => f.write_str(n),
            None => write!(f, "command {:02X}h", self.0),
        }
    }
}

impl fmt::Debug for Command {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(self, f)
    }
}

/// One datagram the master sends.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Datagram {
    /// Command.
    pub(crate) command: Command,
    /// ADP (position, station address) — or the logical address's low word.
    pub(crate) adp: u16,
    /// ADO (register) — or the logical address's high word.
    pub(crate) ado: u16,
    /// The data (a read sends this many bytes, usually zeros).
    pub(crate) data: Vec<u8>,
}

impl Datagram {
    /// A physical or broadcast datagram.
    pub(crate) fn new(command: Command, adp: u16, ado: u16, data: Vec<u8>) -> Datagram {
        Datagram {
            command,
            adp,
            ado,
            data,
        }
    }

    /// A read of `len` bytes.
    pub(crate) fn read(command: Command, adp: u16, ado: u16, len: usize) -> Datagram {
        Datagram::new(command, adp, ado, vec![0; len])
    }

    /// A logical datagram at `address`.
    pub(crate) fn logical(command: Command, address: u32, data: Vec<u8>) -> Datagram {
        Datagram::new(command, address as u16, (address >> 16) as u16, data)
    }

    /// `FPRD 1001h:0130h` or `LRW 00010000h`.
    pub(crate) fn describe(&self) -> String {
        address(self.command, self.adp, self.ado)
    }
}

fn address(c: Command, adp: u16, ado: u16) -> String {
    if c.logical() {
        format!("{c} {:08X}h", u32::from(adp) | u32::from(ado) << 16)
    } else {
        format!("{c} {adp:04X}h:{ado:04X}h")
    }
}

/// What came back for one datagram.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Returned {
    /// Command as returned.
    pub(crate) command: Command,
    /// ADP as returned (auto-increment commands count it up per slave).
    pub(crate) adp: u16,
    /// ADO as returned.
    pub(crate) ado: u16,
    /// Data as returned.
    pub(crate) data: Vec<u8>,
    /// Working counter.
    pub(crate) wkc: u16,
}

/// The master cannot build the frame.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub(crate) enum BuildError {
    /// The datagrams do not fit one frame.
    #[error("{len} bytes of datagrams do not fit a frame ({MAX_PAYLOAD} at most)")]
    TooLong {
        /// Their length.
        len: usize,
    },
    /// A datagram's data is longer than its 11-bit length field.
    #[error("datagram of {len} bytes: the length field holds 2047 at most")]
    DatagramTooLong {
        /// Its length.
        len: usize,
    },
}

impl From<BuildError> for super::error::UsageError {
    fn from(e: BuildError) -> Self {
        super::error::UsageError::TooLong {
            what: "EtherCAT frame",
            len: match e {
                BuildError::TooLong { len } | BuildError::DatagramTooLong { len } => len,
            },
            max: MAX_PAYLOAD,
        }
    }
}

fn ethernet(mac: [u8; 6], capacity: usize) -> Vec<u8> {
    let mut f = Vec::with_capacity(capacity.max(MIN_FRAME));
    f.extend([0xFF; 6]);
    f.extend(mac);
    f.extend(ETHERTYPE.to_be_bytes());
    f
}

/// The Ethernet frame carrying `datagrams` with `index`, padded to 60 bytes.
pub(crate) fn frame(
    mac: [u8; 6],
    index: u8,
    datagrams: &[Datagram],
) -> Result<Vec<u8>, BuildError> {
    let len: usize = datagrams.iter().map(|d| DG_HEADER + d.data.len() + 2).sum();
    if len > MAX_PAYLOAD {
        return Err(BuildError::TooLong { len });
    }
    let mut f = ethernet(mac, ETH_HEADER + ECAT_HEADER + len);
    f.extend((len as u16 | 0x1000).to_le_bytes());
    for (i, d) in datagrams.iter().enumerate() {
        if d.data.len() > 0x7FF {
            return Err(BuildError::DatagramTooLong { len: d.data.len() });
        }
        let more = if i + 1 < datagrams.len() { 0x8000 } else { 0 };
        f.extend([d.command.0, index]);
        f.extend(d.adp.to_le_bytes());
        f.extend(d.ado.to_le_bytes());
        f.extend((d.data.len() as u16 | more).to_le_bytes());
        f.extend([0, 0]);
        f.extend(&d.data);
        f.extend([0, 0]);
    }
    f.resize(f.len().max(MIN_FRAME), 0);
    Ok(f)
}

/// The Ethernet frame carrying `payload` (an EtherCAT header and datagrams as given).
pub(crate) fn raw_frame(mac: [u8; 6], payload: &[u8]) -> Result<Vec<u8>, BuildError> {
    if payload.len() > MAX_PAYLOAD + ECAT_HEADER {
        return Err(BuildError::TooLong { len: payload.len() });
    }
    let mut f = ethernet(mac, ETH_HEADER + payload.len());
    f.extend(payload);
    f.resize(f.len().max(MIN_FRAME), 0);
    Ok(f)
}

/// The bytes after the Ethernet header of an EtherCAT frame (one 802.1Q tag skipped).
pub(crate) fn ethercat_payload(frame: &[u8]) -> Option<&[u8]> {
    let ty = |at: usize| {
        frame
            .get(at..at + 2)
            .map(|b| u16::from_be_bytes([b[0], b[1]]))
    };
    match ty(12)? {
        ETHERTYPE => frame.get(14..),
        0x8100 if ty(16)? == ETHERTYPE => frame.get(18..),
        _ => None,
    }
}

/// What a received frame is to the exchange waiting for `index`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Reply {
    /// Not an EtherCAT frame, or another index: not ours.
    Foreign,
    /// An EtherCAT frame that cannot be parsed, or ours with other datagrams.
    Malformed(String),
    /// The answer.
    Ours(Vec<Returned>),
}

/// Parses `frame` as the answer to `sent` with `index`.
pub(crate) fn parse_reply(frame: &[u8], index: u8, sent: &[Datagram]) -> Reply {
    let Some(p) = ethercat_payload(frame) else {
        return Reply::Foreign;
    };
    let Some(h) = p.get(..2) else {
        return Reply::Malformed(format!("truncated: need 2 bytes, got {}", p.len()));
    };
    let h = u16::from_le_bytes([h[0], h[1]]);
    let (len, kind) = (usize::from(h & 0x7FF), h >> 12);
    if kind != 1 {
        return Reply::Foreign;
    }
    let Some(body) = p.get(ECAT_HEADER..ECAT_HEADER + len) else {
        return Reply::Malformed(format!(
            "frame length {len} exceeds the {} bytes present",
            p.len() - ECAT_HEADER
        ));
    };
    let mut out = Vec::new();
    let mut at = 0;
    loop {
        let Some(hd) = body.get(at..at + DG_HEADER) else {
            return Reply::Malformed(format!("datagram {} truncated", out.len()));
        };
        if hd[1] != index {
            return Reply::Foreign;
        }
        let l = u16::from_le_bytes([hd[6], hd[7]]);
        let dlen = usize::from(l & 0x7FF);
        let Some(rest) = body.get(at + DG_HEADER..at + DG_HEADER + dlen + 2) else {
            return Reply::Malformed(format!(
                "datagram {}: length {dlen} runs past the frame",
                out.len()
            ));
        };
        out.push(Returned {
            command: Command(hd[0]),
            adp: u16::from_le_bytes([hd[2], hd[3]]),
            ado: u16::from_le_bytes([hd[4], hd[5]]),
            data: rest[..dlen].to_vec(),
            wkc: u16::from_le_bytes([rest[dlen], rest[dlen + 1]]),
        });
        at += DG_HEADER + dlen + 2;
        if l & 0x8000 == 0 {
            break;
        }
    }
    let same = out.len() == sent.len()
        && out
            .iter()
            .zip(sent)
            .all(|(r, s)| r.command == s.command && r.data.len() == s.data.len());
    if same {
        Reply::Ours(out)
    } else {
        Reply::Malformed(format!(
            "index {index:02X}h came back with other datagrams than sent"
        ))
    }
}

/// `FPRD 1001h:0130h 6 B + LRW 00010000h 24 B`.
pub(crate) fn describe_sent(datagrams: &[Datagram]) -> String {
    let v: Vec<String> = datagrams
        .iter()
        .map(|d| format!("{} {} B", d.describe(), d.data.len()))
        .collect();
    v.join(" + ")
}

/// `FPRD 1001h:0130h WKC 1 = 02 00` per datagram.
pub(crate) fn describe_returned(returned: &[Returned]) -> String {
    let v: Vec<String> = returned
        .iter()
        .map(|r| {
            let data = if r.data.len() <= 16 {
                crate::runner::hex(&r.data)
            } else {
                format!(
                    "{} … ({} B)",
                    crate::runner::hex(&r.data[..16]),
                    r.data.len()
                )
            };
            format!(
                "{} WKC {} = {data}",
                address(r.command, r.adp, r.ado),
                r.wkc
            )
        })
        .collect();
    v.join(" + ")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// BRD 0000h, 2 bytes, index 5 (ETG.1000.4 §5.4).
    fn brd() -> Vec<Datagram> {
        vec![Datagram::read(Command::BRD, 0, 0x0000, 2)]
    }

    #[test]
    fn a_frame_with_one_datagram() {
        let f = frame([0x10; 6], 5, &brd()).unwrap();
        assert_eq!(
            f[..30],
            [
                0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, // destination: broadcast
                0x10, 0x10, 0x10, 0x10, 0x10, 0x10, // source: the master
                0x88, 0xA4, // EtherType EtherCAT
                0x0E, 0x10, // length 14, type 1
                0x07, 0x05, // BRD, index 5
                0x00, 0x00, 0x00, 0x00, // ADP, ADO
                0x02, 0x00, // length 2, last
                0x00, 0x00, // IRQ
                0x00, 0x00, // data
                0x00, 0x00, // working counter
            ]
        );
        assert_eq!(f.len(), 60, "padded");
    }

    #[test]
    fn the_reply_is_matched_by_index_and_datagrams() {
        let sent = brd();
        let mut f = frame([0x10; 6], 5, &sent).unwrap();
        f[6] |= 0x02;
        f[26] = 0x80; // data as an ESC fills it
        f[28] = 1; // working counter 1
        match parse_reply(&f, 5, &sent) {
            Reply::Ours(r) => assert_eq!((r[0].wkc, r[0].data.clone()), (1, vec![0x80, 0])),
            other => panic!("{other:?}"),
        }
        assert_eq!(parse_reply(&f, 6, &sent), Reply::Foreign, "other index");
        let other = vec![Datagram::read(Command::BRD, 0, 0x0000, 4)];
        assert!(matches!(parse_reply(&f, 5, &other), Reply::Malformed(_)));
        let mut ip = f.clone();
        ip[12..14].copy_from_slice(&[0x08, 0x00]);
        assert_eq!(parse_reply(&ip, 5, &sent), Reply::Foreign, "IPv4");
    }

    #[test]
    fn every_truncation_and_bit_flip_is_handled() {
        let sent = vec![
            Datagram::read(Command::FPRD, 0x1001, 0x0130, 6),
            Datagram::new(Command::LRW, 0, 1, vec![1, 2, 3, 4]),
        ];
        let f = frame([0x10; 6], 9, &sent).unwrap();
        for n in 0..f.len() {
            let _ = parse_reply(&f[..n], 9, &sent);
        }
        for at in 0..f.len() {
            for bit in 0..8 {
                let mut g = f.clone();
                g[at] ^= 1 << bit;
                let _ = parse_reply(&g, 9, &sent);
            }
        }
    }

    #[test]
    fn too_long_is_refused() {
        let big = vec![Datagram::read(Command::FPRD, 1, 0, 1500)];
        assert!(matches!(
            frame([0; 6], 0, &big),
            Err(BuildError::TooLong { .. })
        ));
        assert_eq!(Command(0x0C).to_string(), "LRW");
        assert_eq!(Command(0x2A).to_string(), "command 2Ah");
    }
}
