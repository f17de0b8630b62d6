//! A raw Ethernet link on one interface: pnet opens it and sends, a `recvmsg` on the same
//! packet socket receives.
//!
//! pnet's receiver returns the bytes of a frame and nothing else, while a tester needs two
//! things the kernel says beside them: the packet type (`sll_pkttype`), to keep frames that
//! left this host (`PACKET_OUTGOING`) from being read as if a peer had sent them, and the
//! receive stamp (`SO_TIMESTAMPNS`), to measure a cycle's jitter by when frames arrived rather
//! than by when a thread got round to reading them. So the packet socket is made here (nix),
//! handed to pnet (which binds it to the interface, enables promiscuous mode and sends on it),
//! and a duplicate of its descriptor is read with `recvmsg`, which returns both.
//!
//! The socket is created with protocol 0, which receives nothing until pnet binds it to the
//! interface, so no frame of another interface is ever queued. A packet socket never receives
//! the frames it sent itself (Linux skips the sending socket when it hands outgoing frames to
//! packet sockets); outgoing frames of other sockets on the same interface are dropped by their
//! packet type.

use std::io::IoSliceMut;
use std::os::fd::{AsFd, BorrowedFd, IntoRawFd, OwnedFd};
use std::time::{Duration, Instant};

use nix::errno::Errno;
use nix::poll::{ppoll, PollFd, PollFlags};
use nix::sys::socket::{
    recvmsg, setsockopt, socket, sockopt, AddressFamily, ControlMessageOwned, LinkAddr, MsgFlags,
    SockFlag, SockType,
};
use nix::sys::time::TimeSpec;
use pnet_datalink::{Channel, DataLinkReceiver, DataLinkSender};

use super::iface::{lookup, Interface, Mac};
use super::LinkError;

/// `sll_pkttype` of a frame this host sent (linux/if_packet.h).
const PACKET_OUTGOING: u8 = 4;

/// The IEEE 802.1Q tag's EtherType: the frame's own EtherType follows the 4-byte tag.
const VLAN: u16 = 0x8100;

/// Receive buffer of the link's caller for any frame a standard interface carries: 14-byte
/// header, 1500-byte payload, one 802.1Q tag (the frame check sequence is not delivered).
pub(crate) const MAX_FRAME: usize = 1518;

/// How long [`RawLink::send`] may wait for room in the socket's send queue.
const SEND_TIMEOUT: Duration = Duration::from_secs(1);

/// A frame that [`RawLink::recv`] put into the caller's buffer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Received {
    /// Its length (header included, frame check sequence not).
    pub(crate) len: usize,
    /// When the kernel received it (`SO_TIMESTAMPNS`: the real-time clock, as a duration since
    /// the Unix epoch; compare stamps with each other, not with [`Instant`]). `None` when the
    /// kernel gave none.
    pub(crate) stamp: Option<Duration>,
}

/// What [`RawLink::recv_or`] found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Ready {
    /// A frame of the link, in the caller's buffer.
    Frame(Received),
    /// The other socket is readable, and no frame of the link is queued.
    Other,
    /// Nothing by the deadline.
    Nothing,
}

/// An open raw Ethernet link: frames of one EtherType (or all) on one interface.
pub(crate) struct RawLink {
    iface: Interface,
    ethertype: Option<u16>,
    /// A second EtherType taken besides `ethertype` ([`RawLink::also_take`]).
    also: Option<u16>,
    tx: Box<dyn DataLinkSender>,
    /// pnet's receiver on the same socket. Never read (frames are read with `recvmsg` on
    /// `socket`), kept because it shares the socket's descriptor with `tx`.
    _rx: Box<dyn DataLinkReceiver>,
    /// A duplicate of the packet socket's descriptor, for `recvmsg` and `ppoll`.
    socket: OwnedFd,
    /// How long [`RawLink::recv`] polls the socket before it sleeps in `ppoll`.
    spin: Duration,
    /// Frames dropped because they did not fit the caller's buffer.
    oversized: u64,
}

impl std::fmt::Debug for RawLink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RawLink")
            .field("iface", &self.iface)
            .field("ethertype", &self.ethertype)
            .finish_non_exhaustive()
    }
}

