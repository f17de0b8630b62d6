//! Packet capture of a run, written as a pcapng file; the same for every bus.
//!
//! A [`Capture`] holds whole Ethernet frames, each with its time on the run's time line and a
//! comment. Buses put their traffic in as they have it: a bus on raw Ethernet (EtherCAT) its
//! frames as they are ([`Capture::frame`]); a bus whose links carry application payloads only
//! (EtherNet/IP's TCP stream bytes and UDP datagrams) frames them first
//! (`crate::enip::pcap` synthesizes Ethernet, IPv4 and TCP/UDP around them), keeping what that
//! framing needs between packets in the capture ([`Capture::with_state`]).
//!
//! Each packet carries a comment (pcapng `opt_comment`, Wireshark's `frame.comment`) naming what
//! produced it: the runner labels the tap with the profile, the case and the step before each
//! step (see [`Tap::label`]), so an engineer opening the file sees which case each frame belongs
//! to, and a test can tell the frames a step broke on purpose from the others.
//!
//! The file has an Ethernet interface whose description lists the kinds of traffic in it
//! ([`Capture::source`]), and, when the run put frames on the NORD system bus, a second
//! interface of link type `LINKTYPE_CAN_SOCKETCAN` with those ([`Capture::can`]). Nothing in the file depends on the wall clock or on the order of a
//! hash map, so a capture of the same embedded run is byte-for-byte the same.

use std::any::Any;
use std::fmt;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;
use std::rc::Rc;
use std::time::Duration;

use pcap_file::pcapng::blocks::enhanced_packet::{EnhancedPacketBlock, EnhancedPacketOption};
use pcap_file::pcapng::blocks::interface_description::{
    InterfaceDescriptionBlock, InterfaceDescriptionOption,
};
use pcap_file::pcapng::blocks::section_header::{SectionHeaderBlock, SectionHeaderOption};
use pcap_file::pcapng::PcapNgWriter;
use pcap_file::{DataLink, Endianness, PcapError};

/// The capture's epoch: 2026-11-23T00:00:00Z, in seconds since the Unix epoch. Every `at` is
/// an offset from it.
pub(crate) const EPOCH_SECS: u64 = 1_795_392_000;
/// The interface's snapshot length: larger than any frame a bus captures.
pub(crate) const SNAPLEN: u32 = 262_144;
/// The interface's timestamp resolution (`if_tsresol`): 10^-9 s, the unit pcap-file writes
/// Enhanced Packet Block timestamps in.
pub(crate) const TSRESOL_NANOS: u8 = 9;
/// Longest packet comment, in bytes (an option's length is 16 bits); a longer one is cut at a
/// character boundary and ends in `…`.
pub(crate) const MAX_COMMENT: usize = 4096;
/// The interface description of a capture no bus named itself in.
const NO_SOURCE: &str = "Traffic of a harness run";
/// The description of the system-bus interface.
const CAN_SOURCE: &str = "NORD system bus (CAN 2.0A, CANopen) of a harness run";

/// The interface a packet was captured on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Interface {
    /// Ethernet II frames (interface 0).
    Ethernet,
    /// `struct can_frame` records of the system bus ([`CAN_SOURCE`], after the Ethernet one).
    Can,
}

/// One captured frame.
#[derive(Debug)]
pub(crate) struct Packet {
    /// Time since [`EPOCH_SECS`].
    pub(crate) at: Duration,
    /// Ethernet II onwards, or a CAN frame's capture record.
    pub(crate) frame: Vec<u8>,
    /// What produced it (the capture's label when it was captured).
    pub(crate) comment: Option<Rc<str>>,
    /// Where it was captured.
    pub(crate) interface: Interface,
}

/// A capture: packets collected in memory, written out with [`Capture::write`].
#[derive(Default)]
pub(crate) struct Capture {
    /// The frames, in capture order.
    packets: Vec<Packet>,
    /// The comment of the packets captured from now on.
    label: Option<Rc<str>>,
    /// The kinds of traffic in the capture, in order of first mention.
    sources: Vec<&'static str>,
    /// What the buses keep between packets, one value per type ([`Capture::with_state`]).
    state: Vec<Box<dyn Any>>,
}

