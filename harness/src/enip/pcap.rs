//! EtherNet/IP traffic in the run's capture ([`crate::pcap`]).
//!
//! The scanner's links carry application payloads only (TCP stream bytes of encapsulation
//! messages, UDP datagrams on 44818 and 2222), sometimes over an in-memory link, so this module
//! synthesizes the framing around them: Ethernet II, IPv4 and TCP or UDP, with correct checksums
//! and, for TCP, a handshake, sequence and acknowledgement numbers per direction and a closing
//! FIN exchange. The result dissects cleanly in Wireshark/tshark as `enip`/`cip`/`cipio`, but
//! for the bytes a suite breaks on purpose (`tests/interop_enip.rs` holds a full run to that).
//!
//! MAC addresses are derived from the IPv4 address (`02:00:a:b:c:d`, locally administered),
//! initial sequence numbers from the connection's 4-tuple, and the framing's state (open
//! connections, the next IPv4 identification) lives in the capture ([`Capture::with_state`]),
//! so a capture of the same embedded run is byte-for-byte the same.

use std::collections::HashMap;
use std::net::SocketAddrV4;
use std::time::Duration;

use crate::pcap::Capture;

/// This traffic in the capture interface's description.
const SOURCE: &str =
    "EtherNet/IP traffic of a harness run (Ethernet, IPv4 and TCP/UDP framing synthesized)";
/// Largest TCP payload per segment (Ethernet MTU 1500 less 20 bytes of IPv4 and 20 of TCP).
const MSS: usize = 1460;
/// Largest UDP payload that fits an IPv4 datagram.
const MAX_UDP_PAYLOAD: usize = 65_535 - IPV4_LEN - UDP_LEN;

const ETH_LEN: usize = 14;
const IPV4_LEN: usize = 20;
const UDP_LEN: usize = 8;
const TCP_LEN: usize = 20;
const ETHERTYPE_IPV4: u16 = 0x0800;
const PROTO_TCP: u8 = 6;
const PROTO_UDP: u8 = 17;
const TTL: u8 = 64;
const WINDOW: u16 = 65_535;

const FIN: u8 = 0x01;
const SYN: u8 = 0x02;
const PSH: u8 = 0x08;
const ACK: u8 = 0x10;

/// One TCP connection's sequence state.
#[derive(Debug, Clone, Copy)]
struct TcpState {
    /// Next sequence number the client sends.
    client_next: u32,
    /// Next sequence number the server sends.
    server_next: u32,
}

/// What the synthesized framing keeps between packets of a run, in the capture.
#[derive(Debug, Default)]
struct Framing {
    /// Open TCP connections, keyed by (client, server).
    tcp: HashMap<(SocketAddrV4, SocketAddrV4), TcpState>,
    /// Connections opened so far: mixed into each initial sequence number so that a reopened
    /// 4-tuple starts elsewhere.
    opened: u64,
    /// Next IPv4 identification.
    ip_id: u16,
    /// Connections the links recorded ([`Capture::tcp_connect`]).
    connections: u16,
}

impl Capture {
    /// A link's TCP connection between `client` and `server` opened: counted (see
    /// [`Capture::tcp_connections`]) and its handshake captured ([`Capture::tcp_open`]).
    pub(crate) fn tcp_connect(&mut self, client: SocketAddrV4, server: SocketAddrV4, at: Duration) {
        self.with_state(|f: &mut Framing, _| f.connections = f.connections.wrapping_add(1));
        self.tcp_open(client, server, at);
    }

    /// Connections the links recorded so far with [`Capture::tcp_connect`] (an embedded
    /// link gives each a client port of its own).
    pub(crate) fn tcp_connections(&mut self) -> u16 {
        self.with_state(|f: &mut Framing, _| f.connections)
    }