impl RawLink {
    /// Opens interface `name` for frames of `ethertype` (every frame when `None`); frames of
    /// other types are skipped by [`RawLink::recv`]. Needs root or `CAP_NET_RAW`.
    pub(crate) fn open(name: &str, ethertype: Option<u16>) -> Result<RawLink, LinkError> {
        let pnet_iface = lookup(name)?;
        let iface = Interface::from_pnet(&pnet_iface)?;
        let err = |op, e: Errno| LinkError::io(op, name, std::io::Error::from(e));
        let sock = socket(
            AddressFamily::Packet,
            SockType::Raw,
            SockFlag::SOCK_CLOEXEC,
            None,
        )
        .map_err(|e| err("open a packet socket", e))?;
        setsockopt(&sock, sockopt::ReceiveTimestampns, &true)
            .map_err(|e| err("enable receive stamps (SO_TIMESTAMPNS)", e))?;
        let dup = sock
            .try_clone()
            .map_err(|e| LinkError::io("duplicate the socket", name, e))?;
        let config = pnet_datalink::Config {
            write_timeout: Some(SEND_TIMEOUT),
            read_buffer_size: 64,
            write_buffer_size: MAX_FRAME,
            promiscuous: true,
            socket_fd: Some(sock.into_raw_fd()),
            ..Default::default()
        };
        // pnet owns the descriptor from here on (and closes it on failure).
        let (tx, rx) = match pnet_datalink::channel(&pnet_iface, config) {
            Ok(Channel::Ethernet(tx, rx)) => (tx, rx),
            Ok(_) => {
                return Err(LinkError::Io {
                    op: "open",
                    iface: name.into(),
                    source: std::io::Error::other("pnet gave a channel that is not Ethernet"),
                })
            }
            Err(e) => return Err(LinkError::io("bind the packet socket", name, e)),
        };
        Ok(RawLink {
            iface,
            ethertype,
            also: None,
            tx,
            _rx: rx,
            socket: dup,
            spin: Duration::ZERO,
            oversized: 0,
        })
    }

    /// The interface's Ethernet address.
    pub(crate) fn mac(&self) -> Mac {
        self.iface.mac
    }

    /// Makes [`RawLink::recv`] poll the socket for up to `spin` before it sleeps: a reply that
    /// comes within it is seen without a thread wake-up (see `crate::poll`), at the cost of
    /// the processor while it polls.
    pub(crate) fn set_spin(&mut self, spin: Duration) {
        self.spin = spin;
    }

    /// Frames skipped so far because they did not fit the caller's buffer.
    pub(crate) fn oversized(&self) -> u64 {
        self.oversized
    }

    /// Sends `frame` (Ethernet header first, no frame check sequence) as it is.
    pub(crate) fn send(&mut self, frame: &[u8]) -> Result<(), LinkError> {
        if frame.len() < 14 {
            return Err(LinkError::FrameTooShort { len: frame.len() });
        }
        match self.tx.send_to(frame, None) {
            Some(Ok(())) => Ok(()),
            Some(Err(e)) => Err(LinkError::io("send", &self.iface.name, e)),
            None => Err(LinkError::Io {
                op: "send",
                iface: self.iface.name.clone(),
                source: std::io::Error::other("pnet did not send the frame"),
            }),
        }
    }

    /// Receives the next frame of the link's EtherType that arrived on the interface into
    /// `buf`, waiting until `deadline` at most: `Ok(None)` when none came by then. A frame
    /// already queued is returned even when `deadline` has passed. Frames longer than `buf`
    /// are skipped and counted ([`RawLink::oversized`]); [`MAX_FRAME`] bytes hold any frame of
    /// a standard interface.
    pub(crate) fn recv(
        &mut self,
        buf: &mut [u8],
        deadline: Instant,
    ) -> Result<Option<Received>, LinkError> {
        Ok(match self.recv_or(buf, deadline, None)? {
            Ready::Frame(r) => Some(r),
            Ready::Other | Ready::Nothing => None,
        })
    }