impl fmt::Debug for Capture {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Capture")
            .field("packets", &self.packets.len())
            .field("label", &self.label)
            .field("sources", &self.sources)
            .finish_non_exhaustive()
    }
}

impl Capture {
    /// A whole Ethernet frame (destination MAC onwards, without the frame check sequence),
    /// captured as it is at `at`, with the current label as its comment.
    pub(crate) fn frame(&mut self, frame: &[u8], at: Duration) {
        self.push(frame.to_vec(), at);
    }

    /// [`Capture::frame`] of a frame the caller built and hands over.
    pub(crate) fn push(&mut self, frame: Vec<u8>, at: Duration) {
        self.packets.push(Packet {
            at,
            frame,
            comment: self.label.clone(),
            interface: Interface::Ethernet,
        });
    }

    /// A frame of the NORD system bus, or an error frame its controller reported, captured at
    /// `at` on the capture's CAN interface, with the current label as its comment.
    pub(crate) fn can(&mut self, frame: &proto::can::socketcan::SocketCanRepr, at: Duration) {
        let record = frame.to_pcap_record();
        self.packets.push(Packet {
            at,
            frame: record.to_vec(),
            comment: self.label.clone(),
            interface: Interface::Can,
        });
    }

    /// Names a kind of traffic in the capture (`EtherNet/IP traffic of a harness run …`): the
    /// interface's description lists each kind once, in the order first named. A bus names
    /// its own as it captures.
    pub(crate) fn source(&mut self, what: &'static str) {
        if !self.sources.contains(&what) {
            self.sources.push(what);
        }
    }

    /// Runs `f` with the value of type `S` this capture keeps for a bus (made with
    /// `S::default()` on first use): what a bus's framing needs from one packet to the next,
    /// such as the sequence numbers of synthesized TCP connections. `f` gets the capture
    /// too, to add packets; within `f` the capture's own `S` is out (a nested call with the
    /// same type starts from a default one, which is then lost).
    pub(crate) fn with_state<S: Default + 'static, R>(
        &mut self,
        f: impl FnOnce(&mut S, &mut Capture) -> R,
    ) -> R {
        let mut state: Box<S> = match self.state.iter().position(|s| s.is::<S>()) {
            Some(i) => self.state.swap_remove(i).downcast().unwrap_or_default(),
            None => Box::default(),
        };
        let r = f(&mut state, self);
        self.state.push(state);
        r
    }

    /// Names what the packets captured from now on belong to: each one's comment in the file.
    /// `None`: no comment.
    pub(crate) fn label(&mut self, label: Option<&str>) {
        self.label = label.map(|l| Rc::from(truncate(l, MAX_COMMENT)));
    }

    /// The packets captured so far, in order.
    #[allow(dead_code)]
    pub(crate) fn packets(&self) -> &[Packet] {
        &self.packets
    }

    /// Number of packets captured so far.
    pub(crate) fn len(&self) -> usize {
        self.packets.len()
    }

    /// Whether no packet has been captured.
    #[allow(dead_code)]
    pub(crate) fn is_empty(&self) -> bool {
        self.packets.is_empty()
    }

    /// Writes the capture to `path` as pcapng (little endian): a section header naming the
    /// harness, an Ethernet interface with nanosecond timestamps (and a CAN one after it when
    /// there are system-bus frames), and an Enhanced Packet Block
    /// per packet, stamped 2026-11-23T00:00:00Z plus its `at`, with its comment.
    pub(crate) fn write(&self, path: &Path) -> std::io::Result<()> {
        let file = BufWriter::new(File::create(path)?);
        self.write_to(file)?.flush()
    }

    /// Writes the capture as pcapng to `out`; returns it.
    pub(crate) fn write_to<W: Write>(&self, out: W) -> std::io::Result<W> {
        let section = SectionHeaderBlock {
            endianness: Endianness::Little,
            major_version: 1,
            minor_version: 0,
            section_length: -1,
            options: vec![SectionHeaderOption::UserApplication(
                concat!("nord-harness ", env!("CARGO_PKG_VERSION")).into(),
            )],
        };
        let mut writer = PcapNgWriter::with_section_header(out, section).map_err(io_error)?;
        let description = match self.sources.is_empty() {
            true => NO_SOURCE.to_string(),
            false => self.sources.join("; "),
        };
        let interface = |linktype, description: String| InterfaceDescriptionBlock {
            linktype,
            snaplen: SNAPLEN,
            options: vec![
                InterfaceDescriptionOption::IfDescription(description.into()),
                InterfaceDescriptionOption::IfTsResol(TSRESOL_NANOS),
            ],
        };
        writer
            .write_pcapng_block(interface(DataLink::ETHERNET, description))
            .map_err(io_error)?;
        if self.packets.iter().any(|p| p.interface == Interface::Can) {
            writer
                .write_pcapng_block(interface(DataLink::CAN_SOCKETCAN, CAN_SOURCE.into()))
                .map_err(io_error)?;
        }
        for p in &self.packets {
            let block = EnhancedPacketBlock {
                interface_id: match p.interface {
                    Interface::Ethernet => 0,
                    Interface::Can => 1,
                },
                timestamp: Duration::from_secs(EPOCH_SECS) + p.at,
                original_len: p.frame.len() as u32,
                data: p.frame.as_slice().into(),
                options: p
                    .comment
                    .iter()
                    .map(|c| EnhancedPacketOption::Comment(c.as_ref().into()))
                    .collect(),
            };
            writer.write_pcapng_block(block).map_err(io_error)?;
        }
        Ok(writer.into_inner())
    }
}

