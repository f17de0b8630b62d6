//! The PROFINET IO binding: the harness as IO controller of one NORD device (SK 550P, BU 0620
//! §2.5; SK TU3-PNT, BU 0590), in-process against the simulated device or on a network
//! interface.
//!
//! Opening a DUT finds the device by DCP (by name, or the only one answering), then connects
//! with a PPO 4 module in each inverter's slot (control/status word and three setpoints/actual
//! values, no parameter channel: that goes through the records), PrmEnd, and the device's
//! ApplicationReady: data exchange at 1 ms.
//! The manual-level steps run through the shared parameter channel ([`Channel`]) on a
//! [`Dut`] that carries them the PROFINET way: a PKW order is written to the unit's data
//! record (BU 0620 §2.5.6.2: 100 the interface, 100 + n FI n) and its answer read back from
//! it, "Read Response (−)" (DE 80 B5 00) meaning "not yet"; the control word and setpoints
//! ride in the output CR's frame for the inverter's slot, the status word and actual values
//! come back in the input CR's. The `pnio:` steps go to the controller as written.

use std::cell::RefCell;
use std::rc::Rc;
use std::time::Duration;

use proto::nord::pkw::PkwRepr;
use proto::nord::pnio::{self as def, ModuleKind, RecordTarget};
use proto::nord::ppo::{PpoRepr, PpoType};
use proto::nord::{Inverter, Product};
use proto::pnio::alarm::AlarmItem;
use proto::pnio::dcp::{BlockQualifier, BlockValue, DcpBlock, IpParameter};
use proto::pnio::plan::ExpectedSub;
use proto::pnio::rpc::{Opnum, Uuid};
use proto::pnio::status::cm;
use proto::pnio::PnioStatus;
use serde_json::{json, Value};
use sim::link::{LinkRepr, Unit};

use super::controller::{Connected, Controller, PnioError, Station};
use super::link::Link;
use super::restore::{self, Param, Settling};
use super::step::{Module, PnioStep};
use crate::binding::channel::Channel;
use crate::binding::ledger::{self, Account, Ledger, Problem};
use crate::binding::settle::{self, Drives};
use crate::binding::simulator::{observe_device, OBSERVABLE};
use crate::binding::{Binding, CleanupError, Dut, DutError, Observation, OpenError, StepError};
use crate::hex::hex;
use crate::net::wait::BringUpError;
use crate::outcome::{Exchange, Identity, Refusal};
use crate::profile::Capability;
use crate::suite::{Action, Run};

/// What the embedded simulator offers: every general capability and the `pnio:` steps.
pub(crate) const EMBEDDED_CAPABILITIES: [Capability; 10] = Capability::general_and("pnio");

/// What a device on the network offers: one persistent device, which the harness can neither
/// power-cycle, reset to factory settings nor look into.
pub(crate) const NETWORK_CAPABILITIES: [Capability; 4] = [
    Capability::ParameterAccess,
    Capability::ParameterChannel,
    Capability::ProcessData,
    Capability::Bus("pnio"),
];

/// The `inject` error that makes the simulated device lose an inverter from its system bus.
const LOST: &str = "lost";

/// Bus cycles a parameter order may take to be answered (each cycle one record read).
const ORDER_CYCLES: u32 = 200;

/// The controller, shared by the binding (for the `pnio:` steps) and the channel's DUT.
type Shared<L> = Rc<RefCell<Controller<L>>>;

/// The harness as IO controller.
pub(crate) struct PnioBinding<L> {
    ctl: Shared<L>,
    channel: Channel,
    product: Product,
    inverters: u8,
    what: String,
    capabilities: &'static [Capability],
    /// The name of station the device was found by when the case began.
    own_name: String,
    /// A device on the network: what the case wrote, the drives it ran, and the device as the
    /// run found it, to put back when the case ends.
    persistent: Option<Persistent>,
}

/// What a case on a persistent device changes.
struct Persistent {
    ledger: Ledger<Param>,
    commanded: Vec<Inverter>,
    found: Station,
}

/// The refusal of a PNIO status.
fn refused(status: PnioStatus, mut fields: Value) -> Observation {
    fields["status"] = json!(status_hex(status));
    Observation::refused(
        fields,
        Refusal {
            kind: "PNIO status".into(),
            code: u32::from_be_bytes([status.code, status.decode, status.code1, status.code2]),
            text: status.meaning(),
        },
    )
}

fn status_hex(s: PnioStatus) -> String {
    format!(
        "{:02X}{:02X}{:02X}{:02X}",
        s.code, s.decode, s.code1, s.code2
    )
}

pub(super) fn step_error(e: PnioError) -> StepError {
    match e {
        PnioError::Link(l) => StepError::Link(l.into()),
        // The device's limit passed: late unless the host was (the runner judges that).
        PnioError::NoReply {
            what,
            limit,
            waited,
        } => StepError::Late {
            what: format!("{what} from the device"),
            limit,
            waited,
        },
        e @ (PnioError::NoInput | PnioError::NotFound(_)) => StepError::Link(e.into()),
        // A PROFINET answer that breaks its own rules (an RPC response without its PNIO
        // status) is the device's departure, judged; open_error keeps garbage at bring-up an
        // error.
        e @ PnioError::Malformed { .. } => StepError::Protocol(e.into()),
        // An input CR whose cycle counter stood still past the data hold time: the frames
        // came, stamped on arrival, and none was new.
        e @ PnioError::StoodStill(_) => StepError::Departed(e.into()),
        e @ (PnioError::Nca { .. } | PnioError::NotConnected) => StepError::Refused(e.into()),
    }
}

