//! The list of the buses the harness speaks, in report order. Only the command line (and the
//! library's entry points for tests and benches) reads it; everything below is handed the list
//! (`&[&Bus]`) or what is built from it ([`crate::profile::Catalog`],
//! [`crate::suite::Vocabulary`]), so no shared module reaches up into the buses' folders.

use crate::bus::Bus;
#[cfg(test)]
use crate::{profile::Catalog, suite::Vocabulary};

/// Every bus, in report order.
pub(crate) const BUSES: &[&Bus] = &[
    &crate::enip::BUS,
    &crate::ecat::BUS,
    &crate::epl::BUS,
    &crate::pnio::BUS,
    &crate::can::BUS,
];

/// The profiles and capabilities of every bus, for tests.
#[cfg(test)]
pub(crate) fn catalog() -> Catalog {
    crate::bus::catalog(BUSES)
}

/// What the suite loader knows of every bus, for tests.
#[cfg(test)]
pub(crate) fn vocabulary() -> Vocabulary {
    crate::bus::vocabulary(BUSES)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bus::{by_url, description, urls};

    #[test]
    fn names_and_urls_resolve_through_the_registry() {
        assert_eq!(
            crate::bus::by_name(BUSES, "enip").map(|b| b.title),
            Some("EtherNet/IP")
        );
        assert_eq!(
            crate::bus::by_name(BUSES, "ecat").map(|b| b.title),
            Some("EtherCAT")
        );
        let (bus, _, target) = by_url(BUSES, "ecat://veth0").unwrap();
        assert_eq!((bus.name, target), ("ecat", "veth0"));
        assert!(by_url(BUSES, "ecat://")
            .unwrap_err()
            .contains("nothing after"));
        let (bus, scheme, target) = by_url(BUSES, "socketcand://127.0.0.1/can0").unwrap();
        assert_eq!(
            (bus.name, scheme, target),
            ("can", "socketcand", "127.0.0.1/can0")
        );
        let e = by_url(BUSES, "lin://x").unwrap_err();
        assert!(e.contains("unknown scheme `lin://`"), "{e}");
        assert!(e.contains("enip://, ecat://"), "{e}");
        assert!(by_url(BUSES, "veth0").unwrap_err().contains("give a URL"));
    }

    #[test]
    fn every_profile_of_a_bus_names_the_bus() {
        for bus in BUSES {
            for p in (bus.profiles)() {
                assert_eq!(p.bus, Some(bus.name), "{}", p.name());
                if p.product.is_some() {
                    assert!(
                        p.name().ends_with(&format!("@{}", bus.name)),
                        "{}",
                        p.name()
                    );
                }
            }
        }
    }

    #[test]
    fn every_bus_url_starts_with_its_scheme() {
        for bus in BUSES {
            let scheme = bus.url.split("://").next().unwrap_or_default();
            assert!(
                scheme == bus.name || bus.schemes.contains(&scheme),
                "{}",
                bus.url
            );
            assert_eq!(by_url(BUSES, bus.url).unwrap().0.name, bus.name);
            assert!(urls(BUSES).contains(bus.url));
        }
    }

    #[test]
    fn description_formats_are_found_by_name() {
        assert_eq!(description(BUSES, "eds", None).unwrap().0.name, "enip");
        assert_eq!(
            description(BUSES, "eds", Some("can")).unwrap().0.name,
            "can"
        );
        assert_eq!(description(BUSES, "gsdml", None).unwrap().0.name, "pnio");
        let e = description(BUSES, "xyz", None).unwrap_err();
        assert!(e.contains("known: eds (enip), esi (ecat)"), "{e}");
        assert!(e.contains("eds (can)"), "{e}");
        assert!(description(BUSES, "esi", Some("can")).is_err());
    }
}