/// `text` cut to at most `max` bytes at a character boundary, ending in `…` if cut.
fn truncate(text: &str, max: usize) -> std::borrow::Cow<'_, str> {
    if text.len() <= max {
        return text.into();
    }
    let mut end = max - '…'.len_utf8();
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    format!("{}…", &text[..end]).into()
}

/// A pcap-file error as an I/O error.
fn io_error(e: PcapError) -> std::io::Error {
    match e {
        PcapError::IoError(e) => e,
        other => std::io::Error::new(std::io::ErrorKind::InvalidData, other),
    }
}

/// A capture shared by every link of a run, with the run's own time line: each embedded case
/// starts on a fresh virtual clock, so its times are placed after the last packet so far.
#[derive(Debug, Default)]
pub(crate) struct Tap {
    /// The packets.
    pub(crate) capture: Capture,
    /// The latest time used.
    pub(crate) last: Duration,
}

impl Tap {
    /// Names what the packets captured from now on belong to, e.g. `tu4-eip@enip
    /// cip/encapsulation/short-header step 2: enip raw 6F 00 …`: each one's comment in the
    /// file. The runner calls it before each step.
    pub(crate) fn label(&mut self, label: &str) {
        self.capture.label(Some(label));
    }
}

/// The run's tap, shared by the links.
pub(crate) type SharedTap = std::rc::Rc<std::cell::RefCell<Tap>>;

/// A link's place on the run's capture time line: what it records goes in at the link's own
/// time (virtual on an embedded link), placed after the last packet so far, under `source`.
#[derive(Debug)]
pub(crate) struct Stamper {
    tap: SharedTap,
    base: Duration,
}

impl Stamper {
    /// Records for a link whose clock reads `now`, naming its traffic `source`.
    pub(crate) fn new(tap: SharedTap, source: &'static str, now: Duration) -> Stamper {
        tap.borrow_mut().capture.source(source);
        Stamper::on(tap, now)
    }

    /// Records for a link whose clock reads `now` and whose traffic goes to an interface that
    /// names itself (the system bus's).
    pub(crate) fn on(tap: SharedTap, now: Duration) -> Stamper {
        let base = tap.borrow().last + Duration::from_millis(1);
        Stamper {
            tap,
            base: base.saturating_sub(now),
        }
    }

