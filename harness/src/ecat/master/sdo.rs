//! The CoE SDO client (ETG.1000.6 §5.6.2; CiA 301 §7.2.4.3): upload and download, expedited
//! (up to 4 bytes in the initiate message), normal (the data in the initiate message after the
//! size) and segmented (the rest in segments with an alternating toggle bit), with complete
//! access (every sub-index at once) if asked.
//!
//! The NORD parameters are objects 2000h + 800h·(FI − 1) + parameter number, sub-index 1 first
//! (BU 0620 §2.2.7: P102 of FI 3 is 3066h). An abort transfer from the slave is its refusal,
//! [`Refusal::SdoAbort`] with the abort code (BU 0620 §2.2.7.2); a response that does not
//! answer the request breaks the protocol ([`ProtocolError`]).

use super::codes::SdoAbortCode;
use super::engine::Master;
use super::error::{ProtocolError, Refusal, Result, UsageError};
use super::mailbox::{HEADER, TYPE_COE};
use super::segment::Segment;

/// CoE header bytes.
const COE_HEADER: usize = 2;
/// CoE service: SDO request.
const SDO_REQUEST: u8 = 2;
/// CoE service: SDO response.
const SDO_RESPONSE: u8 = 3;
/// The abort transfer command.
const ABORT: u8 = 0x80;
/// Complete access (command bit 4 of initiate requests).
const COMPLETE: u8 = 0x10;

/// A CoE SDO body: CoE header (number 0, service), then the SDO bytes.
fn coe(service: u8, sdo: &[u8]) -> Vec<u8> {
    let mut b = Vec::with_capacity(COE_HEADER + sdo.len());
    b.extend((u16::from(service) << 12).to_le_bytes());
    b.extend(sdo);
    b
}

/// The initiate bytes: command, index, sub-index, 4 data bytes.
fn initiate(command: u8, index: u16, sub: u8, data: [u8; 4]) -> [u8; 8] {
    let i = index.to_le_bytes();
    [command, i[0], i[1], sub, data[0], data[1], data[2], data[3]]
}

/// One SDO response taken apart: the command byte and the SDO bytes after the CoE header.
struct Response {
    command: u8,
    sdo: Vec<u8>,
}

impl<S: Segment> Master<S> {
    /// One SDO request and its response (an abort is returned as [`Refusal::SdoAbort`]).
    fn sdo_exchange(&mut self, station: u16, index: u16, sub: u8, sdo: &[u8]) -> Result<Response> {
        let m = self.mailbox_request(station, TYPE_COE, &coe(SDO_REQUEST, sdo))?;
        if m.kind != TYPE_COE {
            return Err(ProtocolError::Unexpected {
                expected: "a CoE reply",
                got: format!("mailbox type {}", m.kind),
            }
            .into());
        }
        let service = m.body.get(1).map_or(0, |b| b >> 4);
        let Some(&command) = m.body.get(COE_HEADER) else {
            return Err(ProtocolError::Mailbox("CoE reply without an SDO command".into()).into());
        };
        let sdo = m.body[COE_HEADER..].to_vec();
        // An abort comes as an SDO request (ETG.1000.6 §5.6.2.7) — or as a response.
        if command == ABORT && (service == SDO_REQUEST || service == SDO_RESPONSE) {
            let code = sdo
                .get(4..8)
                .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .ok_or_else(|| ProtocolError::Mailbox("SDO abort without its code".into()))?;
            return Err(Refusal::SdoAbort {
                index,
                sub,
                code: SdoAbortCode(code),
            }
            .into());
        }
        if service != SDO_RESPONSE {
            return Err(ProtocolError::Unexpected {
                expected: "an SDO response",
                got: format!("CoE service {service}"),
            }
            .into());
        }
        Ok(Response { command, sdo })
    }

    /// Checks that an initiate response names the object of the request.
    fn same_object(r: &Response, index: u16, sub: u8) -> Result<()> {
        let got = r
            .sdo
            .get(1..4)
            .map(|b| (u16::from_le_bytes([b[0], b[1]]), b[2]))
            .ok_or_else(|| ProtocolError::Mailbox("SDO response truncated".into()))?;
        if got != (index, sub) {
            return Err(ProtocolError::Unexpected {
                expected: "the response for the object requested",
                got: format!("response for {:04X}h:{:02X}h", got.0, got.1),
            }
            .into());
        }
        Ok(())
    }

