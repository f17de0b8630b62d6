//! The PROFINET IO soak over a veth pair: `harness serve pnio` (a process of its own) in a
//! network namespace on one end, the clients on the other. Good clients ask the device for
//! its DeviceID with DCP Get (IEC 61158-6-10 "DCP": option 2, suboption 3, vendor and device
//! id), which no Set changes, so its answer stays known however the fuzzed clients rename or
//! readdress the device; the device's address is found once with Identify All, and an answer
//! is taken by the client's own Xid. Fuzzed clients send broken DCP telegrams (Identify, Get,
//! Set, Hello) and broken cyclic frames to the device.

use std::ops::Range;
use std::time::{Duration, Instant};

use proto::eth::{MacAddr, ETHERTYPE_PROFINET};
use proto::pnio::dcp::{
    BlockQualifier, BlockValue, DcpBlock, DcpData, DcpOption, DcpRepr, ServiceId, ServiceType,
};
use proto::pnio::MULTICAST_DCP_IDENTIFY;

use super::mutate::Mutator;
use super::raw::{client_mac, RawSocket};
use super::run::{Answer, Bus};

/// How long a good client waits for its answer.
const TIMEOUT: Duration = Duration::from_secs(1);
/// DCPDataLength (bytes 10–11 from the frame id on) and the first block's DCPBlockLength
/// (14–15): broken to lie.
const LENGTHS: [Range<usize>; 2] = [10..12, 14..16];
/// Broken telegrams are at most this long (a full Ethernet payload).
const MAX_LEN: usize = 1500;

/// The device's address on the link, and what its answer must be.
pub(crate) struct Pnio {
    iface: String,
    device: MacAddr,
    expected: DcpData,
}

/// A good client: its socket and its last Xid.
pub(crate) struct Good {
    socket: RawSocket,
    xid: u32,
}

/// A fuzzed client.
pub(crate) struct Fuzzer {
    socket: RawSocket,
    mutator: Mutator,
    telegrams: Vec<Vec<u8>>,
    device: MacAddr,
}

impl Pnio {
    /// The bus on `iface`: the device found with Identify All, and the known answer read once
    /// before any broken telegram is sent.
    pub(crate) fn new(iface: &str) -> Result<Pnio, String> {
        let mut good = Good {
            socket: RawSocket::open(iface, client_mac(0x47, 0xFF))?,
            xid: 0x50_0000,
        };
        let identify = DcpRepr::identify_all(good.xid, 1)
            .emit()
            .map_err(|e| e.to_string())?;
        good.socket
            .send(MULTICAST_DCP_IDENTIFY, ETHERTYPE_PROFINET, &identify);
        let xid = good.xid;
        let device = good
            .socket
            .receive(ETHERTYPE_PROFINET, Instant::now() + TIMEOUT, |src, p| {
                let r = DcpRepr::parse(p).ok()?;
                (r.service == ServiceId::IDENTIFY && r.xid == xid).then_some(src)
            })
            .ok_or("no device answered Identify All")?;
        let expected = get(&mut good, device).ok_or("the device did not answer DCP Get")?;
        Ok(Pnio {
            iface: iface.into(),
            device,
            expected,
        })
    }

    /// The device's address and the known answer, for the report.
    pub(crate) fn said(&self) -> String {
        format!("device {:?}, known answer {:?}", self.device, self.expected)
    }
}

impl Bus for Pnio {
    type Good = Good;
    type Fuzz = Fuzzer;

    fn good(&self, n: usize) -> Result<Good, String> {
        Ok(Good {
            socket: RawSocket::open(&self.iface, client_mac(0x47, n as u8))?,
            xid: (n as u32) << 24,
        })
    }

    fn ask(&self, client: &mut Good) -> Answer {
        match get(client, self.device) {
            Some(d) if d == self.expected => Answer::Right,
            Some(d) => Answer::Wrong(format!("{d:?}")),
            None => Answer::Lost(format!(
                "DCP Get Xid {:#x} not answered within {} ms",
                client.xid,
                TIMEOUT.as_millis()
            )),
        }
    }

    fn fuzzer(&self, seed: u64) -> Result<Fuzzer, String> {
        Ok(Fuzzer {
            socket: RawSocket::open(&self.iface, client_mac(0x46, seed as u8))?,
            mutator: Mutator::new(seed),
            telegrams: good_telegrams()?,
            device: self.device,
        })
    }

    fn fuzz(&self, f: &mut Fuzzer) -> u64 {
        let m = f.mutator.mutate(&f.telegrams, &LENGTHS, MAX_LEN);
        let dst = if f.mutator.rng().bool() {
            f.device
        } else {
            MULTICAST_DCP_IDENTIFY
        };
        u64::from(f.socket.send(dst, ETHERTYPE_PROFINET, &m))
    }
}

/// One DCP Get of the DeviceID: the answer's data, `None` when none came in time.
fn get(client: &mut Good, device: MacAddr) -> Option<DcpData> {
    client.xid = client.xid.wrapping_add(1);
    let xid = client.xid;
    let request = DcpRepr::get(xid, vec![DcpOption::DEVICE_ID]).emit().ok()?;
    let deadline = Instant::now() + TIMEOUT;
    if !client.socket.send(device, ETHERTYPE_PROFINET, &request) {
        return None;
    }
    client
        .socket
        .receive(ETHERTYPE_PROFINET, deadline, |src, payload| {
            let r = DcpRepr::parse(payload).ok()?;
            (src == device
                && r.service == ServiceId::GET
                && r.service_type != ServiceType::REQUEST
                && r.xid == xid)
                .then_some(r.data)
        })
}

/// The good telegrams broken: Identify All, Get of the DeviceID and the name, a Set of the
/// name, a Hello, and a cyclic frame's frame id with data.
fn good_telegrams() -> Result<Vec<Vec<u8>>, String> {
    let temporary = BlockQualifier(0);
    let telegrams = [
        DcpRepr::identify_all(7, 1),
        DcpRepr::get(7, vec![DcpOption::DEVICE_ID, DcpOption::NAME_OF_STATION]),
        DcpRepr::set(
            7,
            vec![DcpBlock::set(
                temporary,
                BlockValue::NameOfStation("soak".into()),
            )],
        ),
        DcpRepr::hello(7, vec![]),
    ];
    let mut out = telegrams
        .iter()
        .map(|t| t.emit().map_err(|e| e.to_string()))
        .collect::<Result<Vec<_>, _>>()?;
    // RT class 1 frame id C000h, 40 bytes of data, cycle counter, status and transfer status.
    out.push([&[0xC0, 0x00][..], &[0; 40], &[0, 1, 0x35, 0]].concat());
    Ok(out)
}