    /// Adds packets at the link's time `now` (`add` gets the capture and the time).
    pub(crate) fn record(&self, now: Duration, add: impl FnOnce(&mut Capture, Duration)) {
        let at = self.base + now;
        let mut t = self.tap.borrow_mut();
        t.last = t.last.max(at);
        add(&mut t.capture, at);
    }
}

/// Reading captures back, for the tests of this module and of the buses' framing.
#[cfg(test)]
pub(crate) mod testing {
    use super::*;

    /// Every block of a pcapng file: the section header, the interfaces, and per packet its
    /// timestamp, bytes and comments.
    #[allow(clippy::type_complexity)]
    pub(crate) fn read_pcapng(
        bytes: &[u8],
    ) -> (
        SectionHeaderBlock<'static>,
        Vec<InterfaceDescriptionBlock<'static>>,
        Vec<(Duration, Vec<u8>, Vec<String>)>,
    ) {
        let mut reader = pcap_file::pcapng::PcapNgReader::new(bytes).unwrap();
        let mut packets = Vec::new();
        while let Some(block) = reader.next_block() {
            let block = block.unwrap();
            if let Some(epb) = block.into_enhanced_packet() {
                assert_eq!(epb.original_len as usize, epb.data.len());
                let comments = epb
                    .options
                    .iter()
                    .map(|o| match o {
                        EnhancedPacketOption::Comment(c) => c.to_string(),
                        other => panic!("unexpected option {other:?}"),
                    })
                    .collect();
                packets.push((epb.timestamp, epb.data.into_owned(), comments));
            }
        }
        (
            reader.section().clone(),
            reader.interfaces().to_vec(),
            packets,
        )
    }

    /// The interface's description (`if_description`).
    pub(crate) fn description(interface: &InterfaceDescriptionBlock<'_>) -> Option<String> {
        interface.options.iter().find_map(|o| match o {
            InterfaceDescriptionOption::IfDescription(d) => Some(d.to_string()),
            _ => None,
        })
    }

