//! The byte layouts the slave reads and writes in place: Ethernet II header, EtherCAT frame
//! header and datagrams (ETG.1000.4 §5.3–§5.4), mailbox header (ETG.1000.6 §5.5), CoE and SDO
//! (ETG.1000.6 §5.6).
//!
//! A stopgap: `proto::ecat` (the shared codec of issue #9 B1) was not in the tree when the
//! slave was written; these are only the offsets and the checks the slave needs, and move to
//! `proto::ecat` views when it lands. Nothing here panics on any input.

use super::coe::{SdoRequest, SdoResponse};

/// EtherType of EtherCAT (ETG.1000.4 §5.3; BU 0620 §2.2.3 figure 3 prints 88ABh, an erratum).
pub const ETHERTYPE: u16 = 0x88A4;
const VLAN: u16 = 0x8100;
/// Bytes of a datagram's header (command .. IRQ).
pub(crate) const DATAGRAM_HEADER: usize = 10;
/// Mailbox header bytes.
pub(crate) const MAILBOX_HEADER: usize = 6;

/// Why a frame was not processed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum DropReason {
    /// Shorter than an Ethernet and EtherCAT header.
    #[error("frame truncated: need {need} bytes, got {got}")]
    Truncated {
        /// Bytes needed.
        need: usize,
        /// Bytes present.
        got: usize,
    },
    /// The EtherCAT header's length exceeds the frame.
    #[error("EtherCAT length {declared} exceeds the {available} bytes after the header")]
    FrameLength {
        /// Declared length.
        declared: usize,
        /// Bytes present.
        available: usize,
    },
    /// A datagram's length runs past the EtherCAT length, or the datagrams do not fill it.
    #[error("datagram {index}: length {len} does not fit the {left} bytes left")]
    DatagramLength {
        /// Datagram number, 0-based.
        index: usize,
        /// Its declared data length.
        len: usize,
        /// Bytes left in the frame.
        left: usize,
    },
    /// Bytes after the last datagram within the EtherCAT length.
    #[error("{extra} bytes after the last datagram within the EtherCAT length")]
    Trailing {
        /// Bytes left over.
        extra: usize,
    },
}

/// Where the EtherCAT payload of an Ethernet frame starts, if it is one (`None`: another
/// EtherType; one 802.1Q tag is skipped).
pub(crate) fn ethercat_offset(frame: &[u8]) -> Option<usize> {
    let ty = |at: usize| {
        frame
            .get(at..at + 2)
            .map(|b| u16::from_be_bytes([b[0], b[1]]))
    };
    match ty(12)? {
        ETHERTYPE => Some(14),
        VLAN if ty(16)? == ETHERTYPE => Some(18),
        _ => None,
    }
}

/// One datagram's position in the frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Span {
    /// Offset of the command byte.
    pub(crate) at: usize,
    /// Data length.
    pub(crate) len: usize,
}

impl Span {
    /// Offset of the data.
    pub(crate) fn data(&self) -> usize {
        self.at + DATAGRAM_HEADER
    }
    /// Offset of the working counter.
    pub(crate) fn wkc(&self) -> usize {
        self.data() + self.len
    }
}

/// Result of checking an EtherCAT payload at `start`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Payload {
    /// Not EtherCAT commands (frame type ≠ 1): passed on unprocessed.
    Other,
    /// The datagrams.
    Datagrams(Vec<Span>),
}

/// Checks the EtherCAT header and every datagram's length (ETG.1000.4 §5.3: the header's
/// length is the sum of the datagrams; each datagram's "more" bit says whether one follows).
pub(crate) fn datagrams(frame: &[u8], start: usize) -> Result<Payload, DropReason> {
    let need = start + 2;
    let head = frame.get(start..need).ok_or(DropReason::Truncated {
        need,
        got: frame.len(),
    })?;
    let h = u16::from_le_bytes([head[0], head[1]]);
    if h >> 12 != 1 {
        return Ok(Payload::Other);
    }
    let declared = usize::from(h & 0x07FF);
    let available = frame.len() - need;
    if declared > available {
        return Err(DropReason::FrameLength {
            declared,
            available,
        });
    }
    let end = need + declared;
    let mut spans = Vec::new();
    let mut at = need;
    loop {
        let left = end - at;
        if left < DATAGRAM_HEADER + 2 {
            return Err(DropReason::DatagramLength {
                index: spans.len(),
                len: 0,
                left,
            });
        }
        let lf = u16::from_le_bytes([frame[at + 6], frame[at + 7]]);
        let len = usize::from(lf & 0x07FF);
        if DATAGRAM_HEADER + len + 2 > left {
            return Err(DropReason::DatagramLength {
                index: spans.len(),
                len,
                left,
            });
        }
        spans.push(Span { at, len });
        at += DATAGRAM_HEADER + len + 2;
        if lf & 0x8000 == 0 {
            break;
        }
    }
    if at != end {
        return Err(DropReason::Trailing { extra: end - at });
    }
    Ok(Payload::Datagrams(spans))
}

/// A mailbox header (ETG.1000.6 table 29).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct MailboxHeader {
    /// Bytes of data after the header.
    pub(crate) length: usize,
    /// Type (0 error, 3 CoE, …).
    pub(crate) kind: u8,
    /// Counter 0..7 (0: not used).
    pub(crate) counter: u8,
}

