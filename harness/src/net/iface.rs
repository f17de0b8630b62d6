//! Network interfaces by name: index and Ethernet address.

use std::fmt;

use super::LinkError;

/// An Ethernet (MAC) address, IEEE 802 §8.2: six octets in transmission order.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub(crate) struct Mac(pub(crate) [u8; 6]);

#[allow(dead_code)] // for the bindings and benches on raw Ethernet; tested below
impl Mac {
    /// The broadcast address, all ones.
    pub(crate) const BROADCAST: Mac = Mac([0xFF; 6]);

    /// Whether the individual/group bit (bit 0 of the first octet) marks a group address.
    pub(crate) fn is_multicast(self) -> bool {
        self.0[0] & 0x01 != 0
    }

    /// Whether the universal/local bit (bit 1 of the first octet) marks a locally
    /// administered address (the bit an EtherCAT slave controller sets in the source address
    /// of every frame it forwards, ETG.1000.4 §5).
    pub(crate) fn is_local(self) -> bool {
        self.0[0] & 0x02 != 0
    }
}

impl fmt::Display for Mac {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let [a, b, c, d, e, g] = self.0;
        write!(f, "{a:02x}:{b:02x}:{c:02x}:{d:02x}:{e:02x}:{g:02x}")
    }
}

impl fmt::Debug for Mac {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(self, f)
    }
}

/// A network interface of this host.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Interface {
    /// Its name (`eth0`, `veth-h3a`).
    pub(crate) name: String,
    /// Its kernel index.
    pub(crate) index: u32,
    /// Its Ethernet address.
    pub(crate) mac: Mac,
    /// Whether it is administratively up.
    pub(crate) up: bool,
}

/// The interface named `name`.
pub(crate) fn interface(name: &str) -> Result<Interface, LinkError> {
    Interface::from_pnet(&lookup(name)?)
}

/// pnet's view of the interface named `name`, which [`super::RawLink`] needs to open it.
pub(super) fn lookup(name: &str) -> Result<pnet_datalink::NetworkInterface, LinkError> {
    let all = pnet_datalink::interfaces();
    match all.iter().find(|i| i.name == name) {
        Some(i) => Ok(i.clone()),
        None => Err(LinkError::NoSuchInterface {
            name: name.to_string(),
            known: all.into_iter().map(|i| i.name).collect(),
        }),
    }
}

impl Interface {
    pub(super) fn from_pnet(i: &pnet_datalink::NetworkInterface) -> Result<Interface, LinkError> {
        let mac = i.mac.ok_or_else(|| LinkError::NoMac {
            iface: i.name.clone(),
        })?;
        Ok(Interface {
            name: i.name.clone(),
            index: i.index,
            mac: Mac(mac.octets()),
            up: i.is_up(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mac_bits_and_display() {
        // SOEM's primary source address 01:01:01:01:01:01 (a group address by its first bit),
        // and the same as an ESC forwards it: bit 1 set, 03:01:01:01:01:01.
        let soem = Mac([0x01, 0x01, 0x01, 0x01, 0x01, 0x01]);
        assert!(soem.is_multicast() && !soem.is_local());
        let back = Mac([0x03, 0x01, 0x01, 0x01, 0x01, 0x01]);
        assert!(back.is_local());
        assert_eq!(back.to_string(), "03:01:01:01:01:01");
        assert_eq!(format!("{:?}", Mac::BROADCAST), "ff:ff:ff:ff:ff:ff");
    }

    #[test]
    fn unknown_interface_is_named_with_the_known_ones() {
        match interface("no-such-if0") {
            Err(LinkError::NoSuchInterface { name, known }) => {
                assert_eq!(name, "no-such-if0");
                assert!(known.iter().any(|k| k == "lo"), "{known:?}");
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn loopback_is_found_with_its_index() {
        let lo = interface("lo").expect("every Linux host has lo");
        assert_eq!(lo.mac, Mac::default());
        assert!(lo.index >= 1);
    }
}