    /// A fresh directory under the target's temporary directory.
    pub(crate) fn tempdir(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("harness-pcap-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }
}

#[cfg(test)]
mod tests {
    use super::testing::{description, read_pcapng, tempdir};
    use super::*;
    use proto::can::socketcan::{ErrorClass, ErrorFrame, SocketCanRepr};

    fn ms(n: u64) -> Duration {
        Duration::from_millis(n)
    }

    /// An EtherCAT frame as a master sends it: broadcast destination, a locally administered
    /// source, EtherType 88A4h, frame header (length 0Eh, type 1), one BRD of the ESC type
    /// register 0000h, 2 bytes, working counter 0.
    fn ecat_frame(index: u8) -> Vec<u8> {
        let mut f = vec![0xFF; 6]; // destination: broadcast
        f.extend([0x02, 0, 0, 0, 0, 0x01]); // source
        f.extend([0x88, 0xA4]); // EtherType EtherCAT
        f.extend([0x0E, 0x10]); // length 14, type 1 (DLPDU)
        f.extend([0x07, index, 0, 0, 0, 0]); // BRD, index, ADP 0, ADO 0000h
        f.extend([0x02, 0x00, 0, 0]); // 2 bytes, last datagram, IRQ 0
        f.extend([0, 0, 0, 0]); // data, working counter
        f
    }

    #[test]
    fn system_bus_frames_go_to_a_can_interface_of_their_own() {
        let mut c = Capture::default();
        c.frame(&ecat_frame(1), ms(1));
        c.label(Some("sk550p@can step 1"));
        let sdo = proto::can::CanFrame::new(0x624, &[0x40, 0x66, 0x20, 0x01, 0, 0, 0, 0]).unwrap();
        c.can(&SocketCanRepr::Frame(sdo), ms(2));
        let bytes = c.write_to(Vec::new()).unwrap();
        let (_, interfaces, packets) = read_pcapng(&bytes);
        let types: Vec<DataLink> = interfaces.iter().map(|i| i.linktype).collect();
        assert_eq!(types, [DataLink::ETHERNET, DataLink::CAN_SOCKETCAN]);
        assert_eq!(description(&interfaces[1]).as_deref(), Some(CAN_SOURCE));
        let (_, record, comments) = &packets[1];
        assert_eq!(
            record[..5],
            [0, 0, 0x06, 0x24, 8],
            "identifier big-endian, then len"
        );
        assert_eq!(record[8..], [0x40, 0x66, 0x20, 0x01, 0, 0, 0, 0]);
        assert_eq!(comments, &["sk550p@can step 1"]);
        // An error frame a controller reported: CAN_ERR_FLAG and its class in the identifier.
        let error = ErrorFrame {
            class: ErrorClass(0x088),
            data: [0, 0, 0x08, 0, 0, 0, 0x08, 0],
        };
        let mut c = Capture::default();
        c.can(&SocketCanRepr::Error(error), ms(3));
        let (_, _, packets) = read_pcapng(&c.write_to(Vec::new()).unwrap());
        let (_, record, _) = &packets[0];
        assert_eq!(record[..5], [0x20, 0, 0, 0x88, 8], "CAN_ERR_FLAG | 088h");
        assert_eq!(record[8..], error.data);
        let mut ethernet_only = Capture::default();
        ethernet_only.frame(&ecat_frame(1), ms(1));
        let (_, interfaces, _) = read_pcapng(&ethernet_only.write_to(Vec::new()).unwrap());
        assert_eq!(
            interfaces.len(),
            1,
            "no CAN interface without system-bus frames"
        );
    }

    #[test]
    fn a_frame_is_captured_as_it_is() {
        let mut cap = Capture::default();
        assert!(cap.is_empty());
        cap.frame(&ecat_frame(1), ms(1));
        cap.push(ecat_frame(2), ms(2));
        assert_eq!(cap.len(), 2);
        assert_eq!(cap.packets()[0].frame, ecat_frame(1));
        assert_eq!(cap.packets()[1].frame, ecat_frame(2));
        assert_eq!(cap.packets()[1].at, ms(2));
    }

    #[test]
    fn write_reads_back() {
        let mut cap = Capture::default();
        cap.frame(&ecat_frame(1), ms(0));
        cap.frame(&ecat_frame(2), Duration::from_micros(1_500_250));
        cap.frame(&ecat_frame(3), Duration::from_nanos(2_000_000_007));
        let dir = tempdir("write_reads_back");
        let path = dir.join("run.pcapng");
        cap.write(&path).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        // Section Header Block, little endian: block type 0A0D0D0Ah, byte-order magic.
        assert_eq!(&bytes[0..4], &[0x0A, 0x0D, 0x0D, 0x0A]);
        assert_eq!(&bytes[8..12], &[0x4D, 0x3C, 0x2B, 0x1A]);

        let (section, interfaces, read) = read_pcapng(&bytes);
        assert_eq!(section.endianness, Endianness::Little);
        assert!(section.options.iter().any(|o| matches!(
            o,
            SectionHeaderOption::UserApplication(a) if a.starts_with("nord-harness ")
        )));
        assert_eq!(interfaces.len(), 1);
        assert_eq!(interfaces[0].linktype, DataLink::ETHERNET);
        assert_eq!(interfaces[0].snaplen, SNAPLEN);
        // pcap-file writes nanoseconds; the interface must say so, or readers take them as µs.
        assert!(interfaces[0]
            .options
            .contains(&InterfaceDescriptionOption::IfTsResol(TSRESOL_NANOS)));
        assert_eq!(description(&interfaces[0]).as_deref(), Some(NO_SOURCE));
        assert_eq!(read.len(), cap.len());
        for ((ts, data, comments), p) in read.iter().zip(cap.packets()) {
            assert_eq!(*ts, Duration::from_secs(EPOCH_SECS) + p.at);
            assert_eq!(data, &p.frame);
            assert!(comments.is_empty(), "no label, no comment: {comments:?}");
        }
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn each_packet_carries_the_label_it_was_captured_under() {
        let mut cap = Capture::default();
        cap.frame(&ecat_frame(1), ms(0)); // no label
        let step1 = "sk550p@ecat ecat/al/init-to-op step 1: ecat state pre-op";
        cap.label(Some(step1));
        cap.frame(&ecat_frame(2), ms(1));
        cap.frame(&ecat_frame(3), ms(2));
        let step2 = "sk550p@ecat ecat/al/init-to-op step 2: ecat state op · ü ✓";
        cap.label(Some(step2));
        cap.frame(&ecat_frame(4), ms(3));
        cap.label(None);
        cap.frame(&ecat_frame(5), ms(4)); // no label again

        let mut bytes = Vec::new();
        cap.write_to(&mut bytes).unwrap();
        let (_, _, read) = read_pcapng(&bytes);
        let comments: Vec<Option<&str>> = read
            .iter()
            .map(|(_, _, c)| {
                assert!(c.len() <= 1, "one comment per packet: {c:?}");
                c.first().map(String::as_str)
            })
            .collect();
        assert_eq!(
            comments,
            vec![None, Some(step1), Some(step1), Some(step2), None]
        );
        // Labels are shared, not copied per packet.
        assert!(Rc::ptr_eq(
            cap.packets()[1].comment.as_ref().unwrap(),
            cap.packets()[2].comment.as_ref().unwrap()
        ));

        // The same capture writes the same bytes.
        let mut again = Vec::new();
        cap.write_to(&mut again).unwrap();
        assert!(again == bytes);
    }

    #[test]
    fn a_long_label_is_cut_at_a_character_boundary() {
        assert_eq!(truncate("short", 10), "short");
        assert_eq!(truncate("0123456789", 10), "0123456789");
        // '…' is 3 bytes: 7 bytes of text remain, and 'é' (2 bytes at 6..8) does not fit.
        assert_eq!(truncate("abcdeféghij", 10), "abcdef…");
        let long = "enip raw ".to_string() + &"6F ".repeat(5000);
        let mut cap = Capture::default();
        cap.label(Some(&long));
        cap.frame(&ecat_frame(1), ms(0));
        let comment = cap.packets()[0].comment.as_deref().unwrap();
        assert!(comment.len() <= MAX_COMMENT, "{}", comment.len());
        assert!(comment.starts_with("enip raw 6F 6F") && comment.ends_with('…'));
        let mut bytes = Vec::new();
        cap.write_to(&mut bytes).unwrap();
        assert_eq!(read_pcapng(&bytes).2[0].2, [comment]);
    }

    #[test]
    fn the_interface_description_lists_each_source_once_in_order() {
        let mut cap = Capture::default();
        cap.source("EtherCAT frames as sent and received");
        cap.source("EtherNet/IP traffic");
        cap.source("EtherCAT frames as sent and received");
        let mut bytes = Vec::new();
        cap.write_to(&mut bytes).unwrap();
        let (_, interfaces, _) = read_pcapng(&bytes);
        assert_eq!(
            description(&interfaces[0]).as_deref(),
            Some("EtherCAT frames as sent and received; EtherNet/IP traffic")
        );
    }

    #[test]
    fn each_state_type_is_kept_between_calls() {
        #[derive(Default)]
        struct Counter(u32);
        #[derive(Default)]
        struct Other(&'static str);
        let mut cap = Capture::default();
        let bump = |cap: &mut Capture| {
            cap.with_state(|c: &mut Counter, cap| {
                c.0 += 1;
                cap.frame(&ecat_frame(c.0 as u8), ms(u64::from(c.0)));
                c.0
            })
        };
        assert_eq!(bump(&mut cap), 1);
        cap.with_state(|o: &mut Other, _| o.0 = "kept");
        assert_eq!(bump(&mut cap), 2);
        assert_eq!(cap.with_state(|o: &mut Other, _| o.0), "kept");
        assert_eq!(bump(&mut cap), 3);
        assert_eq!(cap.len(), 3);
        assert_eq!(cap.packets()[2].frame, ecat_frame(3));
    }
}
