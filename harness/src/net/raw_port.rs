//! The [`Port`] of a device served on a network interface: Ethernet frames of its EtherType on
//! a [`RawLink`], and datagrams on one UDP socket beside it (POWERLINK's SDO port, PROFINET's
//! RPC port), waited on together by one thread, frames first ([`RawLink::recv_or`]): the
//! device sees them in the order they came on the wire, a datagram sent after a reset frame
//! finds it reset.
//!
//! A link that goes down while its interface still exists (the cable out) is waited on: the
//! device sees no frames, its timers still run.

use std::net::{SocketAddr, UdpSocket};
use std::os::fd::AsFd;
use std::time::Instant;

use sim::endpoint::{Input, Output};

use super::driver::Port;
use super::udp::transient;
use super::{LinkError, RawLink, Ready, MAX_FRAME};

/// The largest datagram taken.
const MAX_DATAGRAM: usize = 2048;

/// A raw link, and maybe a UDP socket on the same interface.
#[derive(Debug)]
pub(crate) struct RawPort {
    link: RawLink,
    udp: Option<(UdpSocket, SocketAddr)>,
    frame: Vec<u8>,
    datagram: Vec<u8>,
}

impl RawPort {
    /// Frames on `link` only.
    pub(crate) fn new(link: RawLink) -> RawPort {
        RawPort {
            link,
            udp: None,
            frame: vec![0; MAX_FRAME],
            datagram: vec![0; MAX_DATAGRAM],
        }
    }

    /// Datagrams on `socket`, bound to `addr`, too (the device's port: `addr`'s). The socket
    /// is read only when ready, made non-blocking: a spurious wake-up cannot block the link.
    pub(crate) fn with_udp(
        mut self,
        socket: UdpSocket,
        addr: SocketAddr,
    ) -> Result<RawPort, LinkError> {
        socket
            .set_nonblocking(true)
            .map_err(|e| LinkError::io("make the UDP socket non-blocking", &addr.to_string(), e))?;
        self.udp = Some((socket, addr));
        Ok(self)
    }
}

impl Port for RawPort {
    type Error = LinkError;

    fn recv(&mut self, deadline: Instant) -> Result<Option<Input<'_>>, LinkError> {
        let other = self.udp.as_ref().map(|(s, _)| s.as_fd());
        let ready = match self.link.recv_or(&mut self.frame, deadline, other) {
            Ok(r) => r,
            Err(e) if e.is_link_down() => {
                std::thread::sleep(deadline.saturating_duration_since(Instant::now()));
                return Ok(None);
            }
            Err(e) => return Err(e),
        };
        match ready {
            Ready::Nothing => Ok(None),
            Ready::Frame(r) => Ok(Some(Input::Frame(&self.frame[..r.len]))),
            Ready::Other => {
                let Some((socket, addr)) = &self.udp else {
                    return Ok(None);
                };
                match socket.recv_from(&mut self.datagram) {
                    Ok((n, from)) => Ok(Some(Input::Datagram {
                        port: addr.port(),
                        from,
                        bytes: &self.datagram[..n],
                    })),
                    Err(e) if transient(&e) => Ok(None),
                    Err(e) => Err(LinkError::io(
                        "receive a UDP datagram",
                        &addr.to_string(),
                        e,
                    )),
                }
            }
        }
    }

    fn send(&mut self, out: &Output) -> Result<bool, LinkError> {
        match out {
            Output::Frame(f) => match self.link.send(f) {
                Ok(()) => Ok(true),
                Err(e) if e.is_link_down() => Ok(false),
                Err(e) => Err(e),
            },
            Output::Datagram { port, to, bytes } => {
                let Some((socket, addr)) = self.udp.as_ref().filter(|(_, a)| a.port() == *port)
                else {
                    return Ok(false);
                };
                match socket.send_to(bytes, to) {
                    Ok(_) => Ok(true),
                    Err(e) if transient(&e) => Ok(false),
                    Err(e) => Err(LinkError::io("send a UDP datagram", &addr.to_string(), e)),
                }
            }
            Output::Message { .. } | Output::Close(_) | Output::Can(_) => Ok(false),
        }
    }

    fn oversized(&self) -> u64 {
        self.link.oversized()
    }
}