impl MailboxHeader {
    /// Reads a header; `None` when fewer than 6 bytes.
    pub(crate) fn parse(b: &[u8]) -> Option<MailboxHeader> {
        let h = b.get(..MAILBOX_HEADER)?;
        Some(MailboxHeader {
            length: usize::from(u16::from_le_bytes([h[0], h[1]])),
            kind: h[5] & 0x0F,
            counter: (h[5] >> 4) & 0x07,
        })
    }

    /// A message of `kind` with `body`.
    pub(crate) fn message(kind: u8, counter: u8, body: &[u8]) -> Vec<u8> {
        let mut m = Vec::with_capacity(MAILBOX_HEADER + body.len());
        m.extend((body.len() as u16).to_le_bytes());
        m.extend([0, 0, 0, kind | (counter & 7) << 4]);
        m.extend(body);
        m
    }
}

/// The body of a mailbox error reply (type 0): service 1, then the detail code.
pub(crate) fn mailbox_error(detail: u16) -> Vec<u8> {
    let mut b = 0x0001u16.to_le_bytes().to_vec();
    b.extend(detail.to_le_bytes());
    b
}

/// CoE service of a CoE header (bits 12–15).
pub(crate) fn coe_service(body: &[u8]) -> Option<u8> {
    body.get(1).map(|b| b >> 4)
}

/// Reads an SDO request (the bytes after the CoE header); `None` when shorter than 8 bytes.
pub(crate) fn sdo_request(b: &[u8]) -> Option<SdoRequest> {
    if b.len() < 8 {
        return None;
    }
    let cmd = b[0];
    let index = u16::from_le_bytes([b[1], b[2]]);
    let sub = b[3];
    let complete = cmd & 0x10 != 0;
    let toggle = cmd & 0x10 != 0;
    Some(match cmd >> 5 {
        1 => {
            let sized = cmd & 0x01 != 0;
            let expedited = cmd & 0x02 != 0;
            if expedited {
                let n = usize::from((cmd >> 2) & 3);
                SdoRequest::InitiateDownload {
                    index,
                    sub,
                    complete,
                    expedited,
                    size: sized.then_some((4 - n) as u32),
                    data: b[4..8].to_vec(),
                }
            } else {
                SdoRequest::InitiateDownload {
                    index,
                    sub,
                    complete,
                    expedited,
                    size: sized.then(|| u32::from_le_bytes([b[4], b[5], b[6], b[7]])),
                    data: b[8..].to_vec(),
                }
            }
        }
        0 => {
            // Fewer than 7 bytes: the minimal 8-byte body with n unused bytes (bits 1–3).
            let data = if b.len() == 8 {
                let n = usize::from((cmd >> 1) & 7);
                b[1..8 - n].to_vec()
            } else {
                b[1..].to_vec()
            };
            SdoRequest::DownloadSegment {
                toggle,
                last: cmd & 0x01 != 0,
                data,
            }
        }
        2 => SdoRequest::InitiateUpload {
            index,
            sub,
            complete,
        },
        3 => SdoRequest::UploadSegment { toggle },
        4 => SdoRequest::Abort,
        _ => SdoRequest::Unknown { index, sub },
    })
}

/// The bytes of an SDO response, with the CoE header (service 3, SDO response; 2 for an
/// abort).
pub(crate) fn sdo_response(r: &SdoResponse) -> Vec<u8> {
    let mut b = 0x3000u16.to_le_bytes().to_vec();
    let head = |b: &mut Vec<u8>, cmd: u8, index: u16, sub: u8| {
        b.push(cmd);
        b.extend(index.to_le_bytes());
        b.push(sub);
    };
    let ca = |c: bool| u8::from(c) << 4;
    match r {
        SdoResponse::InitiateDownload {
            index,
            sub,
            complete,
        } => {
            head(&mut b, 0x60 | ca(*complete), *index, *sub);
            b.extend([0; 4]);
        }
        SdoResponse::DownloadSegment { toggle } => {
            b.push(0x20 | u8::from(*toggle) << 4);
            b.extend([0; 7]);
        }
        SdoResponse::UploadExpedited {
            index,
            sub,
            complete,
            data,
        } => {
            let n = 4 - data.len().min(4) as u8;
            head(&mut b, 0x43 | n << 2 | ca(*complete), *index, *sub);
            let mut d = data.clone();
            d.resize(4, 0);
            b.extend(d);
        }
        SdoResponse::UploadNormal {
            index,
            sub,
            complete,
            size,
            data,
        } => {
            head(&mut b, 0x41 | ca(*complete), *index, *sub);
            b.extend(size.to_le_bytes());
            b.extend(data);
        }
        SdoResponse::UploadSegment { toggle, last, data } => {
            let n = 7usize.saturating_sub(data.len()) as u8;
            b.push(u8::from(*toggle) << 4 | n << 1 | u8::from(*last));
            b.extend(data);
            b.resize(b.len() + usize::from(n), 0);
        }
        SdoResponse::Abort { index, sub, code } => {
            // Abort transfer travels as an SDO *request* in both directions (ETG.1000.6
            // §5.6.2.7: CoE service 2), which masters (SOEM) rely on.
            b = 0x2000u16.to_le_bytes().to_vec();
            head(&mut b, 0x80, *index, *sub);
            b.extend(code.0.to_le_bytes());
        }
    }
    b
}

/// A CoE emergency (service 1): error code, error register, 5 manufacturer bytes.
pub(crate) fn emergency(code: u16, register: u8, data: [u8; 5]) -> Vec<u8> {
    let mut b = 0x1000u16.to_le_bytes().to_vec();
    b.extend(code.to_le_bytes());
    b.push(register);
    b.extend(data);
    b
}
