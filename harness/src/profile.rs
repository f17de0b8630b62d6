//! Device profiles: which product a DUT is and what the harness can do with it.
//!
//! One built-in profile per product. The profile decides which cases apply (a case lists the
//! profiles its statement is about) and the DUT's capabilities decide which steps can run.

use proto::nord::Product;
use std::fmt;

/// Something a case may need from the DUT.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub(crate) enum Capability {
    /// Parameter orders (PKW) are answered.
    ParameterChannel,
    /// Control/status words and setpoints/actual values are exchanged.
    ProcessData,
    /// The harness can raise an inverter error (only the simulator).
    FaultInjection,
    /// The harness can see internal state: LEDs, status-machine state, EEPROM writes.
    Observe,
}

impl Capability {
    /// All capabilities.
    pub(crate) const ALL: [Capability; 4] = [
        Capability::ParameterChannel,
        Capability::ProcessData,
        Capability::FaultInjection,
        Capability::Observe,
    ];

    /// Name as suites write it.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Capability::ParameterChannel => "parameter-channel",
            Capability::ProcessData => "process-data",
            Capability::FaultInjection => "fault-injection",
            Capability::Observe => "observe",
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

/// A device profile: the product and how many inverters sit behind it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Profile {
    /// The product.
    pub(crate) product: Product,
    /// Inverters behind the interface (FI 1..=n).
    pub(crate) inverters: u8,
}

impl Profile {
    /// The built-in profile of a product, with the product's maximum inverter count.
    pub(crate) fn builtin(product: Product) -> Profile {
        Profile {
            product,
            inverters: product.max_inverters(),
        }
    }

    /// Every built-in profile.
    pub(crate) fn all() -> Vec<Profile> {
        Product::ALL.into_iter().map(Profile::builtin).collect()
    }

    /// Profile name (`sk550p`, `tu3-eip`, …).
    pub(crate) fn name(&self) -> &'static str {
        self.product.name()
    }

    /// Looks a built-in profile up by name; the error lists the valid names.
    pub(crate) fn by_name(name: &str) -> Result<Profile, String> {
        Product::from_name(name)
            .map(Profile::builtin)
            .ok_or_else(|| {
                let names: Vec<&str> = Product::ALL.iter().map(|p| p.name()).collect();
                format!(
                    "unknown profile `{name}` (built-in profiles: {})",
                    names.join(", ")
                )
            })
    }
}
