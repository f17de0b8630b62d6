//! Loopback addresses of a test's own. EtherNet/IP keeps its ports fixed (TCP and UDP 44818
//! for encapsulation and ListIdentity, UDP 2222 for class-1 I/O: CIP Vol 2 §2-8.1), so tests
//! that run side by side — in this binary, in another, in another job on the host — each take
//! an address of their own from all of 127.0.0.0/8, found free by binding its ports, instead of
//! a fixed one that another job may hold.

#![allow(dead_code)] // each test binary uses a part

use std::net::{Ipv4Addr, TcpListener, UdpSocket};

/// EtherNet/IP's encapsulation port (TCP and UDP).
const ENCAPSULATION: u16 = 44818;
/// EtherNet/IP's class-1 I/O port (UDP).
const IO: u16 = 2222;

/// Whether this host lets this process bind TCP and UDP 44818 and UDP 2222 on `ip` (nothing
/// holds them there, nor on the wildcard address).
fn enip_ports_free(ip: Ipv4Addr) -> bool {
    TcpListener::bind((ip, ENCAPSULATION)).is_ok()
        && UdpSocket::bind((ip, ENCAPSULATION)).is_ok()
        && UdpSocket::bind((ip, IO)).is_ok()
}

/// A random 127.a.b.c (outside 127.0.0.0/24, where services and other tools take fixed
/// addresses) whose EtherNet/IP ports are free: for a served adapter, a third-party server, or
/// a scanner's `--local` address. Panics after 100 addresses with none free.
pub(crate) fn free_loopback() -> Ipv4Addr {
    for _ in 0..100 {
        let ip = Ipv4Addr::new(
            127,
            fastrand::u8(1..=254),
            fastrand::u8(..),
            fastrand::u8(1..=254),
        );
        if enip_ports_free(ip) {
            return ip;
        }
    }
    panic!("no loopback address with TCP/UDP {ENCAPSULATION} and UDP {IO} free in 100 tries (held on 0.0.0.0?)")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_free_loopback_address_is_free_and_one_in_use_is_not() {
        let ip = free_loopback();
        assert_eq!(ip.octets()[0], 127);
        assert_ne!(ip.octets()[..3], [127, 0, 0]);
        let _held = UdpSocket::bind((ip, IO)).expect("the address was free");
        assert!(!enip_ports_free(ip), "UDP {ip}:{IO} is held here");
        // Not checked: that it is free again once released. Another test of the binary may
        // hold a port on the wildcard address meanwhile, which takes it on every address.
    }
}