    /// A TCP connection between `client` and `server` opened: emits SYN, SYN-ACK and ACK.
    /// Opening a connection that is already open starts it anew.
    pub(crate) fn tcp_open(&mut self, client: SocketAddrV4, server: SocketAddrV4, at: Duration) {
        self.with_state(|f: &mut Framing, cap| f.tcp_open(cap, client, server, at));
    }

    /// Stream bytes from `from` to `to` on an open TCP connection, flags PSH|ACK: one segment
    /// per call, or several of at most 1460 bytes each for a longer payload. An empty payload
    /// emits nothing. On a connection not open yet, `from` is taken as the client and the
    /// handshake is emitted first.
    pub(crate) fn tcp_data(
        &mut self,
        from: SocketAddrV4,
        to: SocketAddrV4,
        payload: &[u8],
        at: Duration,
    ) {
        self.with_state(|f: &mut Framing, cap| f.tcp_data(cap, from, to, payload, at));
    }

    /// The connection closed by `from`: emits FIN|ACK from `from`, FIN|ACK from `to` and the
    /// final ACK from `from`. On a connection not open, `from` is taken as the client and the
    /// handshake is emitted first, so the capture stays consistent.
    pub(crate) fn tcp_close(&mut self, from: SocketAddrV4, to: SocketAddrV4, at: Duration) {
        self.with_state(|f: &mut Framing, cap| f.tcp_close(cap, from, to, at));
    }

    /// A UDP datagram of EtherNet/IP. A payload longer than an IPv4 datagram can carry
    /// (65507 bytes) is truncated to that length.
    pub(crate) fn udp(
        &mut self,
        from: SocketAddrV4,
        to: SocketAddrV4,
        payload: &[u8],
        at: Duration,
    ) {
        self.udp_of(SOURCE, from, to, payload, at);
    }

    /// A UDP datagram of the traffic `source` names (another bus's: POWERLINK's SDO over UDP).
    pub(crate) fn udp_of(
        &mut self,
        source: &'static str,
        from: SocketAddrV4,
        to: SocketAddrV4,
        payload: &[u8],
        at: Duration,
    ) {
        self.with_state(|f: &mut Framing, cap| f.udp(cap, source, from, to, payload, at));
    }
}

impl Framing {
    fn tcp_open(
        &mut self,
        cap: &mut Capture,
        client: SocketAddrV4,
        server: SocketAddrV4,
        at: Duration,
    ) {
        let isn = splitmix64(
            u64::from(u32::from(*client.ip())) << 32
                ^ u64::from(u32::from(*server.ip()))
                ^ u64::from(client.port()) << 48
                ^ u64::from(server.port()) << 16
                ^ self.opened.wrapping_mul(0x9E37_79B9_7F4A_7C15),
        );
        self.opened += 1;
        let (client_isn, server_isn) = (isn as u32, (isn >> 32) as u32);
        self.tcp_segment(cap, client, server, client_isn, 0, SYN, &[], at);
        let client_next = client_isn.wrapping_add(1);
        self.tcp_segment(
            cap,
            server,
            client,
            server_isn,
            client_next,
            SYN | ACK,
            &[],
            at,
        );
        let server_next = server_isn.wrapping_add(1);
        self.tcp_segment(cap, client, server, client_next, server_next, ACK, &[], at);
        self.tcp.insert(
            (client, server),
            TcpState {
                client_next,
                server_next,
            },
        );
    }

    fn tcp_data(
        &mut self,
        cap: &mut Capture,
        from: SocketAddrV4,
        to: SocketAddrV4,
        payload: &[u8],
        at: Duration,
    ) {
        if payload.is_empty() {
            return;
        }
        let (key, from_client) = self.connection(cap, from, to, at);
        for chunk in payload.chunks(MSS) {
            let Some(state) = self.tcp.get(&key).copied() else {
                return;
            };
            let (seq, ack) = if from_client {
                (state.client_next, state.server_next)
            } else {
                (state.server_next, state.client_next)
            };
            self.tcp_segment(cap, from, to, seq, ack, PSH | ACK, chunk, at);
            let next = seq.wrapping_add(chunk.len() as u32);
            if let Some(state) = self.tcp.get_mut(&key) {
                if from_client {
                    state.client_next = next;
                } else {
                    state.server_next = next;
                }
            }
        }
    }

