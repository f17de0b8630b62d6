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
    /// EtherNet/IP encapsulation and CIP requests can be sent as such.
    Ethernetip,
    /// The DUT is freshly powered on for every case: drive in its power-on state, counters
    /// (e.g. the actual position) at zero. The embedded simulator is opened anew per case; a
    /// device on the network is one persistent device, which the harness cannot power-cycle.
    PowerOn,
    /// The DUT's parameters are at their factory settings for every case. The embedded
    /// simulator is; a device on the network carries its site's settings (its IP address
    /// first of all), which the harness neither knows nor may overwrite.
    FactoryState,
    /// The DUT may be given a new IP address (P160–P165 or P850–P856 and an Identity Reset):
    /// the simulator keeps its sockets whatever its parameters say; a device on the network
    /// would move to the new address and the harness would lose it.
    Readdressing,
}

impl Capability {
    /// All capabilities.
    pub(crate) const ALL: [Capability; 9] = [
        Capability::ParameterAccess,
        Capability::ParameterChannel,
        Capability::ProcessData,
        Capability::FaultInjection,
        Capability::Observe,
        Capability::Ethernetip,
        Capability::PowerOn,
        Capability::FactoryState,
        Capability::Readdressing,
    ];

    /// Name as suites write it.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Capability::ParameterAccess => "parameter-access",
            Capability::ParameterChannel => "parameter-channel",
            Capability::ProcessData => "process-data",
            Capability::FaultInjection => "fault-injection",
            Capability::Observe => "observe",
            Capability::Ethernetip => "ethernetip",
            Capability::PowerOn => "power-on",
            Capability::FactoryState => "factory-state",
            Capability::Readdressing => "readdressing",
        }
    }

    /// Parses a suite's name.
    pub(crate) fn from_name(s: &str) -> Option<Capability> {
        Capability::ALL.into_iter().find(|c| c.name() == s)
    }
}

impl fmt::Display for Capability {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// How the harness talks to the DUT.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum BindingKind {
    /// PPO telegrams: the NORD parameter channel and process data (data records 100..108).
    Ppo,
    /// EtherNet/IP: explicit messages to the parameter classes and a class-1 I/O connection.
    Enip,
}

/// A device profile: the product, how many inverters sit behind it, and the binding.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Profile {
    /// The NORD product; `None` for the generic `cip` profile, any maker's EtherNet/IP
    /// adapter, against which only the protocol's own cases run.
    pub(crate) product: Option<Product>,
    /// Inverters behind the interface (FI 1..=n).
    pub(crate) inverters: u8,
    /// The binding the cases run over.
    pub(crate) binding: BindingKind,
}

impl Profile {
    /// The built-in PPO profile of a product, with the product's maximum inverter count.
    pub(crate) fn builtin(product: Product) -> Profile {
        Profile {
            product: Some(product),
            inverters: product.max_inverters(),
            binding: BindingKind::Ppo,
        }
    }

    /// The EtherNet/IP profile of a product that speaks EtherNet/IP.
    pub(crate) fn enip(product: Product) -> Option<Profile> {
        proto::nord::eip::identity(product).map(|_| Profile {
            binding: BindingKind::Enip,
            ..Profile::builtin(product)
        })
    }

    /// The generic profile `cip`: an EtherNet/IP adapter of any maker (`run --dut` only).
    pub(crate) fn cip() -> Profile {
        Profile {
            product: None,
            inverters: 0,
            binding: BindingKind::Enip,
        }
    }

    /// Every built-in product profile: each product over PPO, and each EtherNet/IP product
    /// over EtherNet/IP (`<product>@enip`), so every case runs over every binding it can.
    pub(crate) fn all() -> Vec<Profile> {
        let ppo = Product::ALL.into_iter().map(Profile::builtin);
        let enip = Product::ALL.into_iter().filter_map(Profile::enip);
        ppo.chain(enip).collect()
    }

    /// The NORD product, or why the generic profile has none.
    pub(crate) fn nord(&self) -> Result<Product, String> {
        self.product.ok_or_else(|| {
            "profile `cip` stands for any maker's EtherNet/IP adapter, not a NORD product".into()
        })
    }

    /// Profile name (`sk550p`, `tu3-eip`, …, `tu3-eip@enip`, `cip`).
    pub(crate) fn name(&self) -> &'static str {
        match (self.binding, self.product) {
            (_, None) => "cip",
            (BindingKind::Ppo, Some(p)) => p.name(),
            (BindingKind::Enip, Some(Product::Sk550p)) => "sk550p@enip",
            (BindingKind::Enip, Some(Product::Tu3Eip)) => "tu3-eip@enip",
            (BindingKind::Enip, Some(Product::Tu4Eip)) => "tu4-eip@enip",
            (BindingKind::Enip, Some(Product::Cu4Eip)) => "cu4-eip@enip",
            (BindingKind::Enip, Some(p)) => p.name(),
        }
    }

    /// Looks a built-in profile up by name; the error lists the valid names.
    pub(crate) fn by_name(name: &str) -> Result<Profile, String> {
        let known = || Profile::all().into_iter().chain([Profile::cip()]);
        known().find(|p| p.name() == name).ok_or_else(|| {
            let names: Vec<&str> = known().map(|p| p.name()).collect();
            format!(
                "unknown profile `{name}` (built-in profiles: {})",
                names.join(", ")
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_capability_parses_from_its_name() {
        for c in Capability::ALL {
            assert_eq!(Capability::from_name(c.name()), Some(c));
        }
        assert_eq!(Capability::from_name("power-on"), Some(Capability::PowerOn));
        assert_eq!(
            Capability::from_name("factory-state"),
            Some(Capability::FactoryState)
        );
        assert_eq!(Capability::from_name("powered-on"), None);
    }
}
