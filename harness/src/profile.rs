//! Device profiles: which product a DUT is and what the harness can do with it.
//!
//! One built-in profile per product. The profile decides which cases apply (a case lists the
//! profiles its statement is about) and the DUT's capabilities decide which steps can run.

use proto::nord::Product;
use std::fmt;

/// Something a case may need from the DUT.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub(crate) enum Capability {
    /// Parameters can be read and written (over any protocol).
    ParameterAccess,
    /// The NORD parameter channel (PKW telegrams, order labels, error numbers) is answered.
    ParameterChannel,
    /// Control/status words and setpoints/actual values are exchanged.
    ProcessData,
    /// The harness can raise an inverter error (only the simulator).
    FaultInjection,
    /// The harness can see internal state: LEDs, status-machine state, EEPROM writes.
    Observe,
    /// The DUT is freshly powered on for every case: drive in its power-on state, counters
    /// (e.g. the actual position) at zero. The embedded simulator is opened anew per case; a
    /// device on the network is one persistent device, which the harness cannot power-cycle.
    PowerOn,
    /// The DUT's parameters are at their factory settings for every case. The embedded
    /// simulator is; a device on the network carries its site's settings (its IP address
    /// first of all), which the harness neither knows nor may overwrite.
    FactoryState,
    /// The CANopen frames the bus interface exchanges with its inverters on the system bus can
    /// be watched (`observe: { what: system-bus }`): the embedded simulator's gateway, or a
    /// device on the network whose system bus the run taps (`--tap socketcand://…`).
    SystemBus,
    /// The DUT may be given a new address (P160–P165 or P850–P856 and a reset): the simulator
    /// keeps its link whatever its parameters say; a device on the network would move to the
    /// new address and the harness would lose it.
    Readdressing,
    /// The bus's own steps (a registry name: `enip`, `ecat`) can be sent as such.
    Bus(&'static str),
}

impl Capability {
    /// The capabilities that are not a bus.
    pub(crate) const GENERAL: [Capability; 9] = [
        Capability::ParameterAccess,
        Capability::ParameterChannel,
        Capability::ProcessData,
        Capability::FaultInjection,
        Capability::Observe,
        Capability::PowerOn,
        Capability::FactoryState,
        Capability::Readdressing,
        Capability::SystemBus,
    ];

    /// The general capabilities and `bus`'s steps: what a bus's embedded simulator offers
    /// when it answers the parameter channel too.
    pub(crate) const fn general_and(bus: &'static str) -> [Capability; 10] {
        let g = Capability::GENERAL;
        [
            g[0],
            g[1],
            g[2],
            g[3],
            g[4],
            g[5],
            g[6],
            g[7],
            g[8],
            Capability::Bus(bus),
        ]
    }

    /// Name as suites write it (a bus capability is the bus's name).
    pub(crate) fn name(self) -> &'static str {
        match self {
            Capability::ParameterAccess => "parameter-access",
            Capability::ParameterChannel => "parameter-channel",
            Capability::ProcessData => "process-data",
            Capability::FaultInjection => "fault-injection",
            Capability::Observe => "observe",
            Capability::PowerOn => "power-on",
            Capability::FactoryState => "factory-state",
            Capability::Readdressing => "readdressing",
            Capability::SystemBus => "system-bus",
            Capability::Bus(name) => name,
        }
    }
}

impl fmt::Display for Capability {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The name of the generic profiles: `any`, and `any@<bus>` once the bus is known.
pub(crate) const ANY: &str = "any";

/// A device profile: the product, how many inverters sit behind it, and the bus its cases run
/// over.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Profile {
    /// `sk550p` (the PPO link), `sk550p@ecat` (a bus), a generic profile of a bus
    /// (`any@ecat`), or `any` before `--dut` names the bus.
    name: String,
    /// The NORD product; `None` for a generic profile, any maker's device of a bus, against
    /// which only the bus's own cases run.
    pub(crate) product: Option<Product>,
    /// Inverters behind the interface (FI 1..=n).
    pub(crate) inverters: u8,
    /// The bus (a registry name); `None` for the PPO link: the NORD parameter channel and
    /// process data in data records 100..108.
    pub(crate) bus: Option<&'static str>,
}

impl Profile {
    /// The built-in PPO profile of a product, with the product's maximum inverter count.
    pub(crate) fn builtin(product: Product) -> Profile {
        Profile {
            name: product.name().to_string(),
            product: Some(product),
            inverters: product.max_inverters(),
            bus: None,
        }
    }