    fn tcp_close(&mut self, cap: &mut Capture, from: SocketAddrV4, to: SocketAddrV4, at: Duration) {
        let (key, from_client) = self.connection(cap, from, to, at);
        let Some(state) = self.tcp.remove(&key) else {
            return;
        };
        let (from_seq, to_seq) = if from_client {
            (state.client_next, state.server_next)
        } else {
            (state.server_next, state.client_next)
        };
        let from_next = from_seq.wrapping_add(1);
        let to_next = to_seq.wrapping_add(1);
        self.tcp_segment(cap, from, to, from_seq, to_seq, FIN | ACK, &[], at);
        self.tcp_segment(cap, to, from, to_seq, from_next, FIN | ACK, &[], at);
        self.tcp_segment(cap, from, to, from_next, to_next, ACK, &[], at);
    }

    fn udp(
        &mut self,
        cap: &mut Capture,
        source: &'static str,
        from: SocketAddrV4,
        to: SocketAddrV4,
        payload: &[u8],
        at: Duration,
    ) {
        let payload = &payload[..payload.len().min(MAX_UDP_PAYLOAD)];
        let udp_len = (UDP_LEN + payload.len()) as u16;
        let mut segment = Vec::with_capacity(UDP_LEN + payload.len());
        segment.extend_from_slice(&from.port().to_be_bytes());
        segment.extend_from_slice(&to.port().to_be_bytes());
        segment.extend_from_slice(&udp_len.to_be_bytes());
        segment.extend_from_slice(&[0, 0]);
        segment.extend_from_slice(payload);
        let mut checksum = transport_checksum(from, to, PROTO_UDP, &segment);
        if checksum == 0 {
            // Zero means "no checksum" in UDP over IPv4; its ones-complement twin stands in.
            checksum = 0xFFFF;
        }
        segment[6..8].copy_from_slice(&checksum.to_be_bytes());
        self.push_ipv4(cap, source, from, to, PROTO_UDP, false, &segment, at);
    }

    /// The open connection between `a` and `b` in either direction, opened with `a` as client
    /// if there is none; returns its key and whether `a` is the client.
    fn connection(
        &mut self,
        cap: &mut Capture,
        a: SocketAddrV4,
        b: SocketAddrV4,
        at: Duration,
    ) -> ((SocketAddrV4, SocketAddrV4), bool) {
        if self.tcp.contains_key(&(a, b)) {
            ((a, b), true)
        } else if self.tcp.contains_key(&(b, a)) {
            ((b, a), false)
        } else {
            self.tcp_open(cap, a, b, at);
            ((a, b), true)
        }
    }

    /// Emits one TCP segment. SYN segments carry an MSS option.
    #[allow(clippy::too_many_arguments)]
    fn tcp_segment(
        &mut self,
        cap: &mut Capture,
        from: SocketAddrV4,
        to: SocketAddrV4,
        seq: u32,
        ack: u32,
        flags: u8,
        payload: &[u8],
        at: Duration,
    ) {
        let options: &[u8] = if flags & SYN != 0 {
            &[2, 4, (MSS >> 8) as u8, MSS as u8]
        } else {
            &[]
        };
        let header_len = TCP_LEN + options.len();
        let mut segment = Vec::with_capacity(header_len + payload.len());
        segment.extend_from_slice(&from.port().to_be_bytes());
        segment.extend_from_slice(&to.port().to_be_bytes());
        segment.extend_from_slice(&seq.to_be_bytes());
        segment.extend_from_slice(&(if flags & ACK != 0 { ack } else { 0 }).to_be_bytes());
        segment.push(((header_len / 4) as u8) << 4);
        segment.push(flags);
        segment.extend_from_slice(&WINDOW.to_be_bytes());
        segment.extend_from_slice(&[0, 0]); // checksum
        segment.extend_from_slice(&[0, 0]); // urgent pointer
        segment.extend_from_slice(options);
        segment.extend_from_slice(payload);
        let checksum = transport_checksum(from, to, PROTO_TCP, &segment);
        segment[16..18].copy_from_slice(&checksum.to_be_bytes());
        self.push_ipv4(cap, SOURCE, from, to, PROTO_TCP, true, &segment, at);
    }