    /// As [`RawLink::recv`], and waits on `other` (a socket of the same host) as well: a frame
    /// queued on the link comes first, [`Ready::Other`] only when none is. A device served on
    /// the link and on a UDP socket by one thread so takes a datagram after every frame that
    /// came before it on the wire: the kernel hands a frame to packet sockets before it
    /// delivers it to its UDP socket, so those frames are queued here by then.
    pub(crate) fn recv_or(
        &mut self,
        buf: &mut [u8],
        deadline: Instant,
        other: Option<BorrowedFd<'_>>,
    ) -> Result<Ready, LinkError> {
        let spin_until = Instant::now() + self.spin;
        loop {
            if let Some(r) = self.try_recv(buf)? {
                return Ok(Ready::Frame(r));
            }
            let now = Instant::now();
            let glance = now >= deadline || now < spin_until;
            let wait = if glance {
                TimeSpec::from_duration(Duration::ZERO)
            } else {
                TimeSpec::from_duration(deadline - now)
            };
            if glance && other.is_none() {
                if now >= deadline {
                    return Ok(Ready::Nothing);
                }
                std::thread::yield_now();
                continue;
            }
            let mut fds = vec![PollFd::new(self.socket.as_fd(), PollFlags::POLLIN)];
            fds.extend(other.map(|o| PollFd::new(o, PollFlags::POLLIN)));
            match ppoll(&mut fds, Some(wait), None) {
                Ok(_) | Err(Errno::EINTR) => {}
                Err(e) => return Err(self.error("wait for a frame", e)),
            }
            let other_ready = fds
                .get(1)
                .and_then(PollFd::revents)
                .is_some_and(|r| !r.is_empty());
            let frame_ready = fds[0].revents().is_some_and(|r| !r.is_empty());
            if other_ready && !frame_ready {
                return Ok(Ready::Other);
            }
            if glance && !frame_ready {
                if now >= deadline {
                    return Ok(Ready::Nothing);
                }
                std::thread::yield_now();
            }
        }
    }

    /// The next wanted frame already queued, without waiting.
    fn try_recv(&mut self, buf: &mut [u8]) -> Result<Option<Received>, LinkError> {
        loop {
            let mut cmsg = nix::cmsg_space!(TimeSpec);
            let mut iov = [IoSliceMut::new(buf)];
            let msg = match recvmsg::<LinkAddr>(
                std::os::fd::AsRawFd::as_raw_fd(&self.socket),
                &mut iov,
                Some(&mut cmsg),
                MsgFlags::MSG_DONTWAIT | MsgFlags::MSG_TRUNC,
            ) {
                Ok(m) => m,
                Err(Errno::EAGAIN) => return Ok(None),
                Err(Errno::EINTR) => continue,
                Err(e) => return Err(self.error("receive", e)),
            };
            let stamp = msg.cmsgs().ok().and_then(|mut c| {
                c.find_map(|c| match c {
                    ControlMessageOwned::ScmTimestampns(t) => Some(Duration::from(t)),
                    _ => None,
                })
            });
            let (len, truncated) = (msg.bytes, msg.flags.contains(MsgFlags::MSG_TRUNC));
            let from = msg.address;
            // The iovec's borrow of `buf` ends with `msg`.
            if let Some(a) = from {
                if a.pkttype() == PACKET_OUTGOING || a.ifindex() != self.iface.index as usize {
                    continue;
                }
            }
            if !self.wanted(&buf[..len.min(buf.len())]) {
                continue;
            }
            if truncated || len > buf.len() {
                self.oversized += 1;
                continue;
            }
            return Ok(Some(Received { len, stamp }));
        }
    }

    /// Takes frames of `ethertype` too (a PROFINET controller: LLDP beside PROFINET).
    pub(crate) fn also_take(&mut self, ethertype: u16) {
        self.also = Some(ethertype);
    }

    /// Whether `frame` carries the link's EtherType (behind one 802.1Q tag or none).
    fn wanted(&self, frame: &[u8]) -> bool {
        let Some(want) = self.ethertype else {
            return frame.len() >= 14;
        };
        let at = |i: usize| {
            frame
                .get(i..i + 2)
                .map(|b| u16::from_be_bytes([b[0], b[1]]))
        };
        let carried = match at(12) {
            Some(VLAN) => at(16),
            t => t,
        };
        carried.is_some_and(|t| t == want || Some(t) == self.also)
    }

