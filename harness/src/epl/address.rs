//! The POWERLINK subnet on a network interface: a controlled node N is addressed at
//! 192.168.100.N (BU 0620 §3.7.3, BU 2200 §5.2.5; DS 301's class C network 192.168.100.0/24),
//! the managing node at 192.168.100.240. SDO over UDP/IP goes to the node's address, so
//! `harness serve epl` binds that one of the interface's addresses, and `harness run --dut
//! epl://IFACE` needs an address of the interface on that subnet before it sends anything.
//! Both decide from the addresses the interface has (`crate::net::udp::ipv4s_of`), here, and
//! refuse with the interface and its addresses named.

use std::net::Ipv4Addr;

use proto::nord::epl as def;

/// `192.168.100.5/24, 10.0.0.1/8`, or `no IPv4 address`.
fn listed(have: &[(Ipv4Addr, u8)]) -> String {
    if have.is_empty() {
        return "no IPv4 address".into();
    }
    let v: Vec<String> = have.iter().map(|(a, p)| format!("{a}/{p}")).collect();
    v.join(", ")
}

/// Whether `addr/prefix`'s subnet holds `ip`.
fn holds((addr, prefix): (Ipv4Addr, u8), ip: Ipv4Addr) -> bool {
    let mask = u32::MAX
        .checked_shl(32 - u32::from(prefix.min(32)))
        .unwrap_or(0);
    u32::from(addr) & mask == u32::from(ip) & mask
}

/// Where `harness serve epl` serves SDO over UDP/IP for node `node` on `iface`, which has
/// the addresses `have`: its 192.168.100.`node` (wherever the kernel lists it); `None` when
/// the interface has no IPv4 address at all (raw Ethernet only: SDO over ASnd). An interface
/// with addresses but not the node's is refused: an MN would send the node's datagrams to
/// 192.168.100.`node` and never reach it.
pub(crate) fn node_address(
    iface: &str,
    node: u8,
    have: &[(Ipv4Addr, u8)],
) -> Result<Option<Ipv4Addr>, String> {
    let own = def::ip_address(node);
    if have.is_empty() {
        return Ok(None);
    }
    if have.iter().any(|(a, _)| *a == own) {
        return Ok(Some(own));
    }
    let other = have
        .iter()
        .map(|(a, _)| a.octets())
        .find(|o| o[..3] == own.octets()[..3] && (1..=239).contains(&o[3]))
        .map_or(String::new(), |o| {
            format!(", or serve node {} (`--node-id {}`)", o[3], o[3])
        });
    Err(format!(
        "{iface} has {} but not {own}, node {node}'s address (BU 0620 §3.7.3: 192.168.100.<node id>), where an MN sends its SDO over UDP/IP: give it that address (`ip addr add {own}/24 dev {iface}`){other}",
        listed(have)
    ))
}

/// Whether the harness as MN on `iface` (addresses `have`) reaches node `node` over UDP: the
/// interface needs an address whose subnet holds 192.168.100.`node` and is not the node's
/// own (the kernel would deliver the datagrams to this host). The error names the interface,
/// its addresses and the way out.
pub(crate) fn check_mn(iface: &str, node: u8, have: &[(Ipv4Addr, u8)]) -> Result<(), String> {
    let own = def::ip_address(node);
    let usable = have.iter().any(|&(a, p)| a != own && holds((a, p), own));
    if usable {
        return Ok(());
    }
    let why = if have.iter().any(|(a, _)| *a == own) {
        format!("{own} is node {node}'s own address (BU 0620 §3.7.3): datagrams to it would stay on this host")
    } else {
        format!(
            "no address on the POWERLINK subnet that holds node {node}'s {own} (BU 0620 §3.7.3)"
        )
    };
    Err(format!(
        "{iface} has {}: {why}; the harness (MN) sends SDO over UDP/IP there. Give {iface} the MN's address (`ip addr add {}/24 dev {iface}`)",
        listed(have),
        def::ip_address(proto::epl::MN_NODE_ID)
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    const fn ip(d: u8) -> Ipv4Addr {
        Ipv4Addr::new(192, 168, 100, d)
    }

    #[test]
    fn the_node_serves_on_its_own_address_wherever_it_is_listed() {
        let first = (Ipv4Addr::new(10, 0, 0, 7), 8);
        assert_eq!(node_address("veth0", 5, &[]), Ok(None));
        assert_eq!(
            node_address("veth0", 5, &[first, (ip(5), 24)]),
            Ok(Some(ip(5)))
        );
        assert_eq!(node_address("veth0", 1, &[(ip(1), 32)]), Ok(Some(ip(1))));
        let e = node_address("veth0", 5, &[first]).unwrap_err();
        assert!(
            e.starts_with("veth0 has 10.0.0.7/8 but not 192.168.100.5"),
            "{e}"
        );
        assert!(e.contains("ip addr add 192.168.100.5/24 dev veth0"), "{e}");
        assert!(!e.contains("--node-id"), "{e}");
        // An address on the subnet names the node id it would serve.
        let e = node_address("veth0", 5, &[first, (ip(7), 24)]).unwrap_err();
        assert!(e.contains("10.0.0.7/8, 192.168.100.7/24"), "{e}");
        assert!(e.contains("`--node-id 7`"), "{e}");
        // The MN's own address names none.
        let e = node_address("veth0", 5, &[(ip(240), 24)]).unwrap_err();
        assert!(!e.contains("--node-id"), "{e}");
    }

    #[test]
    fn the_mn_needs_an_address_on_the_nodes_subnet_that_is_not_the_nodes() {
        assert_eq!(check_mn("veth1", 1, &[(ip(240), 24)]), Ok(()));
        assert_eq!(
            check_mn("veth1", 7, &[(Ipv4Addr::new(10, 0, 0, 1), 8), (ip(2), 16)]),
            Ok(())
        );
        let e = check_mn("veth1", 1, &[]).unwrap_err();
        assert!(
            e.starts_with("veth1 has no IPv4 address: no address on the POWERLINK subnet"),
            "{e}"
        );
        assert!(
            e.contains("ip addr add 192.168.100.240/24 dev veth1"),
            "{e}"
        );
        let e = check_mn("veth1", 1, &[(Ipv4Addr::new(10, 1, 2, 3), 24)]).unwrap_err();
        assert!(e.starts_with("veth1 has 10.1.2.3/24: no address"), "{e}");
        // On the subnet, but a /32 whose subnet does not hold the node.
        assert!(check_mn("veth1", 1, &[(ip(240), 32)]).is_err());
        let e = check_mn("veth1", 1, &[(ip(1), 24)]).unwrap_err();
        assert!(e.contains("node 1's own address"), "{e}");
    }

    #[test]
    fn subnets_hold_what_their_prefix_says() {
        assert!(holds((ip(240), 24), ip(1)));
        assert!(!holds((ip(240), 25), ip(1)));
        assert!(holds((Ipv4Addr::new(1, 2, 3, 4), 0), ip(1)));
        assert!(holds((ip(1), 32), ip(1)));
    }
}
