//! Seeds the fuzz corpus from what a run exchanged and from the suites:
//!
//! ```text
//! cargo run --release -p fuzz --bin seed -- CAPTURES_DIR SUITES_DIR DESCRIPTIONS_DIR OUT_DIR
//! ```
//!
//! `CAPTURES_DIR` holds the pcapng files of a default run (`harness run -q --out DIR`). Each
//! frame's payload seeds the codec target of its protocol (EtherCAT, POWERLINK, PROFINET, LLDP
//! by EtherType; RPC, POWERLINK SDO and EtherNet/IP by UDP or TCP port; CAN frames and their
//! data), and each case's traffic (the capture comments name the case) becomes one session of
//! each device target it reached: the frames and datagrams to the device with the time
//! between them. Every suite and inventory file seeds `suite`, every file in
//! `DESCRIPTIONS_DIR` `description`. Files are named by their content's hash, so running it
//! twice adds nothing; `-merge=1` (`cargo xtask fuzz --merge`) then keeps the files that add
//! coverage.

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use fuzz::session::{encode, Step};
use pcap_file::pcapng::{Block, PcapNgReader};
use pcap_file::DataLink;
use proto::enip::io::{IoFrame, ENCAP_PORT, IO_PORT};
use proto::eth::{
    EthernetFrame, ETHERTYPE_ECAT, ETHERTYPE_IPV4, ETHERTYPE_LLDP, ETHERTYPE_POWERLINK,
    ETHERTYPE_PROFINET,
};
use proto::pnio::RPC_PORT;

/// A session seed is cut after this many bytes (libFuzzer's inputs stay small and fast).
const SESSION_BYTES: usize = 2 * 1024;

/// The time between two steps of a session is cut at this (the run's pauses between cases
/// add no coverage, only wall time).
const GAP: Duration = Duration::from_secs(3);

/// One packet of a capture.
struct Packet {
    can: bool,
    at: Duration,
    case: String,
    data: Vec<u8>,
}

fn packets(file: &Path) -> Result<Vec<Packet>, String> {
    let bytes = fs::read(file).map_err(|e| format!("{}: {e}", file.display()))?;
    let mut reader =
        PcapNgReader::new(bytes.as_slice()).map_err(|e| format!("{}: {e}", file.display()))?;
    let mut links = Vec::new();
    let mut out = Vec::new();
    while let Some(block) = reader.next_block() {
        match block.map_err(|e| format!("{}: {e}", file.display()))? {
            Block::InterfaceDescription(i) => links.push(i.linktype),
            Block::EnhancedPacket(p) => {
                // The comment is "profile case step N: what": the case is what is before
                // " step ".
                let comment = p.options.iter().find_map(|o| match o {
                    pcap_file::pcapng::blocks::enhanced_packet::EnhancedPacketOption::Comment(
                        c,
                    ) => Some(c.to_string()),
                    _ => None,
                });
                let case = comment
                    .as_deref()
                    .map(|c| {
                        c.split_once(" step ")
                            .map_or(c, |(case, _)| case)
                            .to_string()
                    })
                    .unwrap_or_default();
                let can = links.get(p.interface_id as usize) == Some(&DataLink::CAN_SOCKETCAN);
                out.push(Packet {
                    can,
                    at: p.timestamp,
                    case,
                    data: p.data.to_vec(),
                });
            }
            _ => {}
        }
    }
    Ok(out)
}

/// The UDP or TCP payload of an IPv4 packet: (is UDP, source port, destination port, payload).
fn transport(ip: &[u8]) -> Option<(bool, u16, u16, &[u8])> {
    let ihl = usize::from(ip.first()? & 0x0F) * 4;
    let total = usize::from(u16::from_be_bytes([*ip.get(2)?, *ip.get(3)?]));
    let proto = *ip.get(9)?;
    let seg = ip.get(ihl..total.min(ip.len()))?;
    let port = |at: usize| Some(u16::from_be_bytes([*seg.get(at)?, *seg.get(at + 1)?]));
    match proto {
        17 => Some((true, port(0)?, port(2)?, seg.get(8..)?)),
        6 => {
            let off = usize::from(seg.get(12)? >> 4) * 4;
            Some((false, port(0)?, port(2)?, seg.get(off..)?))
        }
        _ => None,
    }
}

/// Codec seeds kept of each case for each target: a run repeats the same telegrams with
/// other values many times, and the merge keeps only what adds coverage anyway.
const PER_CASE: usize = 4;

/// What the seeds are being gathered into: target → seeds, each once.
#[derive(Default)]
struct Seeds {
    seeds: BTreeMap<&'static str, BTreeSet<Vec<u8>>>,
    /// The case the packets now read belong to.
    case: String,
    /// (target, case) → seeds kept.
    kept: BTreeMap<(&'static str, String), usize>,
}

impl Seeds {
    fn add(&mut self, target: &'static str, bytes: &[u8]) {
        let kept = self.kept.entry((target, self.case.clone())).or_default();
        if *kept < PER_CASE && self.seeds.entry(target).or_default().insert(bytes.to_vec()) {
            *kept += 1;
        }
    }

