//! The EtherCAT frame: a 2-byte header and the datagrams (ETG.1000.4 "Frame structure" /
//! "EtherCAT frame"), carried in an Ethernet II frame of EtherType 88A4h
//! ([`crate::eth::ETHERTYPE_ECAT`]) or in a UDP datagram to port 88A4h ([`ECAT_UDP_PORT`]).
//!
//! | bits of the little-endian header word | field |
//! |---|---|
//! | 0–10 | length of the datagrams that follow (sum of their header, data and WKC) |
//! | 11 | reserved, 0 |
//! | 12–15 | type: 1 = EtherCAT DLPDU (commands), 4 = network variables, 5 = mailbox |
//!
//! A received Ethernet frame carries padding up to 60 bytes after the datagrams: the length
//! field, not the buffer, bounds them. [`EcatFrame::datagrams`] walks them checking every
//! length: a datagram that claims more bytes than the frame has is
//! [`Error::DatagramTruncated`] naming it.

use std::fmt;
use std::ops::Range;

use super::datagram::{Datagram, DatagramRepr, HEADER_LEN as DG_HEADER, WKC_LEN};
use super::wire::{fit, le16};
use crate::eth::{EthernetRepr, MacAddr, ETHERTYPE_ECAT};
use crate::wire::Error;

/// UDP port of EtherCAT frames over UDP (ETG.1000.4 "EtherCAT frame inside a UDP datagram":
/// 88A4h = 34980).
pub const ECAT_UDP_PORT: u16 = 0x88A4;
/// EtherCAT header length.
pub const HEADER_LEN: usize = 2;
/// The largest value of the 11-bit length field.
pub const MAX_LEN: usize = 0x07FF;
/// The largest EtherCAT payload a standard Ethernet frame carries (1500 − 2 header bytes).
pub const MAX_DATAGRAMS_LEN: usize = 1498;

/// The frame type of the EtherCAT header (ETG.1000.4 "EtherCAT frame"; open).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct FrameType(pub u8);

impl FrameType {
    /// EtherCAT DLPDU: datagrams (commands).
    pub const DLPDU: FrameType = FrameType(1);
    /// Network variables.
    pub const NETWORK_VARIABLES: FrameType = FrameType(4);
    /// Mailbox (gateway).
    pub const MAILBOX: FrameType = FrameType(5);

    /// The type's name, if defined.
    pub fn name(self) -> Option<&'static str> {
        Some(match self {
            FrameType::DLPDU => "EtherCAT commands",
            FrameType::NETWORK_VARIABLES => "network variables",
            FrameType::MAILBOX => "mailbox",
            _ => return None,
        })
    }
}

impl fmt::Debug for FrameType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.name() {
            Some(n) => write!(f, "FrameType({} {n})", self.0),
            None => write!(f, "FrameType({})", self.0),
        }
    }
}

impl fmt::Display for FrameType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.name() {
            Some(n) => f.write_str(n),
            None => write!(f, "frame type {}", self.0),
        }
    }
}

/// Checked view over an EtherCAT frame: the header, the datagrams, and whatever padding
/// follows them.
#[derive(Debug, Clone)]
pub struct EcatFrame<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> EcatFrame<T> {
    /// Wraps a buffer without checking; accessors panic if it is shorter than 2 bytes.
    pub fn new_unchecked(buffer: T) -> Self {
        EcatFrame { buffer }
    }

    /// Wraps a buffer after checking that it holds the header and as many bytes as the length
    /// field says. The datagrams are checked by [`EcatFrame::datagrams`] /
    /// [`EcatFrame::datagram_ranges`].
    pub fn new_checked(buffer: T) -> Result<Self, Error> {
        let f = EcatFrame { buffer };
        f.check_len()?;
        Ok(f)
    }