/// [`crate::net::wait::bring_up`] of a part of the opening: again while the host was late, and
/// a second look at a device whose answer missed its limit with the host on time.
fn bring_up<T>(attempt: impl FnMut(u32) -> Result<T, PnioError>) -> Result<T, OpenError> {
    crate::net::wait::bring_up(attempt, |e| match e {
        PnioError::NoReply { limit, waited, .. } => Some((*limit, *waited)),
        _ => None,
    })
    .map_err(|e| match e {
        BringUpError::Failed(e) => open_error(e),
        BringUpError::Late(e) => OpenError::Late(e.to_string()),
    })
}

/// Why the device could not be opened.
fn open_error(e: PnioError) -> OpenError {
    match e {
        PnioError::Link(_)
        | PnioError::NoReply { .. }
        | PnioError::NoInput
        | PnioError::NotFound(_) => OpenError::Unreachable(e.to_string()),
        _ => OpenError::BringUp(e.to_string()),
    }
}

/// The PPO type of the module connected in `slot`, `None` for none or another module.
pub(super) fn module_ppo<L: Link>(
    ctl: &Controller<L>,
    product: Product,
    slot: u16,
) -> Option<PpoType> {
    match def::module_by_ident(product, ctl.module_ident(slot)?)?.kind {
        ModuleKind::Ppo(t) => Some(t),
        ModuleKind::DigIo => None,
    }
}

/// A PPO module's output data with the process words `pzd` (control word, setpoints; cut or
/// filled with zeros to the module's), its parameter channel empty where it has one.
pub(super) fn module_bytes(t: PpoType, pzd: &[u16]) -> Vec<u8> {
    let mut pzd = pzd.to_vec();
    pzd.resize(t.pzd_words(), 0);
    PpoRepr {
        pkw: t.has_pkw().then(PkwRepr::default),
        pzd,
    }
    .emit(t)
}

/// The process words of a PPO module's input data (status word, actual values).
pub(super) fn module_pzd(t: PpoType, data: &[u8]) -> Option<Vec<u16>> {
    PpoRepr::parse(data, t).ok().map(|p| p.pzd)
}

/// The module a Connect puts in an inverter's slot unless told: PPO 4, the control/status word
/// and three setpoints/actual values without a parameter channel (BU 0620 §2.5.5.1), which
/// goes through the data records; PPO 2 where a product has no PPO 4.
fn default_ppo(product: Product) -> PpoType {
    [PpoType::TYPE_4, PpoType::TYPE_2]
        .into_iter()
        .find(|t| def::module(product, ModuleKind::Ppo(*t)).is_some())
        .unwrap_or(PpoType::TYPE_2)
}

/// Opening, first part: the device found by DCP (`name`, or the only one), the transcript
/// paused until the AR runs; the device and the binding's description of it.
pub(super) fn find<L: Link>(
    ctl: &mut Controller<L>,
    name: Option<&str>,
    what: &str,
) -> Result<(Station, String), OpenError> {
    ctl.set_recording(false);
    let station = bring_up(|patience| {
        ctl.set_patience(patience);
        ctl.locate(name)
    })?;
    let what = format!(
        "{what}: {:?} ({}, vendor {:04X}h, device {:04X}h, {})",
        station.name, station.type_of_station, station.vendor_id, station.device_id, station.mac
    );
    Ok((station, what))
}

/// Opening, second part: an AR with the DAP and `subs` in data exchange, the transcript on.
pub(super) fn bring_to_data_exchange<L: Link>(
    ctl: &mut Controller<L>,
    subs: &[ExpectedSub],
) -> Result<(), OpenError> {
    let c = bring_up(|patience| {
        ctl.set_patience(patience);
        up(ctl, subs)
    })?;
    ctl.set_patience(1);
    if !c.ready {
        return Err(OpenError::BringUp(format!(
            "the AR did not come up: {}",
            c.why_not_running()
        )));
    }
    ctl.take_exchanges();
    ctl.take_cycles();
    ctl.set_recording(true);
    Ok(())
}

/// Connect with `subs`; a device still holding the AR of an earlier case (which ended without
/// releasing it) refuses with "out of AR resources" until its watchdog ends that AR: once
/// more after it.
fn up<L: Link>(ctl: &mut Controller<L>, subs: &[ExpectedSub]) -> Result<Connected, PnioError> {
    let c = ctl.connect(subs)?;
    let out_of_ar = PnioStatus::cm(cm::CONNECT, cm::CMRPC, cm::CMRPC_OUT_OF_AR);
    if c.status != out_of_ar {
        return Ok(c);
    }
    ctl.run_for(ctl.watchdog() * 2)?;
    ctl.connect(subs)
}

