//! The EtherCAT soak over a veth pair: `harness serve ecat` (a process of its own) in a
//! network namespace on one end, the clients on the other. Good clients read the first
//! slave's ESC identification registers (APRD, position 0, 0000h–0009h: type, revision,
//! build, FMMUs, SyncManagers, RAM size, ports, features; Beckhoff's ESC register
//! description, "Register address space"), which no master can write, so their answer stays
//! known however the fuzzed clients change the slave's state. Each good client sends from its
//! own address and takes as its answer only a frame from that address as the slave returns it
//! (the locally administered bit set) with its datagram's index. Fuzzed clients send broken
//! EtherCAT frames.

use std::ops::Range;
use std::time::{Duration, Instant};

use proto::ecat::datagram::{Command, DatagramRepr};
use proto::ecat::frame::EcatFrameRepr;
use proto::ecat::register::{AL_CONTROL, AL_STATUS, STATION_ADDRESS, TYPE};
use proto::eth::{MacAddr, ETHERTYPE_ECAT};

use super::mutate::Mutator;
use super::raw::{client_mac, RawSocket};
use super::run::{Answer, Bus};

/// Bytes read from [`TYPE`] on: up to and including the features register (0008h–0009h).
const IDENTIFICATION: usize = 10;
/// How long a good client waits for its frame to come back.
const TIMEOUT: Duration = Duration::from_secs(1);
/// The length fields of a frame's EtherCAT header and first datagram (ETG.1000.4 "Frame
/// structure", "EtherCAT datagram"): broken to lie.
const LENGTHS: [Range<usize>; 2] = [0..2, 8..10];
/// Broken EtherCAT payloads are at most this long (a full Ethernet payload).
const MAX_LEN: usize = 1500;

/// The interface the clients use, and what the slave's answer must be.
pub(crate) struct Ecat {
    iface: String,
    expected: Vec<u8>,
}

/// A good client: its socket and the index of its last datagram.
pub(crate) struct Good {
    socket: RawSocket,
    index: u8,
}

/// A fuzzed client.
pub(crate) struct Fuzzer {
    socket: RawSocket,
    mutator: Mutator,
    frames: Vec<Vec<u8>>,
}

impl Ecat {
    /// The bus on `iface`; the known answer is read once, before any broken frame is sent.
    pub(crate) fn new(iface: &str) -> Result<Ecat, String> {
        let mut good = Good {
            socket: RawSocket::open(iface, client_mac(0x47, 0xFF))?,
            index: 0,
        };
        let expected = match read(&mut good) {
            Some((1, data)) => data,
            Some((wkc, _)) => return Err(format!("the first read had working counter {wkc}")),
            None => return Err("the slave did not answer the first read".into()),
        };
        Ok(Ecat {
            iface: iface.into(),
            expected,
        })
    }

    /// The known answer, for the report.
    pub(crate) fn expected(&self) -> &[u8] {
        &self.expected
    }
}

impl Bus for Ecat {
    type Good = Good;
    type Fuzz = Fuzzer;

    fn good(&self, n: usize) -> Result<Good, String> {
        Ok(Good {
            socket: RawSocket::open(&self.iface, client_mac(0x47, n as u8))?,
            index: 0,
        })
    }

    fn ask(&self, client: &mut Good) -> Answer {
        match read(client) {
            Some((1, data)) if data == self.expected => Answer::Right,
            Some((wkc, data)) => Answer::Wrong(format!("working counter {wkc}, {data:02x?}")),
            None => Answer::Lost(format!(
                "APRD {:#04x} not back within {} ms",
                client.index,
                TIMEOUT.as_millis()
            )),
        }
    }

    fn fuzzer(&self, seed: u64) -> Result<Fuzzer, String> {
        Ok(Fuzzer {
            socket: RawSocket::open(&self.iface, client_mac(0x46, seed as u8))?,
            mutator: Mutator::new(seed),
            frames: good_frames()?,
        })
    }

    fn fuzz(&self, f: &mut Fuzzer) -> u64 {
        let m = f.mutator.mutate(&f.frames, &LENGTHS, MAX_LEN);
        u64::from(f.socket.send(MacAddr::BROADCAST, ETHERTYPE_ECAT, &m))
    }
}

/// One APRD of the identification registers: the working counter and data of the answer,
/// `None` when it did not come back in time.
fn read(client: &mut Good) -> Option<(u16, Vec<u8>)> {
    client.index = client.index.wrapping_add(1);
    let index = client.index;
    let request = DatagramRepr::physical(Command::APRD, index, 0, TYPE, vec![0; IDENTIFICATION]);
    let frame = EcatFrameRepr::new(vec![request]).emit().ok()?;
    let deadline = Instant::now() + TIMEOUT;
    if !client
        .socket
        .send(MacAddr::BROADCAST, ETHERTYPE_ECAT, &frame)
    {
        return None;
    }
    let returned = client.socket.mac.with_locally_administered();
    client
        .socket
        .receive(ETHERTYPE_ECAT, deadline, |src, payload| {
            let f = (src == returned)
                .then(|| EcatFrameRepr::parse_bytes(payload).ok())
                .flatten()?;
            match f.datagrams.as_slice() {
                [d] if d.command == Command::APRD && d.index == index => {
                    Some((d.wkc, d.data.clone()))
                }
                _ => None,
            }
        })
}

/// The good frames broken: reads of the identification, the AL status and the station
/// address, a request to Pre-Operational, and a frame of three datagrams.
fn good_frames() -> Result<Vec<Vec<u8>>, String> {
    let d = |c, adp, ado, data| DatagramRepr::physical(c, 0x5A, adp, ado, data);
    let frames = [
        vec![d(Command::APRD, 0, TYPE, vec![0; IDENTIFICATION])],
        vec![d(Command::BRD, 0, AL_STATUS, vec![0; 2])],
        vec![d(Command::FPRD, 0x1001, AL_STATUS, vec![0; 6])],
        vec![d(Command::APWR, 0, AL_CONTROL, vec![0x02, 0])],
        vec![
            d(Command::APRD, 0, STATION_ADDRESS, vec![0; 2]),
            d(Command::BRD, 0, AL_STATUS, vec![0; 2]),
            d(Command::APRW, 0, 0x1000, vec![0; 32]),
        ],
    ];
    frames
        .into_iter()
        .map(|f| EcatFrameRepr::new(f).emit().map_err(|e| e.to_string()))
        .collect()
}
