//! What the served devices' UDP endpoints share: the interface's IPv4 address to bind to, and
//! which socket errors end one exchange rather than the socket.

use std::net::{IpAddr, Ipv4Addr};

/// The first IPv4 address of interface `name` and its prefix length, if it has one.
pub(crate) fn ipv4_of(name: &str) -> Option<(Ipv4Addr, u8)> {
    pnet_datalink::interfaces()
        .into_iter()
        .find(|i| i.name == name)?
        .ips
        .iter()
        .find_map(|n| match n.ip() {
            IpAddr::V4(a) => Some((a, n.prefix())),
            IpAddr::V6(_) => None,
        })
}

/// Every IPv4 address of interface `name` with its prefix length, in the order the kernel
/// lists them; `None` when there is no such interface.
pub(crate) fn ipv4s_of(name: &str) -> Option<Vec<(Ipv4Addr, u8)>> {
    let iface = pnet_datalink::interfaces()
        .into_iter()
        .find(|i| i.name == name)?;
    Some(
        iface
            .ips
            .iter()
            .filter_map(|n| match n.ip() {
                IpAddr::V4(a) => Some((a, n.prefix())),
                IpAddr::V6(_) => None,
            })
            .collect(),
    )
}

/// A UDP error that ends one exchange, not the socket: the read timeout, an interrupted call,
/// a peer gone (ICMP port unreachable), a network not reachable just now.
pub(crate) fn transient(e: &std::io::Error) -> bool {
    use std::io::ErrorKind as K;
    matches!(
        e.kind(),
        K::WouldBlock
            | K::TimedOut
            | K::Interrupted
            | K::ConnectionRefused
            | K::ConnectionReset
            | K::HostUnreachable
            | K::NetworkUnreachable
            | K::NetworkDown
    )
}