    /// Wraps a transport segment in IPv4 and Ethernet II and captures the frame.
    #[allow(clippy::too_many_arguments)]
    fn push_ipv4(
        &mut self,
        cap: &mut Capture,
        source: &'static str,
        from: SocketAddrV4,
        to: SocketAddrV4,
        protocol: u8,
        dont_fragment: bool,
        segment: &[u8],
        at: Duration,
    ) {
        let mut frame = Vec::with_capacity(ETH_LEN + IPV4_LEN + segment.len());
        frame.extend_from_slice(&mac(to));
        frame.extend_from_slice(&mac(from));
        frame.extend_from_slice(&ETHERTYPE_IPV4.to_be_bytes());

        let id = self.ip_id;
        self.ip_id = self.ip_id.wrapping_add(1);
        let total_len = (IPV4_LEN + segment.len()) as u16;
        let flags_fragment: u16 = if dont_fragment { 0x4000 } else { 0 };
        let mut ip = [0u8; IPV4_LEN];
        ip[0] = 0x45; // version 4, header length 5 words
        ip[2..4].copy_from_slice(&total_len.to_be_bytes());
        ip[4..6].copy_from_slice(&id.to_be_bytes());
        ip[6..8].copy_from_slice(&flags_fragment.to_be_bytes());
        ip[8] = TTL;
        ip[9] = protocol;
        ip[12..16].copy_from_slice(&from.ip().octets());
        ip[16..20].copy_from_slice(&to.ip().octets());
        let checksum = !ones_complement_sum(0, &ip);
        ip[10..12].copy_from_slice(&checksum.to_be_bytes());

        frame.extend_from_slice(&ip);
        frame.extend_from_slice(segment);
        cap.source(source);
        cap.push(frame, at);
    }
}

/// The locally administered MAC address standing for an IPv4 host: `02:00:a:b:c:d`.
fn mac(addr: SocketAddrV4) -> [u8; 6] {
    let [a, b, c, d] = addr.ip().octets();
    [0x02, 0x00, a, b, c, d]
}

/// The TCP or UDP checksum of `segment` (its checksum field zero) with the IPv4 pseudo-header.
fn transport_checksum(from: SocketAddrV4, to: SocketAddrV4, protocol: u8, segment: &[u8]) -> u16 {
    let mut pseudo = [0u8; 12];
    pseudo[0..4].copy_from_slice(&from.ip().octets());
    pseudo[4..8].copy_from_slice(&to.ip().octets());
    pseudo[9] = protocol;
    pseudo[10..12].copy_from_slice(&(segment.len() as u16).to_be_bytes());
    let sum = ones_complement_sum(ones_complement_sum(0, &pseudo), segment);
    !sum
}

/// Adds `bytes`, as big-endian 16-bit words (an odd last byte padded with zero), to `sum` in
/// ones-complement arithmetic.
fn ones_complement_sum(sum: u16, bytes: &[u8]) -> u16 {
    let mut acc = u32::from(sum);
    let mut words = bytes.chunks_exact(2);
    for word in &mut words {
        acc += u32::from(u16::from_be_bytes([word[0], word[1]]));
    }
    if let [last] = words.remainder() {
        acc += u32::from(*last) << 8;
    }
    while acc > 0xFFFF {
        acc = (acc & 0xFFFF) + (acc >> 16);
    }
    acc as u16
}