    /// A product over a bus: `<product>@<bus>`.
    pub(crate) fn on_bus(product: Product, bus: &'static str) -> Profile {
        Profile {
            name: format!("{}@{bus}", product.name()),
            bus: Some(bus),
            ..Profile::builtin(product)
        }
    }

    /// A generic profile of a bus: any maker's device (`run --dut` only).
    pub(crate) fn generic(name: &str, bus: &'static str) -> Profile {
        Profile {
            name: name.to_string(),
            product: None,
            inverters: 0,
            bus: Some(bus),
        }
    }

    /// The NORD product, or why a generic profile has none.
    pub(crate) fn nord(&self) -> Result<Product, String> {
        self.product.ok_or_else(|| {
            format!(
                "profile `{}` stands for any maker's device, not a NORD product",
                self.name
            )
        })
    }

    /// Profile name (`sk550p`, `tu3-eip@enip`, `sk550p@ecat`, `any@enip`).
    pub(crate) fn name(&self) -> &str {
        &self.name
    }
}

/// The NORD product a `serve` command's `--profile` names: a product (`sk550p`) or a product
/// over a bus (`sk550p@ecat`). Serving needs no list of the buses: the bus is the command's
/// own, and the command checks that the product speaks it.
pub(crate) fn product_named(name: &str) -> Result<Product, String> {
    let product = name.split_once('@').map_or(name, |(p, _)| p);
    if product == ANY || name == "cip" {
        return Err(format!(
            "profile `{name}` stands for any maker's device, not a NORD product"
        ));
    }
    Product::from_name(product).ok_or_else(|| {
        let names: Vec<&str> = Product::ALL.into_iter().map(Product::name).collect();
        format!("unknown profile `{name}` (products: {})", names.join(", "))
    })
}

/// Every profile and capability a run may name: each product over PPO, and each bus's NORD
/// profiles and its generic one (`any@<bus>`). It is built from the buses' entries by whoever
/// holds their list (`crate::bus::catalog`) and handed down, so that nothing here reads the list.
#[derive(Debug, Clone)]
pub(crate) struct Catalog {
    /// The bus names, in report order.
    buses: Vec<&'static str>,
    /// Each bus's NORD profiles, then its generic one, bus after bus.
    of_buses: Vec<Profile>,
}

impl Catalog {
    /// The catalog of these buses: each with its NORD profiles, in report order.
    pub(crate) fn new(buses: impl IntoIterator<Item = (&'static str, Vec<Profile>)>) -> Catalog {
        let mut names = Vec::new();
        let mut of_buses = Vec::new();
        for (bus, profiles) in buses {
            names.push(bus);
            of_buses.extend(profiles);
            of_buses.push(Profile::generic(&format!("{ANY}@{bus}"), bus));
        }
        Catalog {
            buses: names,
            of_buses,
        }
    }

    /// Every capability: the general ones and one per bus.
    pub(crate) fn capabilities(&self) -> Vec<Capability> {
        let buses = self.buses.iter().map(|b| Capability::Bus(b));
        Capability::GENERAL.into_iter().chain(buses).collect()
    }

    /// The capability a suite names.
    pub(crate) fn capability(&self, name: &str) -> Option<Capability> {
        self.capabilities().into_iter().find(|c| c.name() == name)
    }

    /// The default run's profiles: each product over PPO, and each product over each bus it
    /// speaks (`<product>@<bus>`), so every case runs over every binding it can.
    pub(crate) fn all(&self) -> Vec<Profile> {
        let ppo = Product::ALL.into_iter().map(Profile::builtin);
        let nord = self.of_buses.iter().filter(|p| p.product.is_some());
        ppo.chain(nord.cloned()).collect()
    }

    /// Looks a built-in profile up by name; the error lists the valid names. `any` is any
    /// maker's device of the bus `--dut` names ([`Catalog::over`] makes it `any@<bus>`);
    /// `cip` is `any@enip`, its name before every bus had a generic profile.
    pub(crate) fn by_name(&self, name: &str) -> Result<Profile, String> {
        match name {
            ANY => {
                return Ok(Profile {
                    name: ANY.to_string(),
                    product: None,
                    inverters: 0,
                    bus: None,
                })
            }
            "cip" => return self.by_name("any@enip"),
            _ => {}
        }
        self.known().find(|p| p.name() == name).ok_or_else(|| {
            format!(
                "unknown profile `{name}` (built-in profiles: {}; `{ANY}` with `--dut`)",
                self.names().join(", ")
            )
        })
    }

    /// Every built-in profile: each product over PPO, then each bus's NORD profiles and its
    /// generic one.
    fn known(&self) -> impl Iterator<Item = Profile> + '_ {
        Product::ALL
            .into_iter()
            .map(Profile::builtin)
            .chain(self.of_buses.iter().cloned())
    }

