//! The embedded simulator as every binding opens it: the simulated device of a profile (as
//! the firmware release [`FIRMWARE_VAR`] names), the in-memory PPO link that carries the bytes
//! a bus would on a virtual clock, and what every embedded DUT can show (`observe:`).

use serde_json::{json, Value};
use sim::clock::{Clock, VirtualClock};
use sim::device::{Device, DeviceConfig, Firmware};
use sim::link::{mem_pair, MemEnd};
use std::time::Duration;

use super::{Dut, DutError, OpenError, StepError};
use crate::profile::{Capability, Profile};
use proto::nord::Inverter;

/// Bus cycle of the embedded link: 4 ms, a common PROFINET send clock multiple.
const CYCLE: Duration = Duration::from_millis(4);

/// What the embedded PPO link offers: everything but a bus's own steps (a fresh simulator per
/// case is in its power-on and factory state, and keeps its link whatever its address).
const PPO_CAPABILITIES: [Capability; 9] = Capability::GENERAL;

/// The environment variable that picks the embedded simulator's firmware release: unset or
/// `release`, or `next` ([`Firmware::Next`]: P856's factory value and the modules' P171 revision changed), to compare the runs of
/// two releases with `harness diff` on the simulator. A variable rather than an option: it is
/// a demonstration and test aid, never offered for a real DUT.
pub(crate) const FIRMWARE_VAR: &str = "NORD_SIM_FIRMWARE";

/// The release a [`FIRMWARE_VAR`] value names.
fn firmware_named(value: Option<&str>) -> Result<Firmware, String> {
    match value {
        None | Some("" | "release") => Ok(Firmware::Release),
        Some("next") => Ok(Firmware::Next),
        Some(other) => Err(format!(
            "{FIRMWARE_VAR}=`{other}`: give `release` or `next`"
        )),
    }
}

/// The firmware release the environment asks the embedded simulator for.
pub(crate) fn sim_firmware() -> Result<Firmware, String> {
    match std::env::var(FIRMWARE_VAR) {
        Ok(v) => firmware_named(Some(&v)),
        Err(std::env::VarError::NotPresent) => firmware_named(None),
        Err(e) => Err(format!("{FIRMWARE_VAR}: {e}")),
    }
}

/// The simulated device of a profile: its product with the profile's inverters, as the
/// firmware release [`FIRMWARE_VAR`] names.
pub(crate) fn device_config(profile: &Profile) -> Result<DeviceConfig, OpenError> {
    Ok(DeviceConfig {
        inverters: profile.inverters,
        firmware: sim_firmware().map_err(OpenError::Profile)?,
        ..DeviceConfig::new(profile.nord().map_err(OpenError::Profile)?)
    })
}

/// The simulator for a profile behind the in-memory PPO link.
pub(crate) fn ppo_dut(profile: &Profile) -> Result<Box<dyn Dut>, OpenError> {
    let config = device_config(profile)?;
    Ok(Box::new(Embedded::new(Device::new(config))))
}

/// The simulator and both ends of its link.
struct Embedded {
    device: Device,
    clock: VirtualClock,
    harness_end: MemEnd,
    device_end: MemEnd,
}

impl Embedded {
    fn new(device: Device) -> Self {
        let (harness_end, device_end) = mem_pair();
        Embedded {
            device,
            clock: VirtualClock::new(),
            harness_end,
            device_end,
        }
    }
}

impl Dut for Embedded {
    fn describe(&self) -> String {
        format!(
            "embedded simulator ({}, {} inverters)",
            self.device.config().product.name(),
            self.device.config().inverters
        )
    }

    fn capabilities(&self) -> &[Capability] {
        &PPO_CAPABILITIES
    }

    fn cycle_time(&self) -> Duration {
        CYCLE
    }