/// The modules of a Connect: the given ones in FI 1, 2… slots, [`default_ppo`] for the rest
/// of the inverters (an ident number as written, for a wrong module).
fn expected(
    product: Product,
    inverters: u8,
    modules: &[Module],
) -> Result<Vec<ExpectedSub>, String> {
    let mut subs = Vec::new();
    for n in 1..=inverters.max(modules.len() as u8) {
        let fi = Inverter::new(i64::from(n)).map_err(|e| e.to_string())?;
        let slot = def::inverter_slot(product, fi).map_err(|e| e.to_string())?;
        let module = modules.get(usize::from(n) - 1).copied();
        let sub = match module {
            None | Some(Module::Ppo(_)) => {
                let t = match module {
                    Some(Module::Ppo(t)) => t,
                    _ => default_ppo(product),
                };
                let m = def::module(product, ModuleKind::Ppo(t)).ok_or(format!(
                    "{} has no PPO {} module",
                    product.name(),
                    t.0
                ))?;
                def::expected_module(slot, &m)
            }
            Some(Module::Ident(ident)) => ExpectedSub {
                slot,
                module_ident: ident,
                subslot: def::IO_SUBSLOT,
                ident,
                input_len: 4,
                output_len: 4,
            },
        };
        subs.push(sub);
    }
    Ok(subs)
}

