//! `harness run --dut … --tap socketcand://HOST[:PORT]/CHANNEL` (or `--tap can://IFACE`): the
//! system bus of a bus
//! module under test, watched while its field bus is tested, so that cases assert what the
//! gateway put on the system bus for a field-bus request (`observe: { what: system-bus }`).
//!
//! A thread reads every frame of the tapped bus into a buffer from the moment the run opens the
//! DUT; an observation takes what came since the last one. The served modules publish their
//! gateway's frames with `harness serve enip --system-bus ADDR` (`relay_system_bus`); a real
//! module's system bus is reached through a socketcand server on a CAN adapter beside it.

use std::net::SocketAddr;
use std::sync::{Arc, Mutex};
use std::thread;
use std::time::Duration;

use proto::can::CanFrame;

use super::link::{CanLink, Socketcand};
use crate::binding::DutFactory;
use crate::binding::{Binding, CleanupError, Observation, OpenError, StepError};
use crate::outcome::{Exchange, Identity};
use crate::profile::{Capability, Profile};
use crate::suite::Action;

/// How long an observation waits for frames still on their way (the served relay hands its
/// frames over every 2 ms) before it takes what came.
const SETTLE: Duration = Duration::from_millis(20);

/// The frames of a tapped system bus, each with its time on the bus (socketcand's timestamp; on
/// a CAN interface, when it came). The reader runs until the bus's server closes the connection
/// or the run ends.
#[derive(Clone)]
pub(crate) struct SystemBusTap {
    frames: Arc<Mutex<Vec<(Duration, CanFrame)>>>,
    what: String,
}

impl SystemBusTap {
    /// Connects to `url` (`socketcand://HOST[:PORT]/CHANNEL`, or `can://IFACE` for a CAN
    /// interface of this host) and starts reading.
    pub(crate) fn connect(url: &str, limit: Duration) -> Result<SystemBusTap, String> {
        let bad = |what: &str| format!("`--tap {url}`: {what}");
        if let Some(iface) = url.strip_prefix("can://") {
            let link = super::socketcan::SocketCan::open(iface).map_err(|e| bad(&e.to_string()))?;
            return Ok(SystemBusTap::reading(
                link,
                format!("system bus on {iface}"),
            ));
        }
        let target = url
            .strip_prefix("socketcand://")
            .ok_or_else(|| bad("give socketcand://HOST[:PORT]/CHANNEL or can://IFACE"))?;
        let (host, channel) = target
            .split_once('/')
            .filter(|(_, c)| !c.is_empty())
            .ok_or_else(|| bad("give the bus after a slash (…/can0)"))?;
        let addr: SocketAddr =
            crate::net::serve_args::socket_addr(host, super::serve::DEFAULT_PORT)
                .map_err(|e| bad(&e))?;
        let link = Socketcand::connect(addr, channel, limit).map_err(|e| bad(&e.to_string()))?;
        Ok(SystemBusTap::reading(
            link,
            format!("system bus `{channel}` of socketcand {addr}"),
        ))
    }

    /// Reads every frame of `link` on a thread of its own.
    fn reading<L: CanLink + Send + 'static>(mut link: L, what: String) -> SystemBusTap {
        let tap = SystemBusTap {
            frames: Arc::default(),
            what,
        };
        let frames = tap.frames.clone();
        thread::spawn(move || loop {
            match link.recv_stamped(Duration::from_secs(1)) {
                Ok(Some(stamped)) => {
                    frames
                        .lock()
                        .unwrap_or_else(|p| p.into_inner())
                        .push(stamped);
                }
                Ok(None) => {}
                Err(_) => return,
            }
        });
        tap
    }

    /// The frames since the last call.
    fn take(&self) -> Vec<(Duration, CanFrame)> {
        thread::sleep(SETTLE);
        std::mem::take(&mut *self.frames.lock().unwrap_or_else(|p| p.into_inner()))
    }
}

/// Opens the DUTs of `inner` with the tap beside them.
pub(crate) struct TapFactory {
    pub(crate) inner: Box<dyn DutFactory>,
    pub(crate) tap: SystemBusTap,
}

impl DutFactory for TapFactory {
    fn describe(&self) -> String {
        format!("{}, its {} tapped", self.inner.describe(), self.tap.what)
    }

    fn open(&mut self, profile: &Profile, retries: u32) -> Result<Box<dyn Binding>, OpenError> {
        let inner = self.inner.open(profile, retries)?;
        let mut capabilities = inner.capabilities().to_vec();
        capabilities.push(Capability::SystemBus);
        // What came before the case is not the case's.
        self.tap
            .frames
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .clear();
        Ok(Box::new(TapBinding {
            inner,
            tap: self.tap.clone(),
            capabilities,
        }))
    }
}

/// A DUT's binding and the tap: `observe: { what: system-bus }` reads the tap.
struct TapBinding {
    inner: Box<dyn Binding>,
    tap: SystemBusTap,
    capabilities: Vec<Capability>,
}

impl Binding for TapBinding {
    fn describe(&self) -> String {
        self.inner.describe()
    }

    fn capabilities(&self) -> &[Capability] {
        &self.capabilities
    }

    fn perform(&mut self, action: &Action) -> Result<Observation, StepError> {
        match action {
            Action::Observe { what, .. } if what == "system-bus" => {
                Ok(crate::binding::simulator::system_bus_observation(&self.tap.take()).into())
            }
            _ => self.inner.perform(action),
        }
    }

    fn take_exchanges(&mut self) -> Vec<Exchange> {
        self.inner.take_exchanges()
    }

    fn finish(&mut self) -> Result<(), CleanupError> {
        self.inner.finish()
    }

    fn finish_closes(&self) -> bool {
        self.inner.finish_closes()
    }

    fn identity(&mut self) -> Option<Result<Identity, StepError>> {
        self.inner.identity()
    }
}