    /// The codec seeds of one Ethernet frame, and the session step it is for a device.
    fn ethernet<'a>(&mut self, frame: &'a [u8]) -> Option<(&'static str, Step<'a>)> {
        let eth = EthernetFrame::new_checked(frame).ok()?;
        let payload = eth.inner_payload();
        let device = match eth.inner_ethertype() {
            ETHERTYPE_ECAT => {
                self.add("ecat", frame);
                self.add("ecat", payload);
                ("device_ecat", Step::Frame(frame))
            }
            ETHERTYPE_POWERLINK => {
                self.add("epl", payload);
                ("device_epl", Step::Frame(frame))
            }
            ETHERTYPE_PROFINET => {
                self.add("pnio", payload);
                ("device_pnio", Step::Frame(frame))
            }
            ETHERTYPE_LLDP => {
                self.add("lldp", payload);
                return None;
            }
            ETHERTYPE_IPV4 => {
                let ip_at = frame.len() - payload.len();
                let (udp, src, dst, data) = transport(&frame[ip_at..])?;
                let port = |p: u16| src == p || dst == p;
                if data.is_empty() {
                    return None;
                }
                if port(RPC_PORT) {
                    self.add("pnio_rpc", data);
                    ("device_pnio", Step::Datagram(0, data))
                } else if port(proto::epl::SDO_UDP_PORT) {
                    self.add("epl", data);
                    ("device_epl", Step::Datagram(0, data))
                } else if port(IO_PORT) {
                    self.add("enip", data);
                    for run_idle in [false, true] {
                        if let Ok(io) = IoFrame::parse(data, run_idle) {
                            self.add("nord", &io.data);
                        }
                    }
                    ("device_enip", Step::Datagram(1, data))
                } else if port(ENCAP_PORT) {
                    self.add("enip", data);
                    match udp {
                        true => ("device_enip", Step::Datagram(0, data)),
                        false => ("device_enip", Step::Stream(0, data)),
                    }
                } else {
                    return None;
                }
            }
            _ => return None,
        };
        Some(device)
    }
}

/// A CAN frame of the capture (LINKTYPE_CAN_SOCKETCAN: 32-bit id in network order, length,
/// 3 bytes, data) as a device session's frame: 11-bit id little-endian, then the data.
fn can_step(frame: &[u8]) -> Option<Vec<u8>> {
    let id = u32::from_be_bytes(frame.get(..4)?.try_into().ok()?) & 0x7FF;
    let len = usize::from(*frame.get(4)?).min(8);
    let data = frame.get(8..8 + len)?;
    Some([&(id as u16).to_le_bytes()[..], data].concat())
}

fn captures(dir: &Path, seeds: &mut Seeds) -> Result<(), String> {
    let mut files: Vec<PathBuf> = walk(dir)?
        .into_iter()
        .filter(|f| f.extension().is_some_and(|e| e == "pcapng" || e == "pcap"))
        .collect();
    files.sort();
    for file in files {
        let packets = packets(&file)?;
        // device target → case → (time of the last step, steps' bytes)
        let mut sessions: BTreeMap<(&'static str, String), (Duration, Vec<u8>)> = BTreeMap::new();
        for p in &packets {
            seeds.case.clone_from(&p.case);
            let can_bytes;
            let (device, step) = if p.can {
                seeds.add("can", &p.data);
                let Some(bytes) = can_step(&p.data) else {
                    continue;
                };
                seeds.add("canopen", &bytes[2..]);
                can_bytes = bytes;
                ("device_can", Step::Frame(&can_bytes))
            } else {
                match seeds.ethernet(&p.data) {
                    Some(d) => d,
                    None => continue,
                }
            };
            let (last, bytes) = sessions
                .entry((device, p.case.clone()))
                .or_insert((p.at, Vec::new()));
            if bytes.len() >= SESSION_BYTES {
                continue;
            }
            let gap = p.at.saturating_sub(*last).min(GAP);
            *last = p.at;
            let mut steps = vec![step];
            if !gap.is_zero() {
                steps.insert(0, Step::Advance(gap));
            }
            bytes.extend(encode(&steps));
        }
        for ((device, case), (_, bytes)) in sessions {
            seeds.case = case;
            seeds.add(device, &bytes);
        }
    }
    Ok(())
}

fn walk(dir: &Path) -> Result<Vec<PathBuf>, String> {
    let mut out = Vec::new();
    let entries = fs::read_dir(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    for entry in entries {
        let path = entry.map_err(|e| e.to_string())?.path();
        if path.is_dir() {
            out.extend(walk(&path)?);
        } else {
            out.push(path);
        }
    }
    Ok(out)
}

/// A name from the content (FNV-1a, 64 bit): the same seed is written once.
fn name(bytes: &[u8]) -> String {
    let hash = bytes.iter().fold(0xCBF2_9CE4_8422_2325_u64, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01B3)
    });
    format!("{hash:016x}")
}

fn run(args: &[String]) -> Result<(), String> {
    let [captures_dir, suites, descriptions, out] = args else {
        return Err(
            "usage: seed CAPTURES_DIR SUITES_DIR DESCRIPTIONS_DIR OUT_DIR (see the source)".into(),
        );
    };
    let mut seeds = Seeds::default();
    captures(Path::new(captures_dir), &mut seeds)?;
    for (dir, target, ext) in [
        (suites, "suite", Some("yaml")),
        (descriptions, "description", None),
    ] {
        for f in walk(Path::new(dir))? {
            if ext.is_none_or(|e| f.extension().is_some_and(|x| x == e)) {
                let bytes = fs::read(&f).map_err(|e| format!("{}: {e}", f.display()))?;
                seeds.case = f.display().to_string();
                seeds.add(target, &bytes);
            }
        }
    }
    for (target, list) in seeds.seeds {
        let dir = Path::new(out).join(target);
        fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        for bytes in &list {
            fs::write(dir.join(name(bytes)), bytes).map_err(|e| e.to_string())?;
        }
        println!("{target}: {} seeds", list.len());
    }
    Ok(())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("seed: {e}");
            ExitCode::FAILURE
        }
    }
}
