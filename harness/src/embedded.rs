//! The embedded DUT: a fresh simulator in-process for every case, behind the binding of the
//! profile's bus (or the PPO link), on a virtual clock (deterministic, instant). It opens a bus
//! through the bus's entry, from the list of buses it is handed.

use crate::binding::channel::Channel;
use crate::binding::simulator::{ppo_dut, sim_firmware};
use crate::binding::{Binding, DutFactory, OpenError};
use crate::bus::Bus;
use crate::profile::Profile;
use sim::device::Firmware;

/// Opens a fresh simulator per case, behind the profile's binding: the PPO link, or the bus's
/// own binding; a bus's frames go to the tap when there is one.
pub(crate) struct EmbeddedFactory {
    /// The buses whose profiles it opens.
    buses: &'static [&'static Bus],
    /// What the buses' bindings may use.
    pub(crate) context: crate::bus::Embedded,
}

impl EmbeddedFactory {
    /// A factory of the embedded simulator over `buses` (and the PPO link).
    pub(crate) fn new(buses: &'static [&'static Bus]) -> EmbeddedFactory {
        EmbeddedFactory {
            buses,
            context: crate::bus::Embedded::default(),
        }
    }
}

impl DutFactory for EmbeddedFactory {
    fn describe(&self) -> String {
        describe()
    }

    fn fork(&self) -> Option<Box<dyn DutFactory + Send>> {
        // A capture is one time line of the run's packets: one thread writes it.
        self.context
            .tap
            .is_none()
            .then(|| Box::new(Untapped(self.buses)) as Box<dyn DutFactory + Send>)
    }

    fn open(&mut self, profile: &Profile, retries: u32) -> Result<Box<dyn Binding>, OpenError> {
        open(self.buses, profile, retries, &self.context)
    }
}

/// An [`EmbeddedFactory`] without a capture, for a thread of its own.
struct Untapped(&'static [&'static Bus]);

impl DutFactory for Untapped {
    fn describe(&self) -> String {
        describe()
    }

    fn fork(&self) -> Option<Box<dyn DutFactory + Send>> {
        Some(Box::new(Untapped(self.0)))
    }

    fn open(&mut self, profile: &Profile, retries: u32) -> Result<Box<dyn Binding>, OpenError> {
        open(self.0, profile, retries, &crate::bus::Embedded::default())
    }
}

/// The embedded simulator, as reports name it.
fn describe() -> String {
    match sim_firmware() {
        Ok(Firmware::Next) => "embedded simulator (firmware next)".into(),
        _ => "embedded simulator".into(),
    }
}

/// A fresh simulator for `profile`, behind its binding.
fn open(
    buses: &[&Bus],
    profile: &Profile,
    retries: u32,
    context: &crate::bus::Embedded,
) -> Result<Box<dyn Binding>, OpenError> {
    match profile.bus {
        None => {
            let product = profile.nord().map_err(OpenError::Profile)?;
            Ok(Box::new(Channel::new(ppo_dut(profile)?, product, retries)))
        }
        Some(name) => {
            let bus = crate::bus::by_name(buses, name)
                .ok_or_else(|| OpenError::Profile(format!("no bus `{name}`")))?;
            (bus.embedded)(profile, context)
        }
    }
}

/// The identity the embedded simulator of `product` reports over `bus`, as a connection check
/// reads it (for each bus's own identity test).
#[cfg(test)]
pub(crate) fn identity_over(
    product: proto::nord::Product,
    bus: &'static str,
) -> crate::outcome::Identity {
    let profile = Profile::on_bus(product, bus);
    let mut dut = EmbeddedFactory::new(crate::buses::BUSES)
        .open(&profile, 25)
        .expect("the embedded simulator opens");
    dut.identity()
        .expect("the bus has an identity service")
        .expect("the simulator answers it")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One case written twice: the second runs after the first, on a simulator of its own.
    /// With `process`, process data before and after the parameter access (the system bus
    /// has no process data yet: its profiles run the access alone).
    fn twice(process: bool) -> String {
        let case = |id: &str| {
            let (before, after) = if process {
                (
                    "\n      - process: { control: \"047Eh\", for: 20ms }",
                    "\n      - process: { control: \"047Fh\", setpoints: [\"2000h\"], for: 20ms }",
                )
            } else {
                ("", "")
            };
            format!(
                r#"
  - id: {id}
    title: process data, a parameter read and write, process data again
    ref: {{ section: "6.1.3", page: 114 }}
    steps:{before}
      - read: {{ param: 102 }}
      - write: {{ param: 102, value: 300 }}{after}"#
            )
        };
        format!(
            "doc: BU 0620\nedition: \"2020-03 en\"\ncases:{}{}\n",
            case("first"),
            case("again")
        )
    }

    /// A case's exchanges are a function of the case alone: the identifiers the harness and
    /// the simulated device choose (EtherNet/IP connection serial numbers and ids, PROFINET RPC
    /// activities, session handles and keys, EtherCAT datagram indices, POWERLINK SDO sequence
    /// numbers) start afresh in every case, so a case sends and receives the same bytes
    /// whatever ran before it, under every profile of every bus.
    #[test]
    fn a_cases_exchanges_do_not_depend_on_the_cases_before_it() {
        let (can, others): (Vec<Profile>, Vec<Profile>) = crate::buses::catalog()
            .all()
            .into_iter()
            .partition(|p| p.bus == Some("can"));
        assert!(!can.is_empty() && !others.is_empty());
        for (profiles, process) in [(others, true), (can, false)] {
            exchanges_repeat(profiles, process);
        }
    }

    fn exchanges_repeat(profiles: Vec<Profile>, process: bool) {
        let loaded = crate::suite::load_text_for_tests(&twice(process));
        let opts = crate::runner::RunOptions {
            retries: 25,
            ..crate::runner::RunOptions::new(profiles.clone())
        };
        let run = crate::runner::run(
            &loaded,
            &opts,
            &mut EmbeddedFactory::new(crate::buses::BUSES),
        );
        for profile in profiles {
            let cases: Vec<_> = run
                .cases
                .iter()
                .filter(|c| c.profile == profile.name())
                .collect();
            let [first, again] = cases[..] else {
                panic!("{}: {} cases", profile.name(), cases.len());
            };
            for c in [first, again] {
                assert_eq!(
                    c.verdict,
                    crate::outcome::Verdict::Pass,
                    "{} {}: {}",
                    c.profile,
                    c.id,
                    c.message
                );
            }
            // The transcripts past their headers: each step with its exchanges.
            let [a, b] = [first, again].map(|c| c.transcript.as_deref().unwrap_or_default());
            let steps: Vec<&str> = a.split("\nstep ").skip(1).collect();
            assert_eq!(steps.len(), first.steps.len(), "{}: {a}", c_name(first));
            for (n, step) in (1..).zip(&steps) {
                assert!(
                    step.contains("\n  -> "),
                    "{} step {n}: no exchange",
                    c_name(first)
                );
            }
            assert_eq!(
                a,
                b,
                "{}: the second case's exchanges differ",
                c_name(first)
            );
        }
    }

    fn c_name(c: &crate::outcome::CaseResult) -> String {
        format!("{} {}", c.profile, c.id)
    }
}
