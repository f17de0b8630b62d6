//! Raw Ethernet for the soak's clients on the root end of a veth pair (the served device on
//! the other end, in a namespace of its own): a packet socket per client, frames sent and
//! the device's answers picked out of everything else on the link (the other clients'
//! frames, which a packet socket sees too).

use std::time::{Duration, Instant};

use pnet_datalink::{Channel, Config, DataLinkReceiver, DataLinkSender, NetworkInterface};
use proto::eth::{EthernetFrame, EthernetRepr, MacAddr};

/// How long a receive waits at most before the deadline is looked at again.
const POLL: Duration = Duration::from_millis(5);

/// A client's address: `00:4E:53:4B:kind:n` (`kind` G for good, F for fuzzed), so that each
/// client tells its own answers from the others'.
pub(crate) fn client_mac(kind: u8, n: u8) -> MacAddr {
    MacAddr([0x00, 0x4E, 0x53, 0x4B, kind, n])
}

/// A packet socket on one interface.
pub(crate) struct RawSocket {
    tx: Box<dyn DataLinkSender>,
    rx: Box<dyn DataLinkReceiver>,
    /// The client's own address: the source of what it sends.
    pub(crate) mac: MacAddr,
}

impl RawSocket {
    /// A socket on `iface` sending from `mac`.
    pub(crate) fn open(iface: &str, mac: MacAddr) -> Result<RawSocket, String> {
        let interface: NetworkInterface = pnet_datalink::interfaces()
            .into_iter()
            .find(|i| i.name == iface)
            .ok_or(format!("no interface {iface}"))?;
        let config = Config {
            read_timeout: Some(POLL),
            ..Config::default()
        };
        match pnet_datalink::channel(&interface, config) {
            Ok(Channel::Ethernet(tx, rx)) => Ok(RawSocket { tx, rx, mac }),
            Ok(_) => Err(format!("{iface}: not an Ethernet channel")),
            Err(e) => Err(format!("packet socket on {iface}: {e}")),
        }
    }

    /// Sends `payload` with EtherType `ethertype` to `dst`; whether it went out.
    pub(crate) fn send(&mut self, dst: MacAddr, ethertype: u16, payload: &[u8]) -> bool {
        let frame = EthernetRepr {
            dst,
            src: self.mac,
            ethertype,
        }
        .emit(payload);
        matches!(self.tx.send_to(&frame, None), Some(Ok(())))
    }

    /// The first frame of EtherType `ethertype` whose payload `pick` takes, until `deadline`;
    /// `pick` sees each frame's source and payload.
    pub(crate) fn receive<T>(
        &mut self,
        ethertype: u16,
        deadline: Instant,
        mut pick: impl FnMut(MacAddr, &[u8]) -> Option<T>,
    ) -> Option<T> {
        while Instant::now() < deadline {
            let Ok(bytes) = self.rx.next() else {
                continue;
            };
            let Ok(frame) = EthernetFrame::new_checked(bytes) else {
                continue;
            };
            if frame.ethertype() != ethertype {
                continue;
            }
            if let Some(t) = pick(frame.src(), frame.payload()) {
                return Some(t);
            }
        }
        None
    }
}