impl<L: Link + 'static> PnioBinding<L> {
    /// Finds the device (`name`, or the only one), connects and brings the AR to data
    /// exchange.
    pub(crate) fn open(
        mut ctl: Controller<L>,
        product: Product,
        inverters: u8,
        name: Option<String>,
        what: String,
        persistent: bool,
    ) -> Result<PnioBinding<L>, OpenError> {
        let (station, what) = find(&mut ctl, name.as_deref(), &what)?;
        if station.vendor_id != def::VENDOR_ID {
            return Err(OpenError::BringUp(format!(
                "{:?} has vendor id {:04X}h, not NORD's {:04X}h",
                station.name,
                station.vendor_id,
                def::VENDOR_ID
            )));
        }
        let subs = expected(product, inverters, &[]).map_err(OpenError::Profile)?;
        bring_to_data_exchange(&mut ctl, &subs)?;
        let ctl = Rc::new(RefCell::new(ctl));
        let dut = PnioDut {
            ctl: ctl.clone(),
            product,
            pending: None,
        };
        Ok(PnioBinding {
            channel: Channel::new(Box::new(dut), product, ORDER_CYCLES),
            capabilities: if persistent {
                &NETWORK_CAPABILITIES
            } else {
                &EMBEDDED_CAPABILITIES
            },
            own_name: station.name.clone(),
            ctl,
            product,
            inverters,
            what,
            persistent: persistent.then(|| Persistent {
                ledger: Ledger::default(),
                commanded: Vec::new(),
                found: station,
            }),
        })
    }

    fn pnio_step(&mut self, step: &PnioStep) -> Result<Observation, StepError> {
        let (product, inverters) = (self.product, self.inverters);
        let fi1 = Inverter::new(1)
            .ok()
            .and_then(|fi| def::inverter_slot(product, fi).ok());
        let plan = StepPlan {
            connect: &move |m: &[Module]| expected(product, inverters, m),
            place: (fi1.unwrap_or(0), def::IO_SUBSLOT),
            nord: true,
            own_name: &self.own_name,
            // Our GSDML declares DeviceAccessSupported (the simulated device keeps one).
            device_access: true,
        };
        bus_step(&mut self.ctl.borrow_mut(), step, &plan)
    }

    /// One action of a case.
    fn act(&mut self, action: &Action) -> Result<Observation, StepError> {
        match action {
            Action::Bus(step) => {
                let step = step
                    .as_any()
                    .downcast_ref::<PnioStep>()
                    .ok_or_else(|| StepError::NotApplicable(format!("a `{}:` step", step.bus())))?;
                self.pnio_step(step)
            }
            Action::Write(o) if self.persistent.is_some() => self.write(action, o),
            Action::Process {
                inverter,
                control,
                setpoints,
                run: Run::For(d),
            } => {
                self.note_commanded(*inverter);
                let one = Action::Process {
                    inverter: *inverter,
                    control: *control,
                    setpoints: setpoints.clone(),
                    run: Run::Cycles(1),
                };
                self.for_time(&one, *d)
            }
            Action::Process {
                inverter,
                control,
                setpoints,
                run: Run::Cycles(n),
            } => {
                self.note_commanded(*inverter);
                let step = |n| Action::Process {
                    inverter: *inverter,
                    control: *control,
                    setpoints: setpoints.clone(),
                    run: Run::Cycles(n),
                };
                self.channel.perform(&step(*n))?;
                // The status comes from one cycle more: a device that took the last output
                // late (a loaded host) has answered it by then.
                self.channel.perform(&step(1))
            }
            Action::Wait(d) => {
                let cycle = self.ctl.borrow().cycle();
                self.for_time(&Action::Wait(cycle), *d)
            }
            other => {
                if let Action::Process { inverter, .. } = other {
                    self.note_commanded(*inverter);
                }
                self.channel.perform(other)
            }
        }
    }

    /// A parameter write on a persistent device, through the ledger: the value before is read
    /// first (the first write of it in the case).
    fn write(
        &mut self,
        action: &Action,
        o: &crate::suite::OrderSpec,
    ) -> Result<Observation, StepError> {
        let key = Param::of(o);
        let wants = self
            .persistent
            .as_ref()
            .is_some_and(|p| p.ledger.wants_original(&key));
        if wants {
            let before = self
                .channel
                .perform(&Action::Read(key.read()))
                .map_err(|e| e.to_string())
                .and_then(|obs| match (obs.refusal, obs.fields["value"].as_i64()) {
                    (None, Some(v)) => Ok(restore::value_bytes(v)),
                    (Some(r), _) => Err(r.text),
                    (None, None) => Err("no value in the answer".into()),
                });
            if let Some(p) = self.persistent.as_mut() {
                p.ledger.original(key, before);
            }
        }
        let r = self.channel.perform(action);
        if let Some(p) = self.persistent.as_mut() {
            let outcome = match &r {
                Ok(obs) => Ok(obs.refusal.is_none()),
                Err(e) => Err(e),
            };
            p.ledger.wrote(&key, ledger::may_have_taken_effect(outcome));
        }
        r
    }

    /// A persistent device's cleanup: a fresh AR, the drives the case ran back in
    /// "Switch-on block", the case's writes put back, the AR released, the name and address
    /// the run found set back.
    fn restore(&mut self) -> Result<(), String> {
        let Some(p) = self.persistent.take() else {
            return Ok(());
        };
        let mut account = Account::default();
        let mut ctl = self.ctl.borrow_mut();
        let link = |what: &'static str| move |e: PnioError| Problem::step(what, step_error(e));
        if account.attempt(|| "a fresh AR".into()) {
            let _ = ctl.release();
            let subs = expected(self.product, self.inverters, &[]).map_err(Problem::other);
            let r = subs.and_then(|subs| {
                let c = up(&mut ctl, &subs).map_err(link("connecting again"))?;
                match c.ready {
                    true => Ok(()),
                    false => Err(Problem::other(format!("connecting again: {}", c.status))),
                }
            });
            account.note(r);
        }
        if !p.commanded.is_empty() && account.attempt(|| "settling the drives".into()) {
            let mut drives = Drives::new(self.inverters, &p.commanded);
            let period = ctl.cycle();
            let mut pending = Vec::new();
            let mut c = Settling {
                ctl: &mut ctl,
                product: self.product,
                words: Vec::new(),
            };
            account.note(drives.settle(&mut c, &mut pending, period, link("settling the drives")));
        }
        drop(ctl);
        let channel = &mut self.channel;
        // The channel sends the control words it last had with every record call below: from
        // now on "disable voltage", where the drives now are, not the case's last words, which
        // would take them out of "Switch-on block" again for the next case to find.
        for &inverter in &p.commanded {
            if account.attempt(|| format!("{inverter} disable voltage in the cyclic data")) {
                let disable = Action::Process {
                    inverter,
                    control: settle::DISABLE,
                    setpoints: Vec::new(),
                    run: Run::Cycles(1),
                };
                let r = channel.perform(&disable).map(drop);
                account.note(r.map_err(|e| Problem::step("disabling voltage", e)));
            }
        }
        p.ledger.restore(&mut account, |key, before| {
            let value = restore::value_of(before);
            match channel.perform(&Action::Write(key.write(value))) {
                Ok(obs) => match obs.refusal {
                    None => Ok(()),
                    Some(r) => Err(Problem::other(format!("setting back {key}: {}", r.text))),
                },
                Err(e) => Err(Problem::step(format!("setting back {key}"), e)),
            }
        });
        let mut ctl = self.ctl.borrow_mut();
        if account.attempt(|| "releasing the AR".into()) {
            let r = ctl.release().map(|_| ()).map_err(link("releasing the AR"));
            account.note(r);
        }
        if ctl.holds_access() && account.attempt(|| "releasing the DeviceAccess AR".into()) {
            let r = ctl
                .release()
                .map(|_| ())
                .map_err(link("releasing the DeviceAccess AR"));
            account.note(r);
        }
        if account.attempt(|| "the name and address as found".into()) {
            account.note(restore::station(&mut ctl, &p.found).map_err(Problem::other));
        }
        account.into_result()
    }

    /// Notes an inverter the case sent control words, for the cleanup of a persistent device.
    fn note_commanded(&mut self, inverter: Inverter) {
        if let Some(p) = self.persistent.as_mut() {
            if !p.commanded.contains(&inverter) {
                p.commanded.push(inverter);
            }
        }
    }

    /// Repeats the one-cycle `step` until `d` has passed on the link's clock (the virtual one
    /// in-process): a step "for 1 s" gives the device's drive model a second, however many
    /// cycles a loaded host manages in it. The last cycle's observation.
    fn for_time(&mut self, step: &Action, d: Duration) -> Result<Observation, StepError> {
        let cycle = self.ctl.borrow().cycle();
        let end = self.ctl.borrow_mut().link_mut().now() + d.saturating_sub(cycle / 2);
        self.channel.perform(step)?;
        while self.ctl.borrow_mut().link_mut().now() < end {
            self.channel.perform(step)?;
        }
        // One cycle more, as for a counted step.
        self.channel.perform(step)
    }

    /// The cyclic traffic of the last step as one transcript line.
    fn cycles_exchange(&mut self) -> Option<Exchange> {
        let log = self.ctl.borrow_mut().take_cycles();
        (log.sent > 0).then(|| Exchange {
            sent_hex: hex(&log.last_sent),
            sent: format!("{} output frames (the last shown)", log.sent),
            received_hex: hex(&log.last_received),
            received: format!("{} input frames (the last shown)", log.received),
        })
    }
}