    fn cycle(&mut self, frame: &[u8]) -> Result<Option<Vec<u8>>, StepError> {
        self.harness_end.send(frame.to_vec());
        // The device side of the link: answer every frame; drop what it cannot answer, as a
        // real device drops a malformed frame.
        while let Some(f) = self.device_end.recv() {
            if let Ok(answer) = self.device.handle(&f, self.clock.now()) {
                self.device_end.send(answer);
            }
        }
        self.clock.advance(CYCLE);
        Ok(self.harness_end.recv())
    }

    fn inject(&mut self, inverter: Inverter, error: &str) -> Result<(), DutError> {
        Ok(self.device.inject_fault(inverter, error)?)
    }

    fn observe(&mut self, what: &str, inverter: Inverter) -> Result<Value, DutError> {
        observe_device(&mut self.device, what, inverter, self.clock.now())?
            .ok_or_else(|| DutError(format!("cannot observe `{what}` ({OBSERVABLE})")))
    }
}

/// What every embedded DUT can show.
pub(crate) const OBSERVABLE: &str =
    "state, leds, eeprom-writes, interface-eeprom-writes, system-bus";

/// The frames of the system bus a `system-bus` observation shows in full; the count covers all.
const SYSTEM_BUS_FRAMES_SHOWN: usize = 200;

/// Internal state of the simulated device at `now`; `None` for a `what` it does not know, so a
/// binding can add its own.
pub(crate) fn observe_device(
    device: &mut Device,
    what: &str,
    inverter: Inverter,
    now: Duration,
) -> Result<Option<Value>, String> {
    Ok(Some(match what {
        "state" => json!({ "state": device.state_name(inverter)? }),
        "leds" => {
            let (dev, bus) = device.leds(inverter, now)?;
            json!({ "dev": dev, "bus": bus })
        }
        "eeprom-writes" => json!({ "count": device.eeprom_writes(Some(inverter))? }),
        "interface-eeprom-writes" => json!({ "count": device.eeprom_writes(None)? }),
        "system-bus" => system_bus(device),
        _ => return Ok(None),
    }))
}

/// What the bus interface put on the system bus since the last look (the first look attaches
/// the tap, `sim::device::Device::tap_system_bus`): the frames (`ID DATA`, joined by `; `),
/// the SDO frames among them alone, their count, and the shortest time between two SYNCs
/// (µs), the process-data cycle.
fn system_bus(device: &mut Device) -> Value {
    system_bus_observation(&device.tap_system_bus())
}

/// A `system-bus` observation of `frames` (see [`system_bus`]).
pub(crate) fn system_bus_observation(frames: &[(Duration, proto::can::CanFrame)]) -> Value {
    let syncs: Vec<Duration> = frames
        .iter()
        .filter(|(_, f)| f.id() == 0x080)
        .map(|(t, _)| *t)
        .collect();
    let gap = syncs.windows(2).map(|w| w[1] - w[0]).min();
    let shown: Vec<String> = frames
        .iter()
        .take(SYSTEM_BUS_FRAMES_SHOWN)
        .map(|(_, f)| crate::hex::can_frame(f))
        .collect();
    let sdo: Vec<String> = frames
        .iter()
        .filter(|(_, f)| (0x581..=0x67F).contains(&f.id()))
        .map(|(_, f)| crate::hex::can_frame(f))
        .collect();
    json!({
        "frames": shown.join("; "),
        "sdo": sdo.join("; "),
        "count": frames.len(),
        "sync_gap_us": gap.map(|g| g.as_micros() as u64),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_firmware_variable_names_a_release_or_is_refused() {
        assert_eq!(firmware_named(None), Ok(Firmware::Release));
        assert_eq!(firmware_named(Some("")), Ok(Firmware::Release));
        assert_eq!(firmware_named(Some("release")), Ok(Firmware::Release));
        assert_eq!(firmware_named(Some("next")), Ok(Firmware::Next));
        assert_eq!(
            firmware_named(Some("v2")),
            Err("NORD_SIM_FIRMWARE=`v2`: give `release` or `next`".into())
        );
    }

    #[test]
    fn the_ppo_link_offers_every_general_capability() {
        assert_eq!(PPO_CAPABILITIES, Capability::GENERAL);
    }
}