    fn error(&self, op: &'static str, e: Errno) -> LinkError {
        LinkError::io(op, &self.iface.name, std::io::Error::from(e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::net::veth::Veth;

    /// An EtherCAT-typed frame (EtherType 88A4h) from `src` to the broadcast address,
    /// padded to the 60-byte minimum, with `tag` as its first payload byte.
    fn frame(src: Mac, ethertype: u16, tag: u8) -> Vec<u8> {
        let mut f = Vec::with_capacity(60);
        f.extend_from_slice(&Mac::BROADCAST.0); // destination
        f.extend_from_slice(&src.0); // source
        f.extend_from_slice(&ethertype.to_be_bytes()); // EtherType
        f.push(tag);
        f.resize(60, 0);
        f
    }

    const ECAT: u16 = 0x88A4;

    #[test]
    fn unknown_interface_is_an_error_before_any_socket() {
        match RawLink::open("no-such-if0", Some(ECAT)) {
            Err(LinkError::NoSuchInterface { name, .. }) => assert_eq!(name, "no-such-if0"),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn frames_cross_a_veth_pair_filtered_by_ethertype_and_stamped() {
        let Some(v) = Veth::new("x") else { return };
        let mut a = RawLink::open(&v.0, Some(ECAT)).expect("open a");
        let mut b = RawLink::open(&v.1, Some(ECAT)).expect("open b");
        assert_ne!(a.mac(), Mac::default());
        // Another EtherType first: b skips it and takes the EtherCAT frame behind it.
        a.send(&frame(a.mac(), 0x0800, 1)).unwrap();
        a.send(&frame(a.mac(), ECAT, 2)).unwrap();
        let mut buf = [0u8; MAX_FRAME];
        let r = b
            .recv(&mut buf, Instant::now() + Duration::from_secs(2))
            .unwrap()
            .expect("a frame within 2 s");
        assert_eq!(&buf[..r.len], &frame(a.mac(), ECAT, 2)[..]);
        assert!(r.stamp.is_some(), "kernel receive stamp");
        // b answers; a sees b's frame, never its own two.
        b.send(&frame(Mac([0x03, 1, 1, 1, 1, 1]), ECAT, 3)).unwrap();
        let r = a
            .recv(&mut buf, Instant::now() + Duration::from_secs(2))
            .unwrap()
            .expect("b's frame");
        assert_eq!(buf[14], 3);
        let t = Instant::now();
        let none = a.recv(&mut buf, t + Duration::from_millis(50)).unwrap();
        assert_eq!(none, None, "a read back a frame: {:02x?}", &buf[..r.len]);
        assert!(t.elapsed() >= Duration::from_millis(50));
        assert!(
            t.elapsed() < Duration::from_millis(500),
            "{:?}",
            t.elapsed()
        );
    }

    #[test]
    fn a_second_socket_on_the_sending_side_does_not_see_outgoing_frames() {
        let Some(v) = Veth::new("o") else { return };
        let mut a = RawLink::open(&v.0, Some(ECAT)).unwrap();
        let mut also_a = RawLink::open(&v.0, Some(ECAT)).unwrap();
        a.send(&frame(a.mac(), ECAT, 7)).unwrap();
        let mut buf = [0u8; MAX_FRAME];
        let got = also_a.recv(&mut buf, Instant::now() + Duration::from_millis(100));
        assert_eq!(got.unwrap(), None, "PACKET_OUTGOING frame read as received");
    }

    #[test]
    fn oversized_frames_are_skipped_and_counted() {
        let Some(v) = Veth::new("s") else { return };
        let mut a = RawLink::open(&v.0, Some(ECAT)).unwrap();
        let mut b = RawLink::open(&v.1, Some(ECAT)).unwrap();
        let mut big = frame(a.mac(), ECAT, 1);
        big.resize(200, 0);
        a.send(&big).unwrap();
        a.send(&frame(a.mac(), ECAT, 2)).unwrap();
        let mut buf = [0u8; 100];
        let r = b
            .recv(&mut buf, Instant::now() + Duration::from_secs(2))
            .unwrap()
            .expect("the small frame");
        assert_eq!((r.len, buf[14], b.oversized()), (60, 2, 1));
        assert!(matches!(
            a.send(&[0u8; 13]),
            Err(LinkError::FrameTooShort { len: 13 })
        ));
    }
}