/// What a `pnio:` step needs of the binding it runs on.
pub(super) struct StepPlan<'a> {
    /// The submodules a Connect expects beside the DAP's, for the modules a step names
    /// (none: the binding's own layout).
    pub(super) connect: &'a dyn Fn(&[Module]) -> Result<Vec<ExpectedSub>, String>,
    /// Slot and subslot of a record step that names none.
    pub(super) place: (u16, u16),
    /// Alarms carry NORD's error numbers (a NORD product).
    pub(super) nord: bool,
    /// The name of station the binding found the device by (`identify: own`).
    pub(super) own_name: &'a str,
    /// The device's description declares a DeviceAccess AR (GSDML DeviceAccessSupported).
    pub(super) device_access: bool,
}

impl StepPlan<'_> {
    /// Slot and subslot of a record step: as it names them, else the binding's place.
    fn at(&self, slot: Option<u16>, subslot: Option<u16>) -> (u16, u16) {
        (
            slot.unwrap_or(self.place.0),
            subslot.unwrap_or(self.place.1),
        )
    }
}

/// A `pnio:` step, as written, on the controller.
pub(super) fn bus_step<L: Link>(
    ctl: &mut Controller<L>,
    step: &PnioStep,
    plan: &StepPlan<'_>,
) -> Result<Observation, StepError> {
    Ok(match step {
        PnioStep::Identify(_) | PnioStep::IdentifyOwn => {
            let name = match step {
                PnioStep::Identify(name) => name.clone(),
                _ => Some(plan.own_name.to_string()),
            };
            let found = ctl.identify(name.as_deref()).map_err(step_error)?;
            let stations: Vec<Value> = found
                .iter()
                .map(|s| {
                    json!({
                        "name": s.name,
                        "mac": s.mac.to_string(),
                        "ip": s.ip.map(|i| i.ip.to_string()),
                        "mask": s.ip.map(|i| i.mask.to_string()),
                        "gateway": s.ip.map(|i| i.gateway.to_string()),
                        "vendor": s.vendor_id,
                        "device": s.device_id,
                        "type": s.type_of_station,
                    })
                })
                .collect();
            let first = stations.first().cloned().unwrap_or(Value::Null);
            json!({ "count": stations.len(), "stations": stations, "station": first }).into()
        }
        PnioStep::SetName { name, permanent } => {
            let block = DcpBlock::set(
                qualifier(*permanent),
                BlockValue::NameOfStation(name.clone()),
            );
            dcp_result(ctl.dcp_set(block).map_err(step_error)?)
        }
        PnioStep::SetIp {
            ip,
            mask,
            gateway,
            permanent,
        } => {
            let block = DcpBlock::set(
                qualifier(*permanent),
                BlockValue::IpParameter(IpParameter {
                    ip: *ip,
                    mask: *mask,
                    gateway: *gateway,
                }),
            );
            dcp_result(ctl.dcp_set(block).map_err(step_error)?)
        }
        PnioStep::Signal => {
            let block = DcpBlock::set(
                BlockQualifier::TEMPORARY,
                BlockValue::Signal(proto::pnio::dcp::SIGNAL_FLASH_ONCE),
            );
            dcp_result(ctl.dcp_set(block).map_err(step_error)?)
        }
        PnioStep::ResetFactory => {
            let block = DcpBlock::set(BlockQualifier::RESET_ALL_DATA, BlockValue::ResetToFactory);
            dcp_result(ctl.dcp_set(block).map_err(step_error)?)
        }
        PnioStep::Connect {
            modules,
            reduction_ratio,
        } => {
            ctl.set_reduction_ratio(*reduction_ratio);
            let subs = (plan.connect)(modules).map_err(|e| StepError::Suite(e.into()))?;
            connect_result(ctl.connect(&subs).map_err(step_error)?)
        }
        PnioStep::Release => {
            let status = ctl.release().map_err(step_error)?;
            status_result(status, json!({}))
        }
        PnioStep::DeviceAccess if !plan.device_access => return Err(StepError::NotApplicable(
            "the GSDML's DAP declares no DeviceAccess AR (DeviceAccessSupported is not \"true\")"
                .into(),
        )),
        PnioStep::DeviceAccess => {
            let status = ctl.open_access().map_err(step_error)?;
            status_result(status, json!({}))
        }
        PnioStep::Read {
            index,
            slot,
            subslot,
        } => {
            let (slot, subslot) = plan.at(*slot, *subslot);
            let (status, data) = ctl
                .read_record(slot, subslot, *index, format!("IODRead record {index}"))
                .map_err(step_error)?;
            status_result(status, json!({ "data": hex(&data), "length": data.len() }))
        }
        PnioStep::Write {
            index,
            slot,
            subslot,
            data,
        } => {
            let (slot, subslot) = plan.at(*slot, *subslot);
            let status = ctl
                .write_record(
                    slot,
                    subslot,
                    *index,
                    data,
                    format!("IODWrite record {index}"),
                )
                .map_err(step_error)?;
            status_result(status, json!({}))
        }
        PnioStep::Alarm(wait) => match ctl.acknowledge_alarm(*wait).map_err(step_error)? {
            None => json!({ "alarm": null }).into(),
            Some(n) => {
                let errors: Vec<u16> = n
                    .items
                    .iter()
                    .filter_map(|i| match i {
                        AlarmItem::ChannelDiagnosis(c) => Some(c.error_type),
                        AlarmItem::ExtChannelDiagnosis(e) => Some(e.channel.error_type),
                        _ => None,
                    })
                    .collect();
                json!({
                    "alarm": n.alarm_type.0,
                    "type": n.alarm_type.name(),
                    "slot": n.slot,
                    "subslot": n.subslot,
                    "module": n.module_ident,
                    "number": errors.first(),
                    "error": errors
                        .first()
                        .filter(|_| plan.nord)
                        .and_then(|e| def::alarm_error_number(*e)),
                })
                .into()
            }
        },
        PnioStep::Silence(d) => {
            ctl.silence(*d).map_err(step_error)?;
            json!({}).into()
        }
        PnioStep::Lldp(d) => {
            let (frames, last) = ctl.lldp_for(*d).map_err(step_error)?;
            let du = last.as_deref().map(proto::lldp::Lldpdu::parse);
            let text = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
            match du {
                Some(Err(e)) => return Err(StepError::Protocol(format!("LLDP: {e}").into())),
                Some(Ok(du)) => json!({
                    "frames": frames,
                    "chassis": text(&du.chassis.1),
                    "chassis_subtype": du.chassis.0,
                    "port": text(&du.port.1),
                    "port_subtype": du.port.0,
                    "ttl": du.ttl,
                }),
                None => json!({ "frames": frames, "chassis": null }),
            }
            .into()
        }
        PnioStep::Cycles(n) => {
            let d = ctl.cycle() * (*n as u32);
            ctl.run_for(d).map_err(step_error)?;
            let status = ctl.input_status().map(|s| s.0);
            json!({ "connected": ctl.connected(), "data_status": status }).into()
        }
        PnioStep::Frame(bytes) => {
            let answer = ctl.raw_frame(bytes).map_err(step_error)?;
            json!({ "answered": answer.is_some(), "answer": answer.as_deref().map(hex) }).into()
        }
        PnioStep::Rpc {
            opnum,
            body,
            interface,
        } => {
            let interface = match interface {
                None => Uuid::PNIO_DEVICE_INTERFACE,
                Some(text) => text
                    .parse::<Uuid>()
                    .map_err(|e| StepError::Suite(e.into()))?,
            };
            match ctl.call(
                Opnum(*opnum),
                body.clone(),
                interface,
                format!("RPC opnum {opnum}"),
            ) {
                Ok(a) => status_result(a.status, json!({ "nca": null })),
                Err(PnioError::Nca { packet, status }) => Observation::refused(
                    json!({ "nca": status.0, "packet": packet }),
                    Refusal {
                        kind: "RPC reject".into(),
                        code: status.0,
                        text: format!("{packet} {status}"),
                    },
                ),
                Err(e) => return Err(step_error(e)),
            }
        }
    })
}