    /// Checks the header and its length field against the buffer.
    pub fn check_len(&self) -> Result<(), Error> {
        let got = self.buffer.as_ref().len();
        if got < HEADER_LEN {
            return Err(Error::Truncated {
                what: "EtherCAT header",
                need: HEADER_LEN,
                got,
            });
        }
        let len = self.len();
        if len > got - HEADER_LEN {
            return Err(Error::Length {
                field: "EtherCAT length",
                value: len,
                available: got - HEADER_LEN,
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

    /// The raw header word.
    pub fn header(&self) -> u16 {
        le16(self.b(), 0)
    }
    /// The 11-bit length of the datagrams.
    pub fn len(&self) -> usize {
        usize::from(self.header() & 0x07FF)
    }
    /// Whether the length field says 0.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// The reserved bit 11.
    pub fn reserved(&self) -> bool {
        self.header() & 0x0800 != 0
    }
    /// The frame type.
    pub fn frame_type(&self) -> FrameType {
        FrameType((self.header() >> 12) as u8)
    }
    /// The datagram bytes (as many as the length field says; padding excluded).
    pub fn payload(&self) -> &[u8] {
        let end = (HEADER_LEN + self.len()).min(self.b().len());
        &self.b()[HEADER_LEN..end]
    }
    /// Bytes after the datagrams (Ethernet padding).
    pub fn padding(&self) -> &[u8] {
        let at = (HEADER_LEN + self.len()).min(self.b().len());
        &self.b()[at..]
    }

    /// The datagrams, each length checked; the first malformed one ends the walk with its
    /// error. Does not look at the frame type: check [`EcatFrame::frame_type`] first.
    pub fn datagrams(&self) -> Datagrams<'_> {
        Datagrams {
            buf: self.b(),
            walk: Walk::new(self.b(), self.len()),
        }
    }

    /// Where each datagram lies in the buffer (offsets from the EtherCAT header), all checked
    /// before any is returned.
    pub fn datagram_ranges(&self) -> Result<Vec<Range<usize>>, Error> {
        let mut walk = Walk::new(self.b(), self.len());
        std::iter::from_fn(|| walk.step(self.b())).collect()
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> EcatFrame<T> {
    /// Sets the raw header word (negative tests: a lying length, a wrong type).
    pub fn set_header(&mut self, w: u16) {
        self.buffer.as_mut()[..2].copy_from_slice(&w.to_le_bytes());
    }
    /// Sets the 11-bit length.
    pub fn set_len(&mut self, len: u16) {
        let w = self.header() & !0x07FF | len & 0x07FF;
        self.set_header(w);
    }
    /// Sets the frame type.
    pub fn set_frame_type(&mut self, t: FrameType) {
        let w = self.header() & 0x0FFF | u16::from(t.0 & 0x0F) << 12;
        self.set_header(w);
    }

    /// Writable views of every datagram, for a slave that processes the frame in place. All
    /// lengths are checked first: on `Err` nothing was handed out.
    pub fn datagrams_mut(&mut self) -> Result<Vec<Datagram<&mut [u8]>>, Error> {
        let ranges = self.datagram_ranges()?;
        let mut out = Vec::with_capacity(ranges.len());
        let mut rest: &mut [u8] = self.buffer.as_mut();
        let mut consumed = 0;
        for r in ranges {
            let (_, tail) = rest.split_at_mut(r.start - consumed);
            let (this, tail) = tail.split_at_mut(r.len());
            consumed = r.end;
            rest = tail;
            out.push(Datagram::new_unchecked(this));
        }
        Ok(out)
    }
}

/// The datagram-by-datagram length check shared by [`Datagrams`] and
/// [`EcatFrame::datagram_ranges`].
#[derive(Debug, Clone)]
struct Walk {
    at: usize,
    end: usize,
    index: usize,
    done: bool,
}

impl Walk {
    fn new(buf: &[u8], len: usize) -> Walk {
        Walk {
            at: HEADER_LEN,
            end: (HEADER_LEN + len).min(buf.len()),
            index: 0,
            done: false,
        }
    }

    /// The next datagram's range in `buf`, or the error that ends the walk.
    fn step(&mut self, buf: &[u8]) -> Option<Result<Range<usize>, Error>> {
        if self.done {
            return None;
        }
        let left = self.end - self.at;
        if self.index == 0 && left == 0 {
            // An empty frame holds no datagram.
            self.done = true;
            return None;
        }
        let fail = |s: &mut Walk, need| {
            s.done = true;
            Some(Err(Error::DatagramTruncated {
                index: s.index,
                need,
                got: left,
            }))
        };
        if left < DG_HEADER + WKC_LEN {
            return fail(self, DG_HEADER + WKC_LEN);
        }
        let w = le16(buf, self.at + 6);
        let need = DG_HEADER + usize::from(w & 0x07FF) + WKC_LEN;
        if need > left {
            return fail(self, need);
        }
        let range = self.at..self.at + need;
        self.at += need;
        self.index += 1;
        if w & 0x8000 == 0 {
            self.done = true;
            if self.at != self.end {
                return Some(Err(Error::Trailing {
                    what: "EtherCAT frame after the last datagram",
                    extra: self.end - self.at,
                }));
            }
        }
        Some(Ok(range))
    }
}

/// Iterator over the datagrams of an [`EcatFrame`].
#[derive(Debug, Clone)]
pub struct Datagrams<'a> {
    buf: &'a [u8],
    walk: Walk,
}

impl<'a> Iterator for Datagrams<'a> {
    type Item = Result<Datagram<&'a [u8]>, Error>;

    fn next(&mut self) -> Option<Self::Item> {
        let r = self.walk.step(self.buf)?;
        Some(r.map(|r| Datagram::new_unchecked(&self.buf[r])))
    }
}

/// An EtherCAT frame of type 1: its datagrams.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Default)]
pub struct EcatFrameRepr {
    /// The datagrams, in order.
    pub datagrams: Vec<DatagramRepr>,
}

impl EcatFrameRepr {
    /// A frame of these datagrams.
    pub fn new(datagrams: Vec<DatagramRepr>) -> Self {
        EcatFrameRepr { datagrams }
    }

    /// Reads a frame of type 1 (padding after the datagrams is ignored).
    pub fn parse<T: AsRef<[u8]>>(f: &EcatFrame<T>) -> Result<EcatFrameRepr, Error> {
        f.check_len()?;
        if f.frame_type() != FrameType::DLPDU {
            return Err(Error::Unknown {
                field: "EtherCAT frame type",
                value: u32::from(f.frame_type().0),
            });
        }
        let datagrams = f
            .datagrams()
            .map(|d| d.and_then(|d| DatagramRepr::parse(&d)))
            .collect::<Result<_, _>>()?;
        Ok(EcatFrameRepr { datagrams })
    }

    /// Parses the EtherCAT part of an Ethernet payload.
    pub fn parse_bytes(bytes: &[u8]) -> Result<EcatFrameRepr, Error> {
        EcatFrameRepr::parse(&EcatFrame::new_checked(bytes)?)
    }

    /// Length of the datagrams (the header's length field).
    pub fn datagrams_len(&self) -> usize {
        self.datagrams.iter().map(DatagramRepr::buffer_len).sum()
    }

    /// Bytes of the EtherCAT frame: header and datagrams (no Ethernet padding).
    pub fn buffer_len(&self) -> usize {
        HEADER_LEN + self.datagrams_len()
    }

    /// The EtherCAT frame's bytes; the "more follows" bit is set on every datagram but the
    /// last, whatever the reprs say.
    pub fn emit(&self) -> Result<Vec<u8>, Error> {
        let len = fit("EtherCAT length", self.datagrams_len(), MAX_LEN)?;
        let mut out = vec![0; HEADER_LEN + len];
        out[..2].copy_from_slice(&(len as u16 | 0x1000).to_le_bytes());
        let mut at = HEADER_LEN;
        let last = self.datagrams.len().saturating_sub(1);
        for (i, d) in self.datagrams.iter().enumerate() {
            let n = d.buffer_len();
            let more = i != last;
            let d = DatagramRepr { more, ..d.clone() };
            d.emit_into(&mut out[at..at + n])?;
            at += n;
        }
        Ok(out)
    }

    /// The whole Ethernet frame: header (EtherType 88A4h), EtherCAT frame, padding to 60.
    pub fn emit_ethernet(&self, dst: MacAddr, src: MacAddr) -> Result<Vec<u8>, Error> {
        let payload = self.emit()?;
        Ok(EthernetRepr {
            dst,
            src,
            ethertype: ETHERTYPE_ECAT,
        }
        .emit(&payload))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ecat::datagram::Command;
    use crate::eth::EthernetFrame;

    /// A frame of two datagrams (a scan as masters send it), then 4 bytes of padding.
    const FRAME: [u8; 34] = [
        0x1C, 0x10, // length 28, type 1
        // datagram 0: BRD 0000h:0000h, 2 bytes, more follows
        0x07, 0x01, 0x00, 0x00, 0x00, 0x00, 0x02, 0x80, 0x00, 0x00, //
        0x11, 0x00, // data: ESC type 11h
        0x03, 0x00, // wkc 3
        // datagram 1: FPRD 1001h:0130h, 2 bytes, last
        0x04, 0x02, 0x01, 0x10, 0x30, 0x01, 0x02, 0x00, 0x00, 0x00, //
        0x02, 0x00, // data: PRE-OP
        0x01, 0x00, // wkc 1
        0x00, 0x00, 0x00, 0x00, // padding
    ];

    fn repr() -> EcatFrameRepr {
        EcatFrameRepr::new(vec![
            DatagramRepr {
                wkc: 3,
                more: true,
                ..DatagramRepr::physical(Command::BRD, 1, 0, 0, vec![0x11, 0])
            },
            DatagramRepr {
                wkc: 1,
                ..DatagramRepr::physical(Command::FPRD, 2, 0x1001, 0x0130, vec![2, 0])
            },
        ])
    }

    #[test]
    fn parses_and_round_trips() {
        let f = EcatFrame::new_checked(&FRAME[..]).unwrap();
        assert_eq!(
            (f.len(), f.frame_type(), f.reserved()),
            (28, FrameType::DLPDU, false)
        );
        assert_eq!(f.padding(), [0; 4]);
        let dgs: Vec<_> = f.datagrams().collect::<Result<_, _>>().unwrap();
        assert_eq!(dgs.len(), 2);
        assert_eq!((dgs[0].command(), dgs[0].wkc()), (Command::BRD, 3));
        assert_eq!((dgs[1].ado(), dgs[1].data()), (0x0130, &[2u8, 0][..]));
        let mut r = EcatFrameRepr::parse(&f).unwrap();
        assert!(r.datagrams[0].more && !r.datagrams[1].more);
        assert_eq!(r.emit().unwrap(), FRAME[..30]);
        // Emit sets the more bits itself.
        r.datagrams[0].more = false;
        r.datagrams[1].more = true;
        assert_eq!(r.emit().unwrap(), FRAME[..30]);
        assert_eq!(repr().emit().unwrap(), FRAME[..30]);
        assert_eq!(f.datagram_ranges().unwrap(), vec![2..16, 16..30]);
    }

    #[test]
    fn in_ethernet() {
        let e = repr()
            .emit_ethernet(MacAddr::BROADCAST, MacAddr([2, 0, 0, 0, 0, 1]))
            .unwrap();
        assert_eq!(e.len(), 60);
        let eth = EthernetFrame::new_checked(&e[..]).unwrap();
        assert_eq!(eth.ethertype(), 0x88A4);
        assert_eq!(EcatFrameRepr::parse_bytes(eth.payload()).unwrap(), repr());
    }

    #[test]
    fn truncation_at_every_length_is_an_error() {
        for n in 0..30 {
            assert!(EcatFrameRepr::parse_bytes(&FRAME[..n]).is_err(), "{n}");
        }
        assert_eq!(
            EcatFrameRepr::parse_bytes(&FRAME[..1]),
            Err(Error::Truncated {
                what: "EtherCAT header",
                need: 2,
                got: 1
            })
        );
        assert_eq!(
            EcatFrameRepr::parse_bytes(&FRAME[..29]),
            Err(Error::Length {
                field: "EtherCAT length",
                value: 28,
                available: 27
            })
        );
    }

    #[test]
    fn a_lying_datagram_length_names_the_datagram() {
        let mut b = FRAME;
        // Datagram 1 claims 20 data bytes: 32 bytes, 14 left.
        Datagram::new_unchecked(&mut b[16..30]).set_len(20);
        let f = EcatFrame::new_checked(&b[..]).unwrap();
        let all: Vec<_> = f.datagrams().collect();
        assert_eq!(all.len(), 2);
        assert!(all[0].is_ok());
        assert_eq!(
            all[1].as_ref().unwrap_err(),
            &Error::DatagramTruncated {
                index: 1,
                need: 32,
                got: 14
            }
        );
        assert!(f.datagram_ranges().is_err());
        let mut b2 = b;
        assert!(EcatFrame::new_checked(&mut b2[..])
            .unwrap()
            .datagrams_mut()
            .is_err());

        // The first datagram says "more" but the frame ends after the second.
        let mut b = FRAME;
        Datagram::new_unchecked(&mut b[16..30]).set_more(true);
        assert_eq!(
            EcatFrameRepr::parse_bytes(&b),
            Err(Error::DatagramTruncated {
                index: 2,
                need: 12,
                got: 0
            })
        );

        // The frame length covers the padding but the last datagram says "last".
        let mut b = FRAME;
        EcatFrame::new_unchecked(&mut b[..]).set_len(32);
        assert_eq!(
            EcatFrameRepr::parse_bytes(&b),
            Err(Error::Trailing {
                what: "EtherCAT frame after the last datagram",
                extra: 4
            })
        );

        // A frame length that ends inside a datagram header.
        let mut b = FRAME;
        EcatFrame::new_unchecked(&mut b[..]).set_len(20);
        assert_eq!(
            EcatFrameRepr::parse_bytes(&b),
            Err(Error::DatagramTruncated {
                index: 1,
                need: 12,
                got: 6
            })
        );
    }

    #[test]
    fn other_types_and_empty_frames() {
        let mut b = FRAME;
        EcatFrame::new_unchecked(&mut b[..]).set_frame_type(FrameType::MAILBOX);
        assert_eq!(
            EcatFrameRepr::parse_bytes(&b),
            Err(Error::Unknown {
                field: "EtherCAT frame type",
                value: 5
            })
        );
        let empty = [0x00, 0x10];
        assert_eq!(
            EcatFrameRepr::parse_bytes(&empty).unwrap().datagrams.len(),
            0
        );
        assert_eq!(EcatFrameRepr::default().emit().unwrap(), empty);
        assert_eq!(FrameType(9).to_string(), "frame type 9");
    }

    #[test]
    fn processes_in_place() {
        let mut b = FRAME;
        let mut f = EcatFrame::new_checked(&mut b[..]).unwrap();
        for mut d in f.datagrams_mut().unwrap() {
            d.add_wkc(1);
        }
        assert_eq!((b[14], b[28]), (4, 2));
    }

    #[test]
    fn too_big_to_emit() {
        let r = EcatFrameRepr::new(vec![
            DatagramRepr::logical(Command::LRD, 0, 0, vec![0; 1500]),
            DatagramRepr::logical(Command::LRD, 0, 0, vec![0; 600]),
        ]);
        assert!(matches!(r.emit(), Err(Error::TooLong { max: 2047, .. })));
    }

    mod properties {
        use super::*;
        use crate::ecat::datagram::Command;
        use proptest::collection::vec;
        use proptest::prelude::*;

        fn datagram() -> impl Strategy<Value = DatagramRepr> {
            (
                any::<(u8, u8, u32, bool, u16, u16)>(),
                vec(any::<u8>(), 0..=64),
            )
                .prop_map(
                    |((command, index, address, circulating, irq, wkc), data)| DatagramRepr {
                        command: Command(command),
                        index,
                        address,
                        circulating,
                        more: false,
                        irq,
                        data,
                        wkc,
                    },
                )
        }

        /// A frame as emitted: "more follows" on every datagram but the last.
        fn frame() -> impl Strategy<Value = EcatFrameRepr> {
            vec(datagram(), 0..5).prop_map(|mut ds| {
                let last = ds.len().saturating_sub(1);
                for (i, d) in ds.iter_mut().enumerate() {
                    d.more = i != last;
                }
                EcatFrameRepr::new(ds)
            })
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn emit_then_parse_round_trips(f in frame(), padding in 0usize..16) {
                let mut b = f.emit().unwrap();
                prop_assert_eq!(b.len(), f.buffer_len());
                prop_assert_eq!(EcatFrameRepr::parse_bytes(&b), Ok(f.clone()));
                b.resize(b.len() + padding, 0);
                prop_assert_eq!(EcatFrameRepr::parse_bytes(&b), Ok(f));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(mut bytes in vec(any::<u8>(), 0..48)) {
                let _ = EcatFrameRepr::parse_bytes(&bytes);
                if let Ok(mut f) = EcatFrame::new_checked(&mut bytes[..]) {
                    let _ = f.datagram_ranges();
                    let _ = f.datagrams().count();
                    let _ = (f.payload().len(), f.padding().len());
                    if let Ok(ds) = f.datagrams_mut() {
                        for mut d in ds {
                            let _ = d.data_mut().len();
                        }
                    }
                }
            }
        }
    }
}