    /// The names of every built-in profile ([`Catalog::by_name`] takes each), for help and
    /// messages.
    pub(crate) fn names(&self) -> Vec<String> {
        self.known().map(|p| p.name).collect()
    }

    /// The profiles named on the command line (`--profile`, in the order given), each once:
    /// a name given again, or another name of one profile (`cip` and `any@enip`), is dropped
    /// and returned apart so the caller can say so. The error lists the valid names.
    pub(crate) fn by_names(&self, names: &[String]) -> Result<(Vec<Profile>, Vec<String>), String> {
        let mut chosen: Vec<Profile> = Vec::new();
        let mut repeated = Vec::new();
        for n in names {
            let p = self.by_name(n)?;
            if chosen.iter().any(|q| q.name == p.name) {
                repeated.push(n.clone());
            } else {
                chosen.push(p);
            }
        }
        Ok((chosen, repeated))
    }

    /// `profile`'s product over `bus`, if the product speaks it; `any` is the bus's generic
    /// profile, and a generic profile of another bus is none.
    pub(crate) fn over(&self, profile: &Profile, bus: &'static str) -> Option<Profile> {
        if profile.product.is_none() && profile.bus.is_some_and(|b| b != bus) {
            return None;
        }
        let found = self
            .of_buses
            .iter()
            .find(|p| p.bus == Some(bus) && p.product == profile.product)?;
        Some(Profile {
            inverters: if found.product.is_some() {
                profile.inverters
            } else {
                found.inverters
            },
            ..found.clone()
        })
    }
}
#[cfg(test)]
mod tests {
    use super::*;
    use crate::buses::{catalog, BUSES};

    #[test]
    fn every_capability_parses_from_its_name() {
        for c in catalog().capabilities() {
            assert_eq!(catalog().capability(c.name()), Some(c));
        }
        assert_eq!(catalog().capability("power-on"), Some(Capability::PowerOn));
        assert_eq!(
            catalog().capability("factory-state"),
            Some(Capability::FactoryState)
        );
        assert_eq!(catalog().capability("powered-on"), None);
        assert_eq!(catalog().capability("ecat"), Some(Capability::Bus("ecat")));
    }

    #[test]
    fn a_profile_named_twice_is_chosen_once_in_the_order_given() {
        let names = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let (chosen, repeated) = catalog()
            .by_names(&names(&[
                "sk550p",
                "tu3-eip@enip",
                "sk550p",
                "cip",
                "any@enip",
            ]))
            .unwrap();
        let chosen: Vec<&str> = chosen.iter().map(Profile::name).collect();
        assert_eq!(chosen, ["sk550p", "tu3-eip@enip", "any@enip"]);
        assert_eq!(repeated, ["sk550p", "any@enip"]);
        let e = catalog()
            .by_names(&names(&["sk550p", "sk999"]))
            .unwrap_err();
        assert!(e.contains("unknown profile `sk999`"), "{e}");
    }

    #[test]
    fn any_is_the_generic_profile_of_the_bus_the_dut_names() {
        let any = catalog().by_name("any").unwrap();
        for bus in BUSES {
            let p = catalog().over(&any, bus.name).unwrap();
            assert_eq!(p.name(), format!("any@{}", bus.name));
            assert_eq!((p.product, p.bus), (None, Some(bus.name)));
            assert_eq!(catalog().by_name(p.name()).unwrap(), p);
        }
        assert_eq!(catalog().by_name("cip").unwrap().name(), "any@enip");
        assert_eq!(
            catalog().over(&catalog().by_name("any@ecat").unwrap(), "enip"),
            None
        );
        let nord = catalog()
            .over(&catalog().by_name("sk550p").unwrap(), "ecat")
            .unwrap();
        assert_eq!(nord.name(), "sk550p@ecat");
        assert!(!catalog().all().iter().any(|p| p.product.is_none()));
    }
}