/// A 64-bit mixing function (SplitMix64's finalizer), for deterministic initial sequence
/// numbers.
fn splitmix64(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pcap::testing::{description, read_pcapng, tempdir};
    use crate::pcap::{Packet, EPOCH_SECS, SNAPLEN, TSRESOL_NANOS};
    use pcap_file::pcapng::blocks::interface_description::InterfaceDescriptionOption;
    use pcap_file::pcapng::blocks::section_header::SectionHeaderOption;
    use pcap_file::{DataLink, Endianness};
    use std::net::Ipv4Addr;
    use std::process::Command;
    use std::rc::Rc;

    fn client() -> SocketAddrV4 {
        SocketAddrV4::new(Ipv4Addr::new(192, 168, 1, 10), 50_123)
    }

    fn server() -> SocketAddrV4 {
        SocketAddrV4::new(Ipv4Addr::new(192, 168, 1, 20), 44_818)
    }

    fn ms(n: u64) -> Duration {
        Duration::from_millis(n)
    }

    /// The IPv4 header and the transport segment of an emitted frame.
    fn split(frame: &[u8]) -> (&[u8], &[u8]) {
        assert_eq!(&frame[12..14], &[0x08, 0x00], "EtherType IPv4");
        let ip = &frame[ETH_LEN..];
        let ihl = usize::from(ip[0] & 0x0F) * 4;
        let total = usize::from(u16::from_be_bytes([ip[2], ip[3]]));
        assert_eq!(total, ip.len(), "IPv4 total length");
        (&ip[..ihl], &ip[ihl..total])
    }

    /// The sum over the pseudo-header and the segment, checksum included: 0xFFFF when right.
    fn verify_transport(ip: &[u8], segment: &[u8]) -> u16 {
        let mut pseudo = [0u8; 12];
        pseudo[0..8].copy_from_slice(&ip[12..20]);
        pseudo[9] = ip[9];
        pseudo[10..12].copy_from_slice(&(segment.len() as u16).to_be_bytes());
        ones_complement_sum(ones_complement_sum(0, &pseudo), segment)
    }

    /// (seq, ack, flags, payload length) of a TCP frame.
    fn tcp_fields(frame: &[u8]) -> (u32, u32, u8, usize) {
        let (_, tcp) = split(frame);
        let seq = u32::from_be_bytes(tcp[4..8].try_into().unwrap());
        let ack = u32::from_be_bytes(tcp[8..12].try_into().unwrap());
        let data_offset = usize::from(tcp[12] >> 4) * 4;
        (seq, ack, tcp[13], tcp.len() - data_offset)
    }

    #[test]
    fn checksums_verify_over_emitted_bytes() {
        let mut cap = Capture::default();
        // Odd payload lengths exercise the padding of the last byte.
        cap.udp(client(), server(), &[0x63, 0, 0, 0, 0, 1, 2], ms(0));
        cap.tcp_open(client(), server(), ms(1));
        cap.tcp_data(client(), server(), &[0x65, 0, 4, 0, 9], ms(2));
        assert_eq!(cap.len(), 5);
        for Packet { frame, .. } in cap.packets() {
            let (ip, segment) = split(frame);
            assert_eq!(ones_complement_sum(0, ip), 0xFFFF, "IPv4 header checksum");
            assert_eq!(ip[8], TTL);
            assert_eq!(verify_transport(ip, segment), 0xFFFF, "transport checksum");
            assert_eq!(&frame[0..2], &[0x02, 0x00], "destination MAC");
            assert_eq!(&frame[2..6], &ip[16..20], "destination MAC from IPv4");
            assert_eq!(&frame[6..8], &[0x02, 0x00], "source MAC");
            assert_eq!(&frame[8..12], &ip[12..16], "source MAC from IPv4");
        }
        let (ip, udp) = split(&cap.packets()[0].frame);
        assert_eq!(ip[9], PROTO_UDP);
        assert_eq!(&ip[6..8], &[0, 0], "no DF on UDP");
        assert_eq!(u16::from_be_bytes([udp[4], udp[5]]), 15, "UDP length");
        assert_ne!(&udp[6..8], &[0, 0], "UDP checksum present");
        let (ip, tcp) = split(&cap.packets()[4].frame);
        assert_eq!(ip[9], PROTO_TCP);
        assert_eq!(&ip[6..8], &[0x40, 0], "DF on TCP");
        assert_eq!(tcp[12] >> 4, 5, "no options on data segments");
        assert_eq!(u16::from_be_bytes([tcp[14], tcp[15]]), WINDOW);
        // IPv4 identification counts up per packet.
        let ids: Vec<u16> = cap
            .packets()
            .iter()
            .map(|p| u16::from_be_bytes([p.frame[18], p.frame[19]]))
            .collect();
        assert_eq!(ids, vec![0, 1, 2, 3, 4]);
    }

    #[test]
    fn tcp_sequence_numbers_continue() {
        let mut cap = Capture::default();
        cap.tcp_open(client(), server(), ms(0));
        cap.tcp_data(client(), server(), &[1; 28], ms(1));
        cap.tcp_data(server(), client(), &[2; 28], ms(2));
        cap.tcp_data(client(), server(), &[3; 3000], ms(3)); // 1460 + 1460 + 80
        cap.tcp_data(server(), client(), &[4; 10], ms(4));
        cap.tcp_data(server(), client(), &[], ms(5)); // nothing
        cap.tcp_close(client(), server(), ms(6));
        assert_eq!(cap.len(), 3 + 1 + 1 + 3 + 1 + 3);

        let from_client = |frame: &[u8]| frame[6..12] == mac(client());
        let lens: Vec<usize> = cap
            .packets()
            .iter()
            .map(|p| tcp_fields(&p.frame).3)
            .collect();
        assert_eq!(lens, vec![0, 0, 0, 28, 28, 1460, 1460, 80, 10, 0, 0, 0]);

        // next[0]: client's next sequence number, next[1]: server's.
        let mut next: [Option<u32>; 2] = [None, None];
        for (i, Packet { frame, .. }) in cap.packets().iter().enumerate() {
            let (seq, ack, flags, len) = tcp_fields(frame);
            let (me, peer) = if from_client(frame) { (0, 1) } else { (1, 0) };
            if let Some(expected) = next[me] {
                assert_eq!(seq, expected, "seq of packet {i}");
            } else {
                assert_ne!(flags & SYN, 0, "first packet of a side is a SYN");
            }
            if flags & ACK != 0 {
                assert_eq!(Some(ack), next[peer], "ack of packet {i}");
            } else {
                assert_eq!(i, 0, "only the SYN lacks ACK");
            }
            if len > 0 {
                assert_eq!(flags, PSH | ACK, "data flags of packet {i}");
            }
            let consumed = len as u32 + u32::from(flags & SYN != 0) + u32::from(flags & FIN != 0);
            next[me] = Some(seq.wrapping_add(consumed));
        }
        let flags: Vec<u8> = cap
            .packets()
            .iter()
            .map(|p| tcp_fields(&p.frame).2)
            .collect();
        assert_eq!(&flags[..3], &[SYN, SYN | ACK, ACK]);
        assert_eq!(&flags[9..], &[FIN | ACK, FIN | ACK, ACK]);
        assert!(from_client(&cap.packets()[9].frame) && !from_client(&cap.packets()[10].frame));

        // The same run gives the same bytes; a reopened connection starts elsewhere.
        let mut again = Capture::default();
        again.tcp_open(client(), server(), ms(0));
        assert_eq!(again.packets()[0].frame, cap.packets()[0].frame);
        again.tcp_close(server(), client(), ms(1));
        again.tcp_open(client(), server(), ms(2));
        assert_ne!(
            tcp_fields(&again.packets()[6].frame).0,
            tcp_fields(&again.packets()[0].frame).0
        );
    }

    #[test]
    fn data_on_unopened_connection_opens_it() {
        let mut cap = Capture::default();
        cap.tcp_data(client(), server(), &[7; 4], ms(0));
        assert_eq!(cap.len(), 4);
        assert_eq!(tcp_fields(&cap.packets()[0].frame).2, SYN);
    }

    #[test]
    fn write_reads_back() {
        let mut cap = Capture::default();
        cap.tcp_open(client(), server(), ms(0));
        cap.tcp_data(client(), server(), &[1; 2000], ms(1));
        cap.udp(
            client(),
            server(),
            &[0x63, 0],
            Duration::from_micros(1_500_250),
        );
        cap.tcp_close(server(), client(), Duration::from_nanos(2_000_000_007));
        let dir = tempdir("enip_write_reads_back");
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
        assert_eq!(description(&interfaces[0]).as_deref(), Some(SOURCE));
        // pcap-file writes nanoseconds; the interface must say so, or readers take them as µs.
        assert!(interfaces[0]
            .options
            .contains(&InterfaceDescriptionOption::IfTsResol(TSRESOL_NANOS)));
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
        cap.tcp_open(client(), server(), ms(0)); // 3 packets, no label
        let step1 = "tu4-eip@enip cip/encapsulation/short-header step 1: enip raw 65 00 04 00";
        cap.label(Some(step1));
        cap.tcp_data(client(), server(), &[1; 3000], ms(1)); // 3 segments
        cap.tcp_data(server(), client(), &[2; 28], ms(2));
        let step2 = "tu4-eip@enip cip/encapsulation/short-header step 2: enip raw 6F 00 · ü ✓";
        cap.label(Some(step2));
        cap.udp(client(), server(), &[0x63, 0], ms(3));
        cap.label(None);
        cap.tcp_close(client(), server(), ms(4)); // 3 packets, no label again

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
        let mut expected = vec![None; 3];
        expected.extend([Some(step1); 4]);
        expected.push(Some(step2));
        expected.extend([None; 3]);
        assert_eq!(comments, expected);
        // Labels are shared, not copied per packet.
        assert!(Rc::ptr_eq(
            cap.packets()[3].comment.as_ref().unwrap(),
            cap.packets()[6].comment.as_ref().unwrap()
        ));

        // The same capture writes the same bytes.
        let mut again = Vec::new();
        cap.write_to(&mut again).unwrap();
        assert!(again == bytes);
    }

    #[test]
    fn tshark_dissects_enip_cleanly() {
        if Command::new("tshark").arg("--version").output().is_err() {
            eprintln!("SKIPPED tshark_dissects_enip_cleanly: tshark is not on PATH");
            return;
        }
        let mut register = vec![0x65, 0x00, 0x04, 0x00];
        register.extend_from_slice(&[0; 20]);
        register.extend_from_slice(&[0x01, 0x00, 0x00, 0x00]);
        let mut registered = register.clone();
        registered[4..8].copy_from_slice(&[0x01, 0x00, 0x00, 0x00]);
        let mut list_identity = vec![0x63, 0x00];
        list_identity.extend_from_slice(&[0; 22]);
        let udp_server = SocketAddrV4::new(*server().ip(), 44_818);
        let udp_client = SocketAddrV4::new(*client().ip(), 50_124);

        let mut cap = Capture::default();
        cap.label(Some("case a: open"));
        cap.tcp_open(client(), server(), ms(0));
        cap.label(Some("case a step 1: enip raw 65 00 04 00 …"));
        cap.tcp_data(client(), server(), &register, ms(1));
        cap.tcp_data(server(), client(), &registered, ms(2));
        cap.label(Some("case b step 1: ListIdentity über UDP ✓"));
        cap.udp(udp_client, udp_server, &list_identity, ms(3));
        // Class 1 I/O on 2222: CPF with a sequenced address item and a connected data item.
        let io = [
            0x02, 0x00, 0x02, 0x80, 0x08, 0x00, 0x01, 0x00, 0x00, 0x00, 0x05, 0x00, 0x00, 0x00,
            0xB1, 0x00, 0x04, 0x00, 0x05, 0x00, 0xAA, 0xBB,
        ];
        let io_from = SocketAddrV4::new(*client().ip(), 2222);
        let io_to = SocketAddrV4::new(*server().ip(), 2222);
        cap.udp(io_from, io_to, &io, ms(4));
        cap.tcp_close(client(), server(), ms(5));
        let data_frames = [4, 5, 6]; // 1-based frame numbers carrying encapsulation messages
        let io_frame = 7;
        let dir = tempdir("enip_tshark");
        // The name says pcap; tshark reads the pcapng inside regardless.
        let path = dir.join("enip.pcap");
        cap.write(&path).unwrap();

        let checks = [
            "-o",
            "tcp.check_checksum:TRUE",
            "-o",
            "udp.check_checksum:TRUE",
            "-o",
            "ip.check_checksum:TRUE",
        ];
        let tshark = |args: &[&str]| {
            let out = Command::new("tshark")
                .arg("-n")
                .arg("-r")
                .arg(&path)
                .args(checks)
                .args(args)
                .output()
                .expect("run tshark");
            let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
            eprintln!(
                "tshark {args:?}:\n{stdout}{}",
                String::from_utf8_lossy(&out.stderr)
            );
            assert!(out.status.success(), "tshark failed");
            stdout
        };

        let fields = tshark(&[
            "-T",
            "fields",
            "-E",
            "separator=;",
            "-e",
            "frame.number",
            "-e",
            "frame.protocols",
            "-e",
            "ip.checksum.status",
            "-e",
            "tcp.checksum.status",
            "-e",
            "udp.checksum.status",
            "-e",
            "frame.comment",
        ]);
        let rows: Vec<Vec<&str>> = fields.lines().map(|l| l.split(';').collect()).collect();
        assert_eq!(rows.len(), cap.len());
        let comments: Vec<&str> = rows.iter().map(|r| r[5]).collect();
        let mut expected = vec!["case a: open"; 3];
        expected.extend(["case a step 1: enip raw 65 00 04 00 …"; 2]);
        expected.extend(["case b step 1: ListIdentity über UDP ✓"; 5]);
        assert_eq!(comments, expected, "Wireshark shows each packet's label");
        for row in &rows {
            let number: usize = row[0].parse().unwrap();
            let protocols = row[1];
            assert!(protocols.starts_with("eth:ethertype:ip:"), "{row:?}");
            if data_frames.contains(&number) {
                assert!(protocols.contains("enip"), "frame {number}: {protocols}");
            }
            if number == io_frame {
                assert!(protocols.contains("cipio"), "frame {number}: {protocols}");
            }
            // 1 is "Good": verified, not just unverified (2) or bad (0).
            assert_eq!(row[2], "1", "IPv4 checksum of frame {number}");
            assert!(
                row[3] == "1" || row[4] == "1",
                "transport checksum of frame {number}: {row:?}"
            );
        }

        let expert = tshark(&["-q", "-z", "expert"]);
        let mut counted = false;
        for line in expert.lines() {
            let line = line.trim();
            for severity in ["Errors", "Warnings", "Warns"] {
                if let Some(rest) = line.strip_prefix(severity) {
                    let count: u32 = rest
                        .trim()
                        .trim_start_matches('(')
                        .trim_end_matches(')')
                        .parse()
                        .unwrap_or(u32::MAX);
                    assert_eq!(count, 0, "expert {severity}: {expert}");
                }
            }
            counted |= line.starts_with("Chats") || line.starts_with("Notes");
        }
        assert!(counted, "tshark's expert summary was not parsed:\n{expert}");
        std::fs::remove_dir_all(dir).unwrap();
    }
}