    /// SDO upload of `index`:`sub` from `station` (complete access: every sub-index from
    /// `sub`, 0 or 1, on).
    pub(crate) fn sdo_upload(
        &mut self,
        station: u16,
        index: u16,
        sub: u8,
        complete: bool,
    ) -> Result<Vec<u8>> {
        let command = 0x40 | if complete { COMPLETE } else { 0 };
        let r = self.sdo_exchange(station, index, sub, &initiate(command, index, sub, [0; 4]))?;
        if r.command >> 5 != 2 {
            return Err(unexpected("an upload initiate response", r.command));
        }
        Self::same_object(&r, index, sub)?;
        let (expedited, sized) = (r.command & 0x02 != 0, r.command & 0x01 != 0);
        if expedited {
            let unused = if sized {
                usize::from((r.command >> 2) & 3)
            } else {
                0
            };
            return Ok(r.sdo.get(4..8 - unused).unwrap_or_default().to_vec());
        }
        let size = r
            .sdo
            .get(4..8)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .ok_or_else(|| ProtocolError::Mailbox("normal upload response truncated".into()))?;
        let mut data = r.sdo.get(8..).unwrap_or_default().to_vec();
        let want = size as usize;
        if data.len() >= want {
            data.truncate(want);
            return Ok(data);
        }
        // Segmented: the rest in upload segments.
        let mut toggle = false;
        loop {
            let t = u8::from(toggle) << 4;
            let r = self.sdo_exchange(station, index, sub, &[0x60 | t, 0, 0, 0, 0, 0, 0, 0])?;
            if r.command >> 5 != 0 {
                return Err(unexpected("an upload segment response", r.command));
            }
            if r.command & 0x10 != t {
                return Err(ProtocolError::Toggle {
                    expected: toggle,
                    got: !toggle,
                }
                .into());
            }
            let seg = &r.sdo[1..];
            // Segments of 7 bytes or fewer say how many of the 7 are unused.
            let len = if seg.len() <= 7 {
                7usize
                    .saturating_sub(usize::from((r.command >> 1) & 7))
                    .min(seg.len())
            } else {
                seg.len()
            };
            data.extend(&seg[..len]);
            if r.command & 0x01 != 0 {
                break;
            }
            if data.len() > want {
                break;
            }
            toggle = !toggle;
        }
        if data.len() != want {
            return Err(ProtocolError::SdoSize {
                announced: size,
                got: data.len(),
            }
            .into());
        }
        Ok(data)
    }

    /// SDO download of `data` to `index`:`sub` of `station` (expedited for 1 to 4 bytes
    /// without complete access, else normal and, if the mailbox is too small, segmented).
    pub(crate) fn sdo_download(
        &mut self,
        station: u16,
        index: u16,
        sub: u8,
        data: &[u8],
        complete: bool,
    ) -> Result<()> {
        let ca = if complete { COMPLETE } else { 0 };
        if !complete && (1..=4).contains(&data.len()) {
            let mut d = [0; 4];
            d[..data.len()].copy_from_slice(data);
            let command = 0x23 | ((4 - data.len() as u8) << 2);
            let r = self.sdo_exchange(station, index, sub, &initiate(command, index, sub, d))?;
            return Self::initiate_done(&r, index, sub);
        }
        let room = self.mailbox_room(station)?;
        // Normal: size, then as much data as fits behind the 8 initiate bytes.
        let first = data.len().min(room.saturating_sub(8));
        let mut sdo = initiate(0x21 | ca, index, sub, (data.len() as u32).to_le_bytes()).to_vec();
        sdo.extend(&data[..first]);
        let r = self.sdo_exchange(station, index, sub, &sdo)?;
        Self::initiate_done(&r, index, sub)?;
        let mut rest = &data[first..];
        let mut toggle = false;
        while !rest.is_empty() {
            let n = rest.len().min(room.saturating_sub(1).max(1));
            let last = n == rest.len();
            let t = u8::from(toggle) << 4;
            let unused = if n < 7 { (7 - n as u8) << 1 } else { 0 };
            let mut seg = vec![t | unused | u8::from(last)];
            seg.extend(&rest[..n]);
            seg.resize(seg.len().max(8), 0);
            let r = self.sdo_exchange(station, index, sub, &seg)?;
            if r.command >> 5 != 1 {
                return Err(unexpected("a download segment response", r.command));
            }
            if r.command & 0x10 != t {
                return Err(ProtocolError::Toggle {
                    expected: toggle,
                    got: !toggle,
                }
                .into());
            }
            rest = &rest[n..];
            toggle = !toggle;
        }
        Ok(())
    }

    fn initiate_done(r: &Response, index: u16, sub: u8) -> Result<()> {
        if r.command >> 5 != 3 {
            return Err(unexpected("a download initiate response", r.command));
        }
        Self::same_object(r, index, sub)
    }

    /// SDO bytes that fit one message into `station`'s receive mailbox (after the mailbox
    /// and CoE headers).
    fn mailbox_room(&self, station: u16) -> Result<usize> {
        let out = self
            .slave(station)
            .and_then(|s| s.mailbox)
            .ok_or(UsageError::NoMailbox { station })?
            .0;
        Ok(usize::from(out.len).saturating_sub(HEADER + COE_HEADER))
    }
}

fn unexpected(expected: &'static str, command: u8) -> super::error::MasterError {
    ProtocolError::Unexpected {
        expected,
        got: format!("SDO command {command:02X}h"),
    }
    .into()
}
