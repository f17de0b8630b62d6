//! One way into and out of every simulated device, so that one driver serves any of them: the
//! EtherNet/IP adapter, the EtherCAT slave, the POWERLINK node, the PROFINET IO device and the
//! system bus's CAN segment each take [`Input`]s and the time and give [`Output`]s and the time
//! they want to be polled next ([`Endpoint`]).
//!
//! Sans-IO, as the devices themselves: an endpoint never reads a clock and never touches a
//! socket. A driver (the harness's `serve` commands on a raw interface, UDP and TCP sockets or
//! a CAN channel) receives, hands over what came with the time since it started, sends what
//! comes back, and sleeps until the next input or [`Endpoint::next_deadline`].

use std::net::SocketAddr;
use std::time::Duration;

use proto::can::CanFrame;

/// A TCP client of a device, as the driver numbers them (each connection a new number).
pub type ClientId = u64;

/// What reaches a device from its network. A device ignores what it has no use for (a CAN
/// frame at an Ethernet interface, a datagram to a port it does not serve), as a NIC drops
/// what is not its own.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Input<'a> {
    /// A whole Ethernet II frame from the raw interface (header first, no frame check
    /// sequence).
    Frame(&'a [u8]),
    /// A UDP datagram to the device's port `port`.
    Datagram {
        /// The device's port it came to (a device may serve several: EtherNet/IP's 44818
        /// and 2222).
        port: u16,
        /// Its sender.
        from: SocketAddr,
        /// Its payload.
        bytes: &'a [u8],
    },
    /// One whole message of a TCP client, cut from the stream by the device's own framing
    /// (for EtherNet/IP `crate::enip::Framer`).
    Message {
        /// The client.
        client: ClientId,
        /// The client's address.
        peer: SocketAddr,
        /// The message.
        bytes: &'a [u8],
    },
    /// A TCP client went away.
    Closed(ClientId),
    /// A frame another node put on the CAN bus.
    Can(&'a CanFrame),
}

/// What a device sends.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Output {
    /// A whole Ethernet II frame for the raw interface.
    Frame(Vec<u8>),
    /// A UDP datagram from the device's port `port`.
    Datagram {
        /// The device's port it leaves from.
        port: u16,
        /// Where it goes.
        to: SocketAddr,
        /// Its payload.
        bytes: Vec<u8>,
    },
    /// Bytes for a TCP client.
    Message {
        /// The client.
        client: ClientId,
        /// The bytes (a whole message).
        bytes: Vec<u8>,
    },
    /// Close a TCP client's connection, after what was sent it before.
    Close(ClientId),
    /// A frame for the CAN bus.
    Can(CanFrame),
}

/// A simulated device as a driver runs it: inputs in, outputs out, time passed in.
pub trait Endpoint {
    /// Handles `input`, which arrived at `now` (time since the driver started); returns what
    /// to send, in order.
    fn input(&mut self, input: Input<'_>, now: Duration) -> Vec<Output>;

    /// Lets time pass up to `now`: runs what is due (cyclic frames, watchdogs, heartbeats, the
    /// drive model) and returns what to send. A driver calls it by
    /// [`Endpoint::next_deadline`] at the latest and may call it more often (after every
    /// input, say): what is not due yet waits for its time.
    fn poll(&mut self, now: Duration) -> Vec<Output>;

    /// When [`Endpoint::poll`] has something to do next (time since the driver started);
    /// `None` when nothing is scheduled.
    fn next_deadline(&self) -> Option<Duration>;

    /// Raises, at `now`, what the device reports on its own when a fault appears (a PROFINET
    /// alarm, a POWERLINK or CANopen emergency), though nothing is wrong: for a served device
    /// that misbehaves on purpose (`harness serve --misbehave alarm=`). What it raised, and
    /// what to send now (nothing when the report waits for the master to fetch it, as an
    /// EtherCAT mailbox or a POWERLINK StatusResponse does); `None` when the device has nowhere
    /// to raise one yet (no connection to an IO controller) or has no such reports.
    fn raise_alarm(&mut self, now: Duration) -> Option<Raised> {
        let _ = now;
        None
    }
}

/// What [`Endpoint::raise_alarm`] raised.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Raised {
    /// What it is, for the log ("process alarm on slot 1, sequence 3").
    pub what: String,
    /// What to send now.
    pub outputs: Vec<Output>,
}