/// The device's identity: the DCP Identify answer the binding found it by (DeviceID
/// block: vendor and device id; NameOfStation) and its I&M0 record (order id, serial
/// number, software revision; BU 0620 §2.5.3 lists I&M among every conformance class's
/// functions; IEC 61158-6-10 makes I&M0 mandatory). A device that refuses I&M0 keeps the DCP
/// fields, and the source says so.
pub(super) fn identity_of<L: Link>(ctl: &mut Controller<L>) -> Option<Result<Identity, StepError>> {
    let station = ctl.station()?.clone();
    let mut id = Identity {
        source: format!("DCP Identify of station {:?}", station.name),
        vendor: Some(format!("vendor id {:04X}h", station.vendor_id)),
        product_code: Some(format!("device id {:04X}h", station.device_id)),
        product_name: Some(station.type_of_station.clone()),
        revision: None,
        serial: None,
    };
    let read = ctl.read_record(0, 1, proto::pnio::im0::INDEX, "read I&M0".into());
    ctl.take_exchanges();
    match read {
        Ok((status, data)) if status.is_ok() => match proto::pnio::im0::Im0Repr::parse(&data) {
            Ok(im) => {
                id.source += " and I&M0";
                id.product_code = Some(format!(
                    "device id {:04X}h, order id {:?}",
                    station.device_id, im.order_id
                ));
                id.revision = Some(im.software_revision.to_string());
                id.serial = Some(im.serial);
            }
            Err(e) => return Some(Err(StepError::malformed("malformed I&M0")(e))),
        },
        Ok((status, _)) => id.source += &format!(" (I&M0 refused: {})", status_hex(status)),
        Err(e) => return Some(Err(step_error(e))),
    }
    Some(Ok(id))
}

