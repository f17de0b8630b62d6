//! The master's datagrams in frames, on `proto::ecat`'s codec (ETG.1000.4 §5.3–§5.4): building
//! the Ethernet frame for a list of datagrams with the master's index, and deciding what a
//! received frame is to the exchange waiting for that index.

use proto::ecat::frame::{EcatFrame, FrameType, MAX_DATAGRAMS_LEN};
use proto::ecat::{Command, DatagramRepr, EcatFrameRepr};
use proto::eth::{EthernetFrame, EthernetRepr, MacAddr, ETHERTYPE_ECAT};
use proto::wire::Error;

/// A read of `len` bytes at `adp`:`ado` (zeros sent, the slave fills them in).
pub(crate) fn read(command: Command, adp: u16, ado: u16, len: usize) -> DatagramRepr {
    DatagramRepr::physical(command, 0, adp, ado, vec![0; len])
}

/// A physical or broadcast datagram carrying `data`.
pub(crate) fn write(command: Command, adp: u16, ado: u16, data: Vec<u8>) -> DatagramRepr {
    DatagramRepr::physical(command, 0, adp, ado, data)
}

/// A datagram's command and address, kept to name the access in an error: written out only
/// when one occurs (every cycle checks a working counter).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Access {
    command: Command,
    address: u32,
}

impl Access {
    /// The access `d` makes.
    pub(crate) fn of(d: &DatagramRepr) -> Access {
        Access {
            command: d.command,
            address: d.address,
        }
    }
}

/// `FPRD 1001h:0130h` or `LRW 00010000h`.
impl std::fmt::Display for Access {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [adp0, adp1, ado0, ado1] = self.address.to_le_bytes();
        if self.command.is_logical() {
            write!(f, "{} {:08X}h", self.command, self.address)
        } else {
            let (adp, ado) = (
                u16::from_le_bytes([adp0, adp1]),
                u16::from_le_bytes([ado0, ado1]),
            );
            write!(f, "{} {adp:04X}h:{ado:04X}h", self.command)
        }
    }
}

/// The master cannot put the datagrams into one frame.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub(crate) enum BuildError {
    /// More than a standard Ethernet frame carries.
    #[error("{len} bytes of datagrams do not fit a frame ({MAX_DATAGRAMS_LEN} at most)")]
    TooLong {
        /// Their length.
        len: usize,
    },
    /// The codec refused (a datagram longer than its 11-bit length field).
    #[error(transparent)]
    Codec(#[from] Error),
}

/// The Ethernet frame (broadcast, from `mac`) carrying `datagrams`, each with `index`, padded
/// to 60 bytes.
pub(crate) fn frame(
    mac: [u8; 6],
    index: u8,
    datagrams: &[DatagramRepr],
) -> Result<Vec<u8>, BuildError> {
    let repr = EcatFrameRepr::new(
        datagrams
            .iter()
            .map(|d| DatagramRepr {
                index,
                wkc: 0,
                ..d.clone()
            })
            .collect(),
    );
    let len = repr.datagrams_len();
    if len > MAX_DATAGRAMS_LEN {
        return Err(BuildError::TooLong { len });
    }
    Ok(repr.emit_ethernet(MacAddr::BROADCAST, MacAddr(mac))?)
}

/// The Ethernet frame carrying `payload` (an EtherCAT header and datagrams as given).
pub(crate) fn raw_frame(mac: [u8; 6], payload: &[u8]) -> Result<Vec<u8>, BuildError> {
    if payload.len() > MAX_DATAGRAMS_LEN + proto::ecat::frame::HEADER_LEN {
        return Err(BuildError::TooLong { len: payload.len() });
    }
    Ok(EthernetRepr {
        dst: MacAddr::BROADCAST,
        src: MacAddr(mac),
        ethertype: ETHERTYPE_ECAT,
    }
    .emit(payload))
}

