//! The PROFINET IO binding for any maker's device (profile `any@pnio`): the harness as IO
//! controller of a device it knows only from its GSDML (`--description`). Opening finds the
//! device by DCP, then connects the DAP and the I/O module the GSDML plans
//! ([`crate::description::Gsdml`]), PrmEnd and the device's ApplicationReady. Only the
//! `pnio:` steps run: NORD's parameter channel and modules are not there. When a case ends,
//! the AR is released and the device's name and address are set back as the run found them.

use proto::pnio::plan::ExpectedSub;

use super::binding::{bring_to_data_exchange, bus_step, find, identity_of, step_error, StepPlan};
use super::controller::{Controller, Station};
use super::link::Link;
use super::restore;
use super::step::PnioStep;
use crate::binding::{Binding, CleanupError, Observation, OpenError, StepError};
use crate::outcome::{Exchange, Identity};
use crate::profile::Capability;
use crate::suite::Action;

/// What any maker's device on the network offers: its bus's own steps.
const CAPABILITIES: [Capability; 1] = [Capability::Bus("pnio")];

/// The DAP's submodules and the modules a Connect expects, from the device's GSDML.
#[derive(Debug, Clone)]
pub(super) struct Layout {
    pub(super) dap: Vec<ExpectedSub>,
    pub(super) modules: Vec<ExpectedSub>,
    /// The DAP declares DeviceAccessSupported.
    pub(super) device_access: bool,
}

/// The harness as IO controller of any maker's device.
pub(super) struct GenericPnio<L> {
    ctl: Controller<L>,
    layout: Layout,
    what: String,
    /// The device as the run found it, to set back when a case ends.
    found: Station,
}

impl<L: Link + 'static> GenericPnio<L> {
    /// Finds the device (`name`, or the only one) and brings an AR with `layout` to data
    /// exchange.
    pub(super) fn open(
        mut ctl: Controller<L>,
        layout: Layout,
        name: Option<String>,
        what: String,
    ) -> Result<GenericPnio<L>, OpenError> {
        let (found, what) = find(&mut ctl, name.as_deref(), &what)?;
        ctl.set_dap(layout.dap.clone());
        // Any maker's device may raise any alarm its GSDML allows.
        ctl.set_alarm_types(None);
        bring_to_data_exchange(&mut ctl, &layout.modules)?;
        Ok(GenericPnio {
            ctl,
            layout,
            what,
            found,
        })
    }
}

impl<L: Link + 'static> Binding for GenericPnio<L> {
    fn identity(&mut self) -> Option<Result<Identity, StepError>> {
        identity_of(&mut self.ctl)
    }

    fn describe(&self) -> String {
        self.what.clone()
    }

    fn capabilities(&self) -> &[Capability] {
        &CAPABILITIES
    }

    fn perform(&mut self, action: &Action) -> Result<Observation, StepError> {
        let Action::Bus(step) = action else {
            return Err(StepError::NotApplicable(
                "any maker's PROFINET device runs the `pnio:` steps only".into(),
            ));
        };
        let step = crate::binding::own_step::<PnioStep>(step.as_ref(), "PROFINET IO")?;
        let modules = self.layout.modules.clone();
        let place = modules.first().map_or((0, 1), |m| (m.slot, m.subslot));
        let plan = StepPlan {
            connect: &move |named: &[super::step::Module]| {
                if named.is_empty() {
                    Ok(modules.clone())
                } else {
                    Err(
                        "a Connect naming NORD's modules; any maker's device connects its GSDML's"
                            .into(),
                    )
                }
            },
            place,
            nord: false,
            own_name: &self.found.name,
            device_access: self.layout.device_access,
        };
        bus_step(&mut self.ctl, step, &plan)
    }

    /// Releases the case's AR and sets the name and address back as the run found them.
    fn finish(&mut self) -> Result<(), CleanupError> {
        let mut problems = Vec::new();
        if self.ctl.connected() {
            if let Err(e) = self.ctl.release() {
                problems.push(format!("releasing the AR: {}", step_error(e)));
            }
        }
        if self.ctl.holds_access() {
            if let Err(e) = self.ctl.release() {
                problems.push(format!("releasing the DeviceAccess AR: {}", step_error(e)));
            }
        }
        if let Err(e) = restore::station(&mut self.ctl, &self.found) {
            problems.push(e);
        }
        match problems.is_empty() {
            true => Ok(()),
            false => Err(CleanupError(problems.join("; "))),
        }
    }

    fn take_exchanges(&mut self) -> Vec<Exchange> {
        self.ctl.take_exchanges()
    }

    fn finish_closes(&self) -> bool {
        true
    }
}