fn qualifier(permanent: bool) -> BlockQualifier {
    if permanent {
        BlockQualifier::PERMANENT
    } else {
        BlockQualifier::TEMPORARY
    }
}

fn dcp_result(error: proto::pnio::dcp::BlockError) -> Observation {
    let fields = json!({ "error": error.0, "meaning": error.name() });
    if error == proto::pnio::dcp::BlockError::OK {
        fields.into()
    } else {
        Observation::refused(
            fields,
            Refusal {
                kind: "DCP block error".into(),
                code: u32::from(error.0),
                text: format!("{:02X}h {}", error.0, error.name().unwrap_or("unknown")),
            },
        )
    }
}

fn status_result(status: PnioStatus, fields: Value) -> Observation {
    if status.is_ok() {
        let mut fields = fields;
        fields["status"] = json!(status_hex(status));
        fields.into()
    } else {
        refused(status, fields)
    }
}

fn connect_result(c: Connected) -> Observation {
    let diff: Vec<Value> = c
        .diff
        .iter()
        .flat_map(|d| &d.apis)
        .flat_map(|a| &a.modules)
        .map(|m| {
            json!({
                "slot": m.slot,
                "ident": m.ident,
                "state": m.state.name(),
                "submodules": m.submodules.iter().map(|s| json!({
                    "subslot": s.subslot,
                    "ident": s.ident,
                    "state": s.state.0,
                })).collect::<Vec<_>>(),
            })
        })
        .collect();
    let fields = json!({
        "diff": diff,
        "running": c.ready,
        "prm_end": c.prm_end.map(status_hex),
    });
    status_result(c.status, fields)
}

impl<L: Link + 'static> Binding for PnioBinding<L> {
    /// [`identity_of`] the device found.
    fn identity(&mut self) -> Option<Result<Identity, StepError>> {
        identity_of(&mut self.ctl.borrow_mut())
    }

    fn describe(&self) -> String {
        self.what.clone()
    }

    fn capabilities(&self) -> &[Capability] {
        self.capabilities
    }

    /// The action, then whether the device departed from its manual or the standard on its
    /// own meanwhile (or since the opening): an alarm of a type its manual does not name, an
    /// alarm PDU out of sequence. That fails the step it came by, whatever the step did: a
    /// failure rather than a note, as a controller of these devices acts on their alarms, and
    /// one raised for nothing is as wrong as a wrong answer.
    fn perform(&mut self, action: &Action) -> Result<Observation, StepError> {
        let done = self.act(action)?;
        match self.ctl.borrow_mut().take_departure() {
            Some(d) => Err(StepError::Departed(d.into())),
            None => Ok(done),
        }
    }

    fn finish(&mut self) -> Result<(), CleanupError> {
        self.restore().map_err(CleanupError)
    }

    fn finish_closes(&self) -> bool {
        true
    }

    fn take_exchanges(&mut self) -> Vec<Exchange> {
        // The channel's view is the PPO it meant; the controller's is what went on the wire.
        self.channel.take_exchanges();
        let mut ex = self.ctl.borrow_mut().take_exchanges();
        if ex.len() > 6 {
            let skipped = ex.len() - 4;
            let last = ex.split_off(ex.len() - 2);
            ex.truncate(2);
            ex.push(Exchange {
                sent_hex: String::new(),
                sent: format!("… {skipped} more record calls like these …"),
                received_hex: String::new(),
                received: String::new(),
            });
            ex.extend(last);
        }
        ex.extend(self.cycles_exchange());
        ex
    }
}

/// A cycle's frame of the channel, its outputs provided and its order answered, for the
/// answer once the cycle ran.
struct Provided {
    unit: Unit,
    ppo_type: u8,
    ppo: PpoType,
    pkw: Option<PkwRepr>,
    module: Option<(u16, PpoType)>,
}

/// The channel's DUT: one bus cycle carries the PKW order in the unit's record and the
/// process words in the output CR.
struct PnioDut<L> {
    ctl: Shared<L>,
    product: Product,
    /// The order in the device's record, being answered.
    pending: Option<(Unit, PkwRepr)>,
}

impl<L: Link> PnioDut<L> {
    /// The record of a unit and where it is written (the unit's slot; FI 1's for the
    /// interface).
    fn record_of(&self, unit: Unit) -> Option<(u16, u16)> {
        let (target, fi) = match unit {
            Unit::Interface => (RecordTarget::Interface, Inverter::new(1).ok()?),
            Unit::Inverter(fi) => (RecordTarget::Inverter(fi), fi),
        };
        Some((
            def::record_index(target),
            def::inverter_slot(self.product, fi).ok()?,
        ))
    }