/// The bytes after the Ethernet header of an EtherCAT frame (one 802.1Q tag skipped).
pub(crate) fn ethercat_payload(frame: &[u8]) -> Option<&[u8]> {
    let f = EthernetFrame::new_checked(frame).ok()?;
    (f.inner_ethertype() == ETHERTYPE_ECAT).then(|| &frame[f.header_len()..])
}

/// What a received frame is to the exchange waiting for `index`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Reply {
    /// Not an EtherCAT command frame, or another index: not ours.
    Foreign,
    /// An EtherCAT frame that cannot be parsed (whatever its index byte says: a broken frame
    /// is not trusted to say whose it is).
    Malformed(Error),
    /// Ours by its index, but not the datagrams sent (other commands or lengths).
    Mismatch,
    /// The answer.
    Ours(Vec<DatagramRepr>),
}

/// Parses `frame` as the answer to `sent` with `index`.
pub(crate) fn parse_reply(frame: &[u8], index: u8, sent: &[DatagramRepr]) -> Reply {
    let Some(p) = ethercat_payload(frame) else {
        return Reply::Foreign;
    };
    let f = EcatFrame::new_unchecked(p);
    if p.len() >= 2 && f.frame_type() != FrameType::DLPDU {
        return Reply::Foreign;
    }
    let got = match EcatFrame::new_checked(p).and_then(|f| EcatFrameRepr::parse(&f)) {
        Ok(r) => r.datagrams,
        Err(e) => return Reply::Malformed(e),
    };
    if got.iter().any(|d| d.index != index) {
        return Reply::Foreign;
    }
    let same = got.len() == sent.len()
        && got
            .iter()
            .zip(sent)
            .all(|(r, s)| r.command == s.command && r.data.len() == s.data.len());
    if same {
        Reply::Ours(got)
    } else {
        Reply::Mismatch
    }
}

/// `FPRD 1001h:0130h 6 B + LRW 00010000h 24 B`.
pub(crate) fn describe_sent(datagrams: &[DatagramRepr]) -> String {
    let v: Vec<String> = datagrams
        .iter()
        .map(|d| format!("{} {} B", Access::of(d), d.data.len()))
        .collect();
    v.join(" + ")
}

/// `FPRD 1001h:0130h WKC 1 = 02 00` per datagram.
pub(crate) fn describe_returned(returned: &[DatagramRepr]) -> String {
    let v: Vec<String> = returned
        .iter()
        .map(|r| {
            let data = if r.data.len() <= 16 {
                crate::hex::hex(&r.data)
            } else {
                format!("{} … ({} B)", crate::hex::hex(&r.data[..16]), r.data.len())
            };
            format!("{} WKC {} = {data}", Access::of(r), r.wkc)
        })
        .collect();
    v.join(" + ")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brd() -> Vec<DatagramRepr> {
        vec![read(Command::BRD, 0, 0x0000, 2)]
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
        let other = vec![read(Command::BRD, 0, 0x0000, 4)];
        assert_eq!(parse_reply(&f, 5, &other), Reply::Mismatch);
        let mut ip = f.clone();
        ip[12..14].copy_from_slice(&[0x08, 0x00]);
        assert_eq!(parse_reply(&ip, 5, &sent), Reply::Foreign, "IPv4");
        let mut lying = f.clone();
        lying[14] = 0xFF; // EtherCAT length 7FFh
        lying[15] = 0x17;
        assert!(matches!(parse_reply(&lying, 5, &sent), Reply::Malformed(_)));
    }

    #[test]
    fn every_truncation_and_bit_flip_is_handled() {
        let sent = vec![
            read(Command::FPRD, 0x1001, 0x0130, 6),
            DatagramRepr::logical(Command::LRW, 0, 0x0001_0000, vec![1, 2, 3, 4]),
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
        let big = vec![read(Command::FPRD, 1, 0, 1500)];
        assert!(matches!(
            frame([0; 6], 0, &big),
            Err(BuildError::TooLong { .. })
        ));
        assert_eq!(Access::of(&big[0]).to_string(), "FPRD 0001h:0000h");
    }
}