    /// The PKW answer of the order, or "no response" (AK 0) while the device is busy.
    fn order(&mut self, unit: Unit, order: PkwRepr) -> Option<PkwRepr> {
        let (index, slot) = self.record_of(unit)?;
        let mut ctl = self.ctl.borrow_mut();
        if self.pending != Some((unit, order)) {
            let status = ctl
                .write_record(
                    slot,
                    def::IO_SUBSLOT,
                    index,
                    &order.emit_bytes(),
                    format!("IODWrite record {index}: {}", order.describe_order()),
                )
                .ok()?;
            if !status.is_ok() {
                return None;
            }
            self.pending = Some((unit, order));
        }
        let (status, data) = ctl
            .read_record(
                slot,
                def::IO_SUBSLOT,
                index,
                format!("IODRead record {index}"),
            )
            .ok()?;
        if status == def::busy_status() {
            return Some(PkwRepr::default());
        }
        if !status.is_ok() {
            return None;
        }
        self.pending = None;
        PkwRepr::parse(&data).ok()
    }

    /// Provides the channel's `frame` to the inverter's module (and runs its PKW order);
    /// `None` for a frame that is not the channel's or a module not connected.
    fn provide(&mut self, frame: &[u8]) -> Option<Provided> {
        let link = LinkRepr::parse(frame).ok()?;
        let ppo = PpoType::new(link.ppo_type).ok()?;
        let sent = PpoRepr::parse(&link.payload, ppo).ok()?;
        // The inverter's module and what it carries (the channel's PPO has the parameter
        // channel; the module need not).
        let module = match link.unit {
            Unit::Inverter(fi) => {
                let slot = def::inverter_slot(self.product, fi).ok()?;
                Some((slot, module_ppo(&self.ctl.borrow(), self.product, slot)?))
            }
            Unit::Interface => None,
        };
        let bytes = module.map(|(_, t)| module_bytes(t, &sent.pzd));
        let provided: Vec<(u16, &[u8])> = module
            .zip(bytes.as_deref())
            .map(|((slot, _), b)| (slot, b))
            .into_iter()
            .collect();
        self.ctl.borrow_mut().provide(&provided).ok()?;
        let pkw = match sent.pkw {
            Some(o) if o != PkwRepr::default() => Some(self.order(link.unit, o)?),
            other => other,
        };
        Some(Provided {
            unit: link.unit,
            ppo_type: link.ppo_type,
            ppo,
            pkw,
            module,
        })
    }

    /// The channel's answer to `sent` from the cycle's input frame.
    fn answer(&self, sent: Provided) -> Option<Vec<u8>> {
        let ctl = self.ctl.borrow();
        let mut pzd = match sent.module {
            Some((slot, t)) => module_pzd(t, &ctl.input(slot)?.0)?,
            None => Vec::new(),
        };
        pzd.resize(sent.ppo.pzd_words(), 0);
        Some(
            LinkRepr {
                unit: sent.unit,
                ppo_type: sent.ppo_type,
                payload: PpoRepr { pkw: sent.pkw, pzd }.emit(sent.ppo),
            }
            .emit(),
        )
    }
}

impl<L: Link> Dut for PnioDut<L> {
    fn describe(&self) -> String {
        format!("PROFINET IO device ({})", self.product.name())
    }

    fn capabilities(&self) -> &[Capability] {
        &EMBEDDED_CAPABILITIES
    }

    fn cycle_time(&self) -> Duration {
        self.ctl.borrow().cycle()
    }

    fn cycle(&mut self, frame: &[u8]) -> Result<Option<Vec<u8>>, StepError> {
        let Some(sent) = self.provide(frame) else {
            return Ok(None);
        };
        // The consumer's time-out (the input CR's data hold time) is the verdict, not silence.
        if !self.ctl.borrow_mut().exchange_cycle().map_err(step_error)? {
            return Ok(None);
        }
        Ok(self.answer(sent))
    }

    fn inject(&mut self, inverter: Inverter, error: &str) -> Result<(), DutError> {
        let mut ctl = self.ctl.borrow_mut();
        let (io, _) = ctl
            .link_mut()
            .device()
            .ok_or_else(|| DutError("a device on the network cannot be made to fault".into()))?;
        // "lost": the inverter drops off the system bus (the device's alarm 1256).
        if error == LOST {
            return Ok(io.lose_inverter(inverter)?);
        }
        Ok(io.device_mut().inject_fault(inverter, error)?)
    }

    fn observe(&mut self, what: &str, inverter: Inverter) -> Result<Value, DutError> {
        let mut ctl = self.ctl.borrow_mut();
        let (io, now) = ctl
            .link_mut()
            .device()
            .ok_or_else(|| DutError("a device on the network cannot be looked into".into()))?;
        let leds = io.leds(now);
        let mut v = observe_device(io.device_mut(), what, inverter, now)?
            .ok_or_else(|| DutError(format!("cannot observe `{what}` ({OBSERVABLE})")))?;
        if what == "leds" {
            for (name, row) in leds {
                v[name] = json!(row);
            }
        }
        Ok(v)
    }
}
