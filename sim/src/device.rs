//! The simulated bus interface with its inverters, fed link frames (sans-IO).
//!
//! One [`Device`] is one product (SK 550P or a TU3/TU4/CU4 module) with FI 1..=n behind it.
//! Each link frame addresses the interface (data record 100) or one inverter (101..108) and
//! carries a PPO telegram: the parameter channel (PKW) is served from that unit's parameter
//! store, the process data (control word, setpoints) drives that inverter's drive model, and
//! the answer goes back in the same PPO type.
//!
//! Parameter orders take a bus cycle to process, as on a real interface: the first cycle that
//! carries a new order is answered with response label 0 ("no response"), and the order's
//! answer follows in a later cycle — which is why the manuals require the master to repeat an
//! order until its answer arrives (BU 0620 §2.5.6).

use proto::nord::params::ParamDef;
use proto::nord::pkw::PkwRepr;
use proto::nord::ppo::{PpoRepr, PpoType};
use proto::nord::{led, Inverter, ParamNumber, Product};
use std::time::Duration;

use crate::bus_status::{self, BusFlags};
use crate::drive::{Drive, DriveParams, FaultCode, CYCLE_PARAMETERS};
use crate::link::{LinkFrameError, LinkRepr, Unit};
use crate::objects::{abort, Refused};
use crate::pkw_server;
use crate::store::{ParamStore, Target};

/// How long after the last valid process data the "BUS" LED still shows communication.
pub const PROCESS_DATA_WINDOW: Duration = Duration::from_millis(100);

/// A parameter number, checked to be one when compiling.
const fn param(number: i64) -> ParamNumber {
    match ParamNumber::new(number) {
        Ok(p) => p,
        Err(_) => panic!("not a parameter number"),
    }
}
const P513: ParamNumber = param(513);
const P151: ParamNumber = param(151);
const P150: ParamNumber = param(150);
const P152: ParamNumber = param(152);
const P170: ParamNumber = param(170);
const P700: ParamNumber = param(700);
const P701: ParamNumber = param(701);
const P870: ParamNumber = param(870);
const P899: ParamNumber = param(899);
/// P513 [-04] is the Ethernet timeout (BU 0620 §4.5: "[-3] = CANopen, [-4] = Ethernet").
const ELEMENT_ETHERNET: Option<proto::nord::ArrayElement> = match proto::nord::ArrayElement::new(4)
{
    Ok(e) => Some(e),
    Err(_) => None,
};
const E10_3: FaultCode = FaultCode { group: 10, sub: 3 };
const E10_5: FaultCode = FaultCode { group: 10, sub: 5 };

/// P513 [-04] "Telegram timeout time" (Ethernet) of an inverter's store, in 0.1 s: `None` for
/// 0 "Off" and -0.1 "No error", which both make the inverter ignore communication errors on
/// the field bus (BU 0620 §4.5, BU 2100 §8.1 "Parameter P513").
fn ethernet_timeout(store: &ParamStore) -> Option<Duration> {
    // SK 550P: [-04] "Ethernet"; behind the SK TU3-PNT one value (BU 0590 §5.2.1).
    let tenths = store
        .read(P513, None, ELEMENT_ETHERNET)
        .or_else(|_| store.read(P513, None, None))
        .ok()?;
    u64::try_from(tenths)
        .ok()
        .filter(|t| *t > 0)
        .map(|t| Duration::from_millis(100 * t))
}

/// P513 [-04] = -0.1 "Kein Fehler" (BU 2200 §8.1): the inverter ignores all communication
/// errors on the field bus and the system bus.
fn ignores_communication_errors(store: &ParamStore) -> bool {
    store.read(P513, None, ELEMENT_ETHERNET) == Ok(-1)
}

/// A module's P171 software version as the parameter shows it, [-01] version in tenths and
/// [-02] revision: the software of the manual's edition (its document history, §1.1.2).
/// BU 2100 (August 2019): V 1.3 R1 SK TU3-EIP, R5 SK TU4-EIP, R4 SK CU4-EIP; BU 2200 (August
/// 2019): V 1.3 R2 SK TU3-POL, R3 SK TU4-POL, R1 SK CU4-POL (the versions the POWERLINK
/// IdentResponse reports, `proto::nord::epl`); BU 0590 (January 2012, its version list p. 3):
/// V 1.0 R4 SK TU3-PNT. The SK 550P has no P171 (its interface software is P745, BU 0620).
pub(crate) fn software_version(product: Product) -> Option<(i32, i32)> {
    match product {
        Product::Tu3Eip => Some((13, 1)),
        Product::Tu4Eip => Some((13, 5)),
        Product::Cu4Eip => Some((13, 4)),
        Product::Tu3Pol => Some((13, 2)),
        Product::Tu4Pol => Some((13, 3)),
        Product::Cu4Pol => Some((13, 1)),
        Product::Tu3Pnt => Some((10, 4)),
        Product::Sk550p => None,
    }
}

/// Which firmware release the simulator behaves as.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Firmware {
    /// The release the suites are written against.
    #[default]
    Release,
    /// A made-up next release, so that comparing the runs of two releases (`harness diff`) can
    /// be shown and tested on the simulator. It says so where the product has a software
    /// version (the modules' P171 [-02] revision is the release's plus one, BU 2100 §7.1.3,
    /// BU 0590 §5.1.3, BU 2200 §7.1.3) and
    /// behaves differently in one documented way: the SK 550P's "Addressing Mode" P856 leaves
    /// the factory as 2 (DHCP) instead of 1 (BOOTP, BU 0620 §4.2.2), the kind of changed
    /// default a release note lists.
    Next,
}

/// How to build a device.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DeviceConfig {
    /// The product simulated.
    pub product: Product,
    /// Inverters behind the interface, 1..=8.
    pub inverters: u8,
    /// Bus cycles a parameter order takes before its answer appears (at least 1).
    pub answer_delay: u32,
    /// The firmware release simulated.
    pub firmware: Firmware,
}

impl DeviceConfig {
    /// The product with its maximum inverter count and a one-cycle answer delay.
    pub fn new(product: Product) -> Self {
        DeviceConfig {
            product,
            inverters: product.max_inverters(),
            answer_delay: 1,
            firmware: Firmware::Release,
        }
    }
}

/// A frame the device cannot answer; a real device drops it, and so does the driver.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DeviceError {
    /// The link frame is malformed.
    #[error(transparent)]
    Link(#[from] LinkFrameError),
    /// The PPO telegram is malformed or of a type the device does not speak.
    #[error("PPO telegram: {0}")]
    Ppo(String),
    /// The addressed inverter is not on the system bus.
    #[error("FI {0} is not on the system bus (the device has {1} inverters)")]
    NoSuchInverter(u8, u8),
}

/// A unit's parameter channel: the order being processed and the answer shown.
#[derive(Debug)]
struct ParamChannel {
    store: ParamStore,
    order: Option<PkwRepr>,
    due: u32,
    response: PkwRepr,
}

impl ParamChannel {
    fn new(store: ParamStore) -> Self {
        ParamChannel {
            store,
            order: None,
            due: 0,
            response: PkwRepr::default(),
        }
    }

    /// One cycle of the parameter channel: a new order restarts processing and clears the
    /// answer; a repeated order is answered once processed, by the unit's store.
    fn cycle(&mut self, order: PkwRepr, delay: u32, product: Product, unit: Unit) -> PkwRepr {
        let supported = proto::nord::pkw::supported_orders(product, unit_is_first(unit));
        self.cycle_with(order, delay, |store, order| {
            pkw_server::handle_order(store, supported, order)
        })
    }

    /// [`ParamChannel::cycle`], the order processed by `serve`.
    fn cycle_with(
        &mut self,
        order: PkwRepr,
        delay: u32,
        serve: impl FnOnce(&mut ParamStore, &PkwRepr) -> PkwRepr,
    ) -> PkwRepr {
        if order.ak == 0 {
            self.order = None;
            self.response = PkwRepr::default();
        } else if self.order != Some(order) {
            self.order = Some(order);
            self.due = delay.max(1);
            self.response = PkwRepr::default();
        } else if self.due > 0 {
            self.due -= 1;
            if self.due == 0 {
                self.response = serve(&mut self.store, &order);
            }
        }
        self.response
    }
}

/// P740 / P741 [-08]…[-12] "Parameter data In / Out 1…5" of an SK 5xxE from SK 540E (BU 0590
/// §5.2.2, p. 42–43): the parameter transfer's order label (AK), parameter number (PNU), index
/// (IND) and value (PWE 1/2); a unit whose P740/P741 are shorter ignores them.
fn show_parameter_data(store: &mut ParamStore, order: &PkwRepr, answer: &PkwRepr) {
    let words = |p: &PkwRepr| {
        [
            i32::from(p.ak),
            i32::from(p.pnu),
            i32::from(p.ind),
            (p.pwe >> 16) as i32,
            (p.pwe & 0xFFFF) as i32,
        ]
    };
    for (e, w) in (8..).zip(words(order)) {
        store.set_info(740, e, w);
    }
    if answer.ak != 0 {
        for (e, w) in (8..).zip(words(answer)) {
            store.set_info(741, e, w);
        }
    }
}

/// FI 1 of the SK 550P (and the interface itself) is the device the bus interface is built
/// into; inverters reached over the system bus support fewer order labels (BU 0620 §2.5.6.3).
fn unit_is_first(unit: Unit) -> bool {
    match unit {
        Unit::Interface => true,
        Unit::Inverter(i) => i.get() == 1,
    }
}

/// The parameters of inverter `fi` at power-on: factory settings, and P515 [-01] "CAN address"
/// the system-bus address it was commissioned with (BU 0620 §3.1 p. 61: FI 1 32, further FIs
/// 34, 36, …), where `sim::can` puts its node.
fn inverter_store(product: Product, fi: Inverter) -> ParamStore {
    let mut store = ParamStore::new(product, Target::Inverter(fi));
    if fi.get() > 1 {
        let node = proto::nord::can::SystemBusAddress::inverter(fi).get();
        store.set_info(515, 1, i32::from(node));
    }
    store
}

/// The interface's CAN controller on the system bus, as injected.
#[derive(Debug, Clone, Copy, Default)]
struct CanState {
    /// "Bus Warning".
    warning: bool,
    /// "Bus Off" since then.
    off_since: Option<Duration>,
    /// The inverters have lost the interface since it went off the bus.
    lost: bool,
}

/// One inverter: its parameters and its drive.
#[derive(Debug)]
struct InverterUnit {
    params: ParamChannel,
    drive: Drive,
    /// When the last valid process data (control bit 10) arrived.
    last_process: Option<Duration>,
    /// Its P513 time-out as the monitor saw it last, and since when (as the module's P151).
    p513_seen: (Option<Duration>, Duration),
    /// What P740/P741 [-01]…[-06] show, so that a cycle writes only the elements that change.
    shown: Option<([u16; 6], [u16; 6])>,
    /// The extended code (P700 [-04]) of an error whose cause names one row of several with
    /// the same P700 number (BU 0620 §5.3).
    extended: Option<(FaultCode, u16)>,
    /// What P700 [-01] shows (only [`InverterUnit::show_fault`] writes it), once read.
    p700: Option<i32>,
    /// The drive's settings as the store held them last.
    settings: Option<Settings>,
    /// Its own node's CAN controller on the system bus, as the segment last reported it
    /// ([`Device::set_node_bus`]).
    node_bus: led::BusState,
}

impl InverterUnit {
    /// One process-data cycle: the control word and setpoints drive the inverter, whose status
    /// word and actual values come back (six words).
    fn process(&mut self, control: u16, setpoints: &[u16], now: Duration) -> [u16; 6] {
        let word = proto::nord::control::ControlWord(control);
        let set = proto::nord::ParamSet::new(i64::from(word.parameter_set())).ok();
        if word.valid() {
            self.last_process = Some(now);
        }
        let store = StoreView(&self.params.store, set);
        let revision = self.params.store.settings_revision();
        let settings = match self.settings.take() {
            Some(s) if s.revision == revision && s.set == set => s,
            _ => Settings::read(&store, revision),
        };
        let out = self.drive.cycle(
            control,
            setpoints,
            &Cached {
                settings: &settings,
                store,
            },
            now,
        );
        self.settings = Some(settings);
        // Information parameters mirror the process data and the present error
        // (BU 0620 §4.5: P740 PZD bus in, P741 PZD bus out, P700 [-01] present error). This
        // runs every bus cycle for every inverter: only the elements that change are written.
        let given = 1 + setpoints.len().min(5);
        let mut shown = self.shown.unwrap_or_default();
        let mut inputs = shown.0;
        inputs[0] = control;
        for (d, w) in inputs[1..given].iter_mut().zip(setpoints) {
            *d = *w;
        }
        let mut outputs = [out.status, 0, 0, 0, 0, 0];
        outputs[1..].copy_from_slice(&out.actuals);
        let first = self.shown.is_none();
        let store = &mut self.params.store;
        for (number, new, held) in [(740, inputs, &mut shown.0), (741, outputs, &mut shown.1)] {
            for (e, (w, h)) in (1u8..).zip(new.iter().zip(held.iter_mut())) {
                let written = number == 741 || usize::from(e) <= given;
                if written && (first || w != h) {
                    store.set_info(number, e, i32::from(*w));
                    *h = *w;
                }
            }
        }
        for (e, w) in (7u8..).zip(setpoints.iter().skip(5)) {
            store.set_info(740, e, i32::from(*w));
        }
        self.shown = Some(shown);
        self.show_fault();
        outputs
    }

    /// P700 [-01] shows the present error as soon as it is raised, not only with the next
    /// process data, and [-04] its extended code ("DS402: Extended error number", BU 0620
    /// §5.3: E10.3 → 7592h; E10.5 of a refused protocol change → 7598h). A new error goes to
    /// P701 "Last error" [-01], the older ones one element down (BU 0620 §4.5, §5.3: "Error
    /// messages … are depicted with parameters P700 and P701").
    fn show_fault(&mut self) {
        let code = self.drive.fault().or(self.drive.pending_fault());
        let p700 = code.map_or(0, FaultCode::p700);
        let store = &mut self.params.store;
        let element = |e: i64| proto::nord::ArrayElement::new(e).ok();
        let shown = self
            .p700
            .unwrap_or_else(|| store.read(P700, None, element(1)).unwrap_or(0));
        if i32::from(p700) == shown {
            // Runs every bus cycle for every inverter: nothing to do while the error stays.
            self.p700 = Some(shown);
            return;
        }
        self.p700 = Some(i32::from(p700));
        if p700 != 0 {
            let last: Vec<i32> = (1..=4)
                .map(|e| store.read(P701, None, element(e)).unwrap_or(0))
                .collect();
            for (e, v) in (2..).zip(last) {
                store.set_info(701, e, v);
            }
            store.set_info(701, 1, i32::from(p700));
        }
        let extended = match self.extended {
            Some((c, x)) if Some(c) == code => x,
            _ => proto::nord::errors::extended_code(p700),
        };
        store.set_info(700, 1, i32::from(p700));
        store.set_info(700, 4, i32::from(extended));
    }
}

/// Parameters the drive reads, from the inverter's store, in the parameter set the control
/// word selects (bits 14–15, BU 0620 §6.1.2.1).
struct StoreView<'a>(&'a ParamStore, Option<proto::nord::ParamSet>);

impl DriveParams for StoreView<'_> {
    fn get(&self, number: u16, element: Option<u8>) -> Option<i32> {
        let number = ParamNumber::new(i64::from(number)).ok()?;
        let element = element.and_then(|e| proto::nord::ArrayElement::new(i64::from(e)).ok());
        self.0.read(number, self.1, element).ok()
    }
}

/// The values of [`CYCLE_PARAMETERS`] in one parameter set at one settings revision of an
/// inverter's store: the drive reads them on every bus cycle, and they change only when a
/// parameter is written.
#[derive(Debug)]
struct Settings {
    revision: u64,
    set: Option<proto::nord::ParamSet>,
    values: [Option<i32>; CYCLE_PARAMETERS.len()],
}

impl Settings {
    fn read(store: &StoreView, revision: u64) -> Settings {
        Settings {
            revision,
            set: store.1,
            values: CYCLE_PARAMETERS.map(|(number, element)| store.get(number, element)),
        }
    }
}

/// The drive's view of the store with [`Settings`] in front.
struct Cached<'a> {
    settings: &'a Settings,
    store: StoreView<'a>,
}

impl DriveParams for Cached<'_> {
    fn get(&self, number: u16, element: Option<u8>) -> Option<i32> {
        match CYCLE_PARAMETERS
            .iter()
            .position(|p| *p == (number, element))
        {
            Some(i) => self.settings.values[i],
            None => self.store.get(number, element),
        }
    }
}

/// The simulated interface and its inverters.
#[derive(Debug)]
pub struct Device {
    config: DeviceConfig,
    interface: ParamChannel,
    inverters: Vec<InverterUnit>,
    fieldbus_timeout: bool,
    /// The module's P151 time-out as the monitor saw it last, and since when: a time-out just
    /// set watches from the next valid process data on, not from process data that stopped
    /// long before (the inverters' P513 alike).
    p151_seen: (Option<Duration>, Duration),
    /// Inverters lost from the system bus (bit n: FI n + 1), no longer online.
    lost: u8,
    /// The module's configuration is refused (P173 bit 5, BU 2200 §7.1.3).
    config_error: bool,
    /// The flags the bus status parameters show (written again only when they change: the
    /// monitoring runs on every frame).
    shown: Option<BusFlags>,
    /// The interface word of output assembly 110 (the SK xU4-EIP's digital outputs).
    module_outputs: u16,
    /// Per inverter, the words the interface's display parameters show
    /// ([`Device::show_process_data`]).
    process_shown: Vec<Option<([u16; 6], [u16; 6])>>,
    /// The gateway to the inverters' parameters over the system bus.
    gateway: crate::system_bus::Gateway,
    /// The system bus's frames, recorded once a tap asked for them ([`Device::tap_system_bus`]).
    tap: Option<crate::system_bus::Tap>,
    /// The interface's CAN controller on the system bus (`inject: { error: bus-off }`).
    can_state: CanState,
    /// The latest time the device was given.
    now: Duration,
}

impl Device {
    /// A device in its power-on state.
    pub fn new(config: DeviceConfig) -> Device {
        let count = config.inverters.clamp(1, 8);
        let mut inverters: Vec<InverterUnit> = (1..=count)
            .filter_map(|n| Inverter::new(i64::from(n)).ok())
            .map(|i| InverterUnit {
                params: ParamChannel::new(inverter_store(config.product, i)),
                drive: Drive::new(),
                last_process: None,
                p513_seen: (None, Duration::ZERO),
                shown: None,
                extended: None,
                p700: None,
                settings: None,
                node_bus: led::BusState::Active,
            })
            .collect();
        // The XU5 extension of the SK 550P (BU 0620 §4.5, p. 91): FI 1 carries the Industrial
        // Ethernet interface (P744 [-02] = 2 "Industrial Ethernet present", P746 [-03] = 1
        // "Ready", P745 [-07]/[-08] the interface software V 1.1 R1 of §1.1.2); the further
        // SK 5x0P on the system bus have none (P744 [-02] = 0 "No extension present").
        if config.product == Product::Sk550p {
            if let Some(fi1) = inverters.first_mut() {
                let store = &mut fi1.params.store;
                store.set_info(744, 2, 2);
                store.set_info(745, 7, 11);
                store.set_info(745, 8, 1);
                store.set_info(746, 3, 1);
            }
        }
        // P745 "Module version" of the inverters behind an SK TU3/TU4 EtherNet/IP or POWERLINK
        // module (BU 2100 §7.2 p. 55, BU 2200 §7.2 p. 60; "—" for the SK CU4): the module's
        // software version as P171 [-01] shows it (no value printed; BU 0590 §5.2.2 names P745
        // the technology unit's software version).
        if let (Some(_), Some((version, _))) = (
            proto::nord::can::p746_interface_id(config.product),
            software_version(config.product),
        ) {
            for unit in inverters.iter_mut() {
                unit.params.store.set_info(745, 1, version);
            }
        }
        let mut interface = ParamChannel::new(ParamStore::new(config.product, Target::Interface));
        // P172 "Configuration level" (BU 2100 §7.1.3, BU 0590 §5.1.3, BU 2200 §7.1.3): 0 CU4,
        // 1 TU4, 2 TU3 (the simulated TU3 modules have no DIP-switch addressing: never 3).
        let level = match config.product {
            Product::Cu4Eip | Product::Cu4Pol => Some(0),
            Product::Tu4Eip | Product::Tu4Pol => Some(1),
            Product::Tu3Eip | Product::Tu3Pol | Product::Tu3Pnt => Some(2),
            Product::Sk550p => None,
        };
        if let Some(l) = level {
            interface.store.set_info(172, 1, l);
        }
        // The MAC address's first three bytes: NORD's manufacturer id F0.5F.5A (BU 0620 §4.4.2
        // P878, BU 2200 §7.1.4 P181); the SK TU3-PNT's "PROFINET identification" 00.0E.CF
        // (BU 0590 §5.1.4 P181, example 00:0E:CF:03:60:00). The EtherNet/IP adapter sets the
        // whole address of its products at power-on.
        let mac: Option<(u16, [i32; 3])> = match config.product {
            Product::Sk550p => Some((878, [0xF0, 0x5F, 0x5A])),
            Product::Tu3Pol | Product::Tu4Pol | Product::Cu4Pol => Some((181, [0xF0, 0x5F, 0x5A])),
            Product::Tu3Pnt => Some((181, [0x00, 0x0E, 0xCF])),
            Product::Tu3Eip | Product::Tu4Eip | Product::Cu4Eip => None,
        };
        if let Some((number, id)) = mac {
            for (e, b) in (1..).zip(id) {
                interface.store.set_info(number, e, b);
            }
        }
        // P171 "Software version" of the modules: [-01] version (one decimal), [-02] revision,
        // [-03] 0 = standard version (BU 2100 §7.1.3 p. 50, BU 0590 §5.1.3 p. 35, BU 2200
        // §7.1.3 p. 53). The next firmware is the release's next revision.
        if let Some((version, revision)) = software_version(config.product) {
            let revision = match config.firmware {
                Firmware::Release => revision,
                Firmware::Next => revision + 1,
            };
            interface.store.set_info(171, 1, version);
            interface.store.set_info(171, 2, revision);
        }
        if config.product == Product::Tu3Pnt {
            // [-04]…[-06]: the rest of the example address 00:0E:CF:03:60:00 (BU 0590 §5.1.4),
            // the one the PROFINET station answers DCP with.
            for (e, b) in (4..).zip([0x03, 0x60, 0x00]) {
                interface.store.set_info(181, e, b);
            }
        }
        if config.firmware == Firmware::Next {
            interface.store.set_info(856, 1, 2);
        }
        Device {
            config: DeviceConfig {
                inverters: count,
                ..config
            },
            interface,
            inverters,
            fieldbus_timeout: false,
            p151_seen: (None, Duration::ZERO),
            lost: 0,
            config_error: false,
            shown: None,
            module_outputs: 0,
            process_shown: vec![None; usize::from(count)],
            gateway: crate::system_bus::Gateway::new(config.product, count),
            tap: None,
            now: Duration::ZERO,
            can_state: CanState::default(),
        }
    }

    /// The frames the bus interface exchanged with its inverters on the system bus since the
    /// last call (`crate::system_bus`), each with its time; the first call attaches the tap
    /// and returns none (nothing is recorded without one).
    pub fn tap_system_bus(&mut self) -> Vec<(Duration, proto::can::CanFrame)> {
        match self.tap.as_mut() {
            Some(tap) => tap.take(),
            None => {
                self.tap = Some(crate::system_bus::Tap::new(self.config.product));
                Vec::new()
            }
        }
    }

    /// A field-bus read of sub-index `sub` (`proto::nord::addr::sdo_subindex`) of parameter
    /// `number` of `unit`: over the system bus, an SDO upload from the inverter's node, when the
    /// unit is an inverter on it ([`crate::system_bus::Gateway`]); else from the unit's own
    /// store. The one way the field buses' parameter objects (CIP, CoE, POWERLINK) read a
    /// parameter's value.
    pub(crate) fn gateway_read(
        &mut self,
        unit: Unit,
        number: ParamNumber,
        sub: u8,
    ) -> Result<Vec<u8>, Refused> {
        self.gateway_access(
            unit,
            number,
            |gateway, fi, store, index, wire| gateway.upload(fi, store, index, sub, wire),
            |store, def| crate::objects::read_value(store, number, def, sub),
        )
    }

    /// A field-bus write of `data` to sub-index `sub` of parameter `number` of `unit`, as
    /// [`Device::gateway_read`] reads: an SDO download through the inverter's node over the
    /// system bus, or to the unit's own store (kept in EEPROM, as a bus write is).
    pub(crate) fn gateway_write(
        &mut self,
        unit: Unit,
        number: ParamNumber,
        sub: u8,
        data: &[u8],
    ) -> Result<(), Refused> {
        self.gateway_access(
            unit,
            number,
            |gateway, fi, store, index, wire| gateway.download(fi, store, index, sub, data, wire),
            |store, def| crate::objects::write_value(store, number, def, sub, data),
        )
    }

    /// A parameter access through the gateway (`remote`, given the frames to fill) or on the
    /// unit's own store (`local`). The frames exchanged are recorded while a tap is attached.
    ///
    /// An injected "bus off" of the interface's CAN controller (`inject: { error: bus-off }`)
    /// is the bus status and the inverters' monitoring of it; the gateway's parameter access
    /// still reaches the nodes then, unrecorded, as the device reached its inverters before the
    /// gateway was real (refusing it, 08000020h, would change what the cases that inject it
    /// see).
    fn gateway_access<T>(
        &mut self,
        unit: Unit,
        number: ParamNumber,
        remote: impl FnOnce(
            &mut crate::system_bus::Gateway,
            Inverter,
            &mut ParamStore,
            u16,
            &mut Vec<proto::can::CanFrame>,
        ) -> Result<T, Refused>,
        local: impl FnOnce(&mut ParamStore, &'static ParamDef) -> Result<T, Refused>,
    ) -> Result<T, Refused> {
        let fi = match unit {
            Unit::Inverter(fi) if self.gateway.reaches(fi) => fi,
            _ => {
                let store = self
                    .store(unit)
                    .map_err(|_| Refused::from(abort::NO_INVERTER))?;
                let def = store.def(number).ok_or(Refused::from(abort::NO_OBJECT))?;
                return local(store, def);
            }
        };
        let Some(unit) = self.inverters.get_mut(usize::from(fi.get()) - 1) else {
            return Err(abort::NO_INVERTER.into());
        };
        let index = proto::nord::ecat::PARAMETER_BASE + number.get();
        let mut wire = Vec::new();
        let result = remote(
            &mut self.gateway,
            fi,
            &mut unit.params.store,
            index,
            &mut wire,
        );
        if let (Some(tap), None) = (self.tap.as_mut(), self.can_state.off_since) {
            tap.exchanged(&wire, self.now);
        }
        result
    }

    /// FI `fi`'s node's SDO server, as the gateway reaches it.
    #[cfg(test)]
    pub(crate) fn node_server(&self, fi: Inverter) -> Option<&crate::sdo_server::SdoServer> {
        self.gateway.server(fi)
    }

    /// The configuration.
    pub fn config(&self) -> DeviceConfig {
        self.config
    }

    fn inverter_mut(&mut self, i: Inverter) -> Result<&mut InverterUnit, DeviceError> {
        let count = self.config.inverters;
        self.inverters
            .get_mut(usize::from(i.get()) - 1)
            .ok_or(DeviceError::NoSuchInverter(i.get(), count))
    }

    /// Telegram monitoring and bus status, evaluated whenever a frame arrives.
    ///
    /// - P513 [-04] "Telegram timeout time" (Ethernet, 0.1 s; 0 = off): an inverter that had
    ///   valid process data and gets none for longer raises E10.3 (BU 0620 §5.1, §5.3: 7592h).
    /// - P151 "Timeout for external bus" of a module (ms; EtherNet/IP: 0 = control-word
    ///   monitoring off, -1 = all monitoring off, BU 2100 §7.1.1; POWERLINK: 0 = monitoring
    ///   off, BU 2200 §7.1.1): the same for the module's telegrams, E10.3 "Timeout by
    ///   P151/P513" (BU 2100 §7.1.1: "Invalid control word set (e.g. PLC to Stop)", 1 s → E10.3).
    /// - the bus status (P872 of the SK 550P, P173 and P170 of the modules; see
    ///   [`bus_status`]): ready, cyclic communication, field-bus timeout, timeout P513/P151
    ///   (while an inverter shows E10.3), the inverters online.
    fn monitor(&mut self, now: Duration) {
        self.now = now;
        self.show_relays();
        let mut flags = BusFlags {
            fieldbus_timeout: self.fieldbus_timeout,
            config_error: self.config_error,
            online: self.online(),
            lost: self.lost,
            bus_warning: self.can_state.warning,
            bus_off: self.can_state.off_since.is_some(),
            ..BusFlags::default()
        };
        self.lose_behind_bus_off(now);
        // Each product's P151 by its own manual (`proto::nord::can::p151_monitoring`): only a
        // time-out in ms watches the telegrams.
        let p151_monitoring = self.p151_monitoring();
        let p151 = match p151_monitoring {
            Some(proto::nord::can::P151Monitoring::Timeout(ms)) => {
                Some(Duration::from_millis(u64::from(ms)))
            }
            _ => None,
        };
        // P151 switching all monitoring off (BU 2100 -1, BU 2200 0 "Überwachung Aus") leaves the
        // field bus unwatched: on the SK CU4/TU4 the field-bus timeout is P151, "the inverter
        // itself does not monitor the communication on the field-bus level" (BU 2200 §8.1,
        // BU 2100 §8.1), so the inverters' P513 raises no E10.3 for it either.
        let fieldbus_off = p151_monitoring == Some(proto::nord::can::P151Monitoring::Off);
        if p151 != self.p151_seen.0 {
            self.p151_seen = (p151, now);
        }
        let p151_set_at = self.p151_seen.1;
        for unit in self.inverters.iter_mut() {
            // Raised and shown in P700 (a bus watchdog's E10.3 when no cycle runs to take it
            // into the status machine) counts as much as taken.
            if unit.drive.fault() == Some(E10_3) || unit.drive.pending_fault() == Some(E10_3) {
                flags.telegram_timeout = true;
            }
            let Some(last) = unit.last_process else {
                continue;
            };
            let silent = now.saturating_sub(last);
            if silent <= PROCESS_DATA_WINDOW {
                flags.cyclic = true;
            }
            let p513 = ethernet_timeout(&unit.params.store).filter(|_| !fieldbus_off);
            if p513 != unit.p513_seen.0 {
                unit.p513_seen = (p513, now);
            }
            // A time-out just set watches from the next valid telegram on (BU 0590 §4.1.7: "the
            // monitoring is activated with the first valid telegram").
            let watched = |set_at: Duration| last >= set_at;
            // P513 = -0.1 "Kein Fehler": the inverter ignores every communication error, the
            // module's P151 time-out included, and keeps its state (BU 2200 §8.1 "Parameter
            // P513", BU 2100 §8.1).
            let p151 = p151.filter(|_| !ignores_communication_errors(&unit.params.store));
            if p513.is_some_and(|l| watched(unit.p513_seen.1) && silent > l)
                || p151.is_some_and(|l| watched(p151_set_at) && silent > l)
            {
                if unit.drive.fault().is_none() {
                    unit.drive.inject_fault(E10_3);
                    unit.show_fault();
                }
                flags.telegram_timeout = true;
            }
        }
        self.show_module_status(now);
        if self.shown != Some(flags) {
            for (number, element, value) in
                bus_status::status_parameters(self.config.product, flags)
            {
                self.interface.store.set_info(number, element, value);
            }
            let was = self.shown.is_some_and(|f| f.telegram_timeout);
            let present = self
                .interface
                .store
                .read(P170, None, proto::nord::ArrayElement::new(1).ok())
                .unwrap_or(0);
            for (number, element, value) in
                bus_status::present_error(self.config.product, was, flags.telegram_timeout, present)
            {
                self.interface.store.set_info(number, element, value);
            }
            // Bus off: the module's P170 shows 103.0 "System bus Off" (BU 2100 §8.3, BU 2200
            // §8.4), unless another error is present.
            if let (true, Some(code), 0) = (
                flags.bus_off,
                proto::nord::can::p170_bus_off(self.config.product),
                self.interface
                    .store
                    .read(P170, None, proto::nord::ArrayElement::new(1).ok())
                    .unwrap_or(0),
            ) {
                self.interface.store.set_info(170, 1, i32::from(code));
            }
            self.shown = Some(flags);
        }
        self.settle_interface();
        self.change_protocol(now);
    }

    /// P153 [-02] "TxPDO Inhibit Time" of an SK CU4/TU4 module, µs: "the pause time for the
    /// system bus in order to reduce the bus load" (BU 2100 §7.1.1 p. 46, BU 2200 §7.1.1 p. 49),
    /// the least time between two process-data cycles its gateway puts on the system bus; 0
    /// for the products without P153.
    fn pdo_pause_us(&self) -> u32 {
        if !proto::nord::can::has_p153_p154(self.config.product) {
            return 0;
        }
        let p153 = ParamNumber::new(153).ok();
        let second = proto::nord::ArrayElement::new(2).ok();
        p153.and_then(|p| self.interface.store.read(p, None, second).ok())
            .and_then(|ms| u32::try_from(ms).ok())
            .map_or(0, |ms| ms * 1000)
    }

    /// P746 "Module status" of each inverter behind an EtherNet/IP or POWERLINK module (BU 2100
    /// §7.2 p. 55, BU 2200 §7.2 p. 60; `proto::nord::can::p746_status`): bit 0 the interface
    /// initialised (from power-on), bit 1 its process data within [`PROCESS_DATA_WINDOW`],
    /// error 011 "P513 timeout" while it shows E10.3 (its telegram monitoring, P513 or the
    /// module's P151, tripped), else 010 "Bus timeout" while the field bus's watchdog has
    /// tripped (P173 bit 2), else 000. Which of the two a P151 trip shows is not stated; E10.3
    /// is "Timeout by P151/P513" (BU 2100 §7.1.1), so the simulator shows 011.
    fn show_module_status(&mut self, now: Duration) {
        use proto::nord::can::{p746_status, P746Error};
        let product = self.config.product;
        let bus_timeout = self.fieldbus_timeout;
        for unit in self.inverters.iter_mut() {
            let cyclic = unit
                .last_process
                .is_some_and(|last| now.saturating_sub(last) <= PROCESS_DATA_WINDOW);
            let timeout =
                unit.drive.fault() == Some(E10_3) || unit.drive.pending_fault() == Some(E10_3);
            let error = match (timeout, bus_timeout) {
                (true, _) => P746Error::P513Timeout,
                (false, true) => P746Error::BusTimeout,
                (false, false) => P746Error::None,
            };
            if let Some(value) = p746_status(product, true, cyclic, error) {
                unit.params.store.set_info(746, 1, value);
            }
        }
    }

    /// What a write to the interface's own parameters sets off at once: P150's outputs, P152's
    /// factory settings. Runs with the monitoring; endpoints that write parameters themselves
    /// (SDO) call it after the write.
    pub(crate) fn settle_interface(&mut self) {
        self.set_relays();
        self.factory_setting();
    }

    /// P152 "Factory setting" of a module (BU 2100 §7.1.1 p. 46, BU 2200 §7.1.1 p. 48, BU 0590
    /// §5.1.1 p. 34): 1 loads the factory settings of all the bus interface's setting
    /// parameters, 2 those of its basic parameters (the NORD standard parameters P15x: "the
    /// basic settings of the bus interface can be made via NORD standard parameters"), 3 the
    /// i-parameters P800…P830 (which the simulated modules do not have); then P152 "returns
    /// automatically to 0".
    fn factory_setting(&mut self) {
        let Ok(p152 @ 1..) = self.interface.store.read(P152, None, None) else {
            return;
        };
        let which: Option<fn(u16) -> bool> = match p152 {
            1 => Some(|_| true),
            2 => Some(|n| (150..=159).contains(&n)),
            3 => Some(|n| (800..=830).contains(&n)),
            _ => None,
        };
        if let Some(which) = which {
            self.interface.store.load_factory_settings(which);
        }
        self.interface.store.set_info(152, 1, 0);
    }

    /// P150 "Relais setzen" of the modules that have it (BU 2200 §7.1.1, p. 48; BU 2100
    /// §7.1.1): 1…4 set the digital outputs whatever the bus says, shown in P175 "Zustand
    /// Relais" (bit 0 DO1, bit 1 DO2, BU 2200 §7.1.3); 0 "Über Bus" leaves them to the bus.
    pub(crate) fn set_relays(&mut self) {
        let Ok(p150) = self.interface.store.read(P150, None, None) else {
            return;
        };
        if let Some(relays) = relays_of(p150) {
            self.interface.store.set_info(175, 1, relays);
        }
    }

    /// P899 "Changing the bus protocol" (BU 0620 §4.1): a value 1..4 changes the protocol
    /// (shown in P870) and P899 returns to 0 — unless process data (control via Ethernet) has
    /// run, when the change is refused with E10.5 "Condition for change of field bus
    /// protocol not present" (7598h).
    fn change_protocol(&mut self, now: Duration) {
        let wanted = self.interface.store.read(P899, None, None).unwrap_or(0);
        if wanted == 0 {
            return;
        }
        let busy = self.inverters.iter().any(|u| {
            u.last_process
                .is_some_and(|t| now.saturating_sub(t) <= PROCESS_DATA_WINDOW)
        });
        if busy {
            if let Some(fi1) = self.inverters.first_mut() {
                fi1.drive.inject_fault(E10_5);
                // "Condition for change of field bus protocol not present" (BU 0620 §5.3).
                fi1.extended = Some((E10_5, 0x7598));
            }
        } else {
            self.interface.store.set_info(870, 1, wanted);
        }
        self.interface.store.set_info(899, 1, 0);
    }

    /// Handles one link frame at time `now`, returning the answer frame.
    pub fn handle(&mut self, frame: &[u8], now: Duration) -> Result<Vec<u8>, DeviceError> {
        self.monitor(now);
        let link = LinkRepr::parse(frame)?;
        let ppo_type = PpoType::new(link.ppo_type).map_err(|e| DeviceError::Ppo(e.to_string()))?;
        let ppo =
            PpoRepr::parse(&link.payload, ppo_type).map_err(|e| DeviceError::Ppo(e.to_string()))?;
        let pkw = match ppo.pkw {
            Some(o) => Some(self.parameter_order(link.unit, o)?),
            None => None,
        };
        let (pkw, pzd) = match link.unit {
            Unit::Interface => (pkw, vec![0; ppo.pzd.len()]),
            Unit::Inverter(i) => {
                let control = ppo.pzd.first().copied().unwrap_or(0);
                let setpoints = ppo.pzd.get(1..).unwrap_or_default();
                let answer = self.process_monitored(i, control, setpoints, now)?;
                let mut pzd = answer.to_vec();
                pzd.resize(ppo.pzd.len(), 0);
                self.show_process_data(i, Some(ppo_type), &ppo.pzd, &pzd);
                (pkw, pzd)
            }
        };
        let answer = PpoRepr { pkw, pzd };
        Ok(LinkRepr {
            unit: link.unit,
            ppo_type: link.ppo_type,
            payload: answer.emit(ppo_type),
        }
        .emit())
    }

    /// One cycle of a unit's parameter channel (a PKW order in a PPO, or one write or read
    /// of a parameter data record): a new order starts processing, the same order again is
    /// answered once processed (`answer_delay` cycles), "no response" (AK 0) until then.
    pub fn parameter_order(&mut self, unit: Unit, order: PkwRepr) -> Result<PkwRepr, DeviceError> {
        let (product, delay) = (self.config.product, self.config.answer_delay);
        match unit {
            Unit::Interface => {
                let answer = self.interface.cycle(order, delay, product, unit);
                self.adopt_ip_settings(&order, &answer);
                Ok(answer)
            }
            Unit::Inverter(i) => {
                let count = self.config.inverters;
                let params = &mut self
                    .inverters
                    .get_mut(usize::from(i.get()) - 1)
                    .ok_or(DeviceError::NoSuchInverter(i.get(), count))?
                    .params;
                let supported = proto::nord::pkw::supported_orders(product, unit_is_first(unit));
                let gateway = &mut self.gateway;
                // Behind the gateway, reads and EEPROM changes are SDO transfers with the
                // inverter's node (`crate::system_bus::serve_order`).
                let mut wire = Vec::new();
                let answer = params.cycle_with(order, delay, |store, order| {
                    crate::system_bus::serve_order(gateway, i, store, supported, order, &mut wire)
                        .unwrap_or_else(|| pkw_server::handle_order(store, supported, order))
                });
                show_parameter_data(&mut params.store, &order, &answer);
                if let (Some(tap), None) = (self.tap.as_mut(), self.can_state.off_since) {
                    tap.exchanged(&wire, self.now);
                    self.tap_order(i, &order, &answer);
                }
                Ok(answer)
            }
        }
    }

    /// A PKW order to FI `fi` the inverter answered, for the tap's image of the orders the
    /// gateway does not carry over the system bus (`crate::system_bus::carries`: the changes
    /// in RAM only, and every order to the SK 550P's own FI 1 is no system-bus traffic
    /// anyway): once per order and answer (the order repeats every cycle until it changes).
    /// The manuals map no PKW error number to an abort code: a refused order shows as abort
    /// 0800 0000h "general error".
    fn tap_order(&mut self, fi: Inverter, order: &PkwRepr, answer: &PkwRepr) {
        use proto::nord::params::Width;
        use proto::nord::pkw::{Ind, OrderLabel, ResponseLabel};
        let label = OrderLabel(order.ak);
        let read = matches!(
            label,
            OrderLabel::REQUEST_VALUE | OrderLabel::REQUEST_ARRAY_VALUE
        );
        if answer.ak == 0 || !(read || label.is_change()) {
            return;
        }
        let Ok(number) = ParamNumber::new(i64::from(order.parameter())) else {
            return;
        };
        let Some(def) = self
            .inverter_mut(fi)
            .ok()
            .and_then(|u| u.params.store.def(number))
        else {
            return;
        };
        let carried = self.gateway.reaches(fi) && crate::system_bus::carries(label);
        let Some(tap) = self.tap.as_mut() else {
            return;
        };
        if !tap.first_answer(fi, order.emit_bytes(), answer.emit_bytes()) || carried {
            return;
        }
        let ind = Ind(order.ind);
        let set = def
            .set_dependent
            .then(|| proto::nord::ParamSet::new(i64::from(ind.set())).ok())
            .flatten();
        let element = match (def.array.is_some(), def.set_dependent) {
            (false, _) => None,
            (true, true) => proto::nord::ArrayElement::new(i64::from(ind.element())).ok(),
            (true, false) => proto::nord::ArrayElement::new(i64::from(ind.subindex()) + 1).ok(),
        };
        let sub = proto::nord::addr::sdo_subindex(set, element);
        let width = match def.width {
            Width::Word => 2,
            Width::Dword => 4,
        };
        let refused = (ResponseLabel(answer.ak) == ResponseLabel::CANNOT_EXECUTE)
            .then_some(proto::nord::errors::SdoAbort(0x0800_0000));
        let index = proto::nord::ecat::PARAMETER_BASE + number.get();
        let now = self.now;
        let value = |r: &PkwRepr| r.value().to_le_bytes();
        let (sent, back) = (value(order), value(answer));
        let access = match (read, refused) {
            (true, None) => crate::system_bus::Access::Read(Ok(&back[..width])),
            (true, Some(code)) => crate::system_bus::Access::Read(Err(code)),
            (false, r) => crate::system_bus::Access::Write(&sent[..width], r.map_or(Ok(()), Err)),
        };
        tap.parameter(fi, index, sub, access, now);
    }

    /// The present IP settings show a saved one: P877 "Present IP gateway" the gateway of P852
    /// (BU 0620 §4.4.3, p. 88), and under PROFINET IO (P870 = 1) P875 / P876 the address and
    /// mask of P850 / P851 (§3.8.1 p. 72) — once element [-04] is written, which saves them
    /// (§4.2.4 p. 82–83: "only saved after a value is entered in the index [-04]"; the store
    /// keeps [-01]…[-03] until then, and corrects or refuses a mask that does not conform).
    fn adopt_ip_settings(&mut self, order: &PkwRepr, answer: &PkwRepr) {
        let label = proto::nord::pkw::OrderLabel(order.ak);
        let written = label.is_array()
            && label != proto::nord::pkw::OrderLabel::REQUEST_ARRAY_VALUE
            && answer.ak != 0
            && answer.ak != proto::nord::pkw::ResponseLabel::CANNOT_EXECUTE.0;
        if !(written && proto::nord::pkw::Ind(order.ind).subindex() == 3) {
            return;
        }
        let store = &mut self.interface.store;
        let profinet = store
            .read(P870, None, None)
            .is_ok_and(|p| p == i32::from(proto::nord::pnio::BUS_PROTOCOL_CODE));
        let shown: &[(u16, u16)] = match order.pnu {
            852 | 1852 => &[(852, 877)],
            850 | 1850 if profinet => &[(850, 875), (851, 876)],
            851 | 1851 if profinet => &[(851, 876)],
            _ => return,
        };
        for &(from, to) in shown {
            let Ok(n) = ParamNumber::new(i64::from(from)) else {
                continue;
            };
            for e in 1..=4u8 {
                let element = proto::nord::ArrayElement::new(i64::from(e)).ok();
                if let Ok(v) = store.read(n, None, element) {
                    store.set_info(to, e, v);
                }
            }
        }
    }

    /// The process-data display parameters for one inverter's words, whichever bus carried
    /// them (`ppo` for a PPO frame):
    /// - SK 550P (BU 0620 §4.3): P873 "Process data bus In" / P874 "Process data bus Out"
    ///   elements 6·(FI−1)+1..+6.
    /// - SK TU3-PNT (BU 0590 §5.1.3–§5.1.4, p. 36–37): P176 [-02] control word, [-03]/[-04]
    ///   setpoints 1/2; P177 [-02] status word, [-03]/[-04] actual values 1/2; P180 [-03] (slot
    ///   3, the FI) the module id of the PPO type (3 = PPO3 … 7 = PPO2).
    /// - SK TU3/TU4/CU4-POL (BU 2200 §7.1.3, p. 55) and -EIP (BU 2100 §7.1.3, p. 52): P176/P177
    ///   [-02 + 6(n-1)] control/status word of FI n and the next five elements its
    ///   setpoints/actual values 1..5.
    pub fn show_process_data(
        &mut self,
        inverter: Inverter,
        ppo: Option<PpoType>,
        sent: &[u16],
        answer: &[u16],
    ) {
        let n = inverter.get() - 1;
        let (params, first, words) = match self.config.product {
            Product::Tu3Pnt => {
                if let Some(code) = ppo.and_then(|p| p.display_code(self.config.product)) {
                    self.interface.store.set_info(180, 3, i32::from(code));
                }
                ((176, 177), 2, 3)
            }
            Product::Tu3Pol
            | Product::Tu4Pol
            | Product::Cu4Pol
            | Product::Tu3Eip
            | Product::Tu4Eip
            | Product::Cu4Eip => ((176, 177), 2 + 6 * n, 6),
            Product::Sk550p => ((873, 874), 1 + 6 * n, 6),
        };
        // Runs on every bus cycle for every inverter: the parameters are written only when
        // the words change.
        let mut exchanged = ([0u16; 6], [0u16; 6]);
        for (d, w) in exchanged.0.iter_mut().zip(sent) {
            *d = *w;
        }
        for (d, w) in exchanged.1.iter_mut().zip(answer) {
            *d = *w;
        }
        let Some(shown) = self.process_shown.get_mut(usize::from(n)) else {
            return;
        };
        if *shown == Some(exchanged) {
            return;
        }
        *shown = Some(exchanged);
        let store = &mut self.interface.store;
        for (e, (i, o)) in (first..).zip(sent.iter().zip(answer)).take(words) {
            // The modules show signed values (P176/P177 −32768…32767), the SK 550P hex words.
            let (i, o) = match params.0 {
                176 => (i32::from(*i as i16), i32::from(*o as i16)),
                _ => (i32::from(*i), i32::from(*o)),
            };
            store.set_info(params.0, e, i);
            store.set_info(params.1, e, o);
        }
    }

    /// One process-data cycle of an inverter outside a PPO frame (an EtherNet/IP assembly):
    /// returns the status word and actual values.
    pub fn process(
        &mut self,
        inverter: Inverter,
        control: u16,
        setpoints: &[u16],
        now: Duration,
    ) -> Result<Vec<u16>, DeviceError> {
        self.monitor(now);
        Ok(self
            .process_monitored(inverter, control, setpoints, now)?
            .to_vec())
    }

    /// [`Device::process`] for one of several inverters whose words one frame carries: the
    /// caller has run the monitoring for the frame ([`Device::tick`]) once, not per inverter
    /// (it looks at every inverter, and runs on every bus cycle).
    ///
    /// The words of an inverter the gateway reaches over the system bus go as CAN frames
    /// through its node, at the system bus's pace ([`crate::system_bus::ProcessData`]): what
    /// comes back is what the node's last TPDOs carried, recorded while a tap is attached. The
    /// SK 550P's own FI 1 takes them directly.
    ///
    /// While the interface's CAN controller is off the bus (`inject: { error: bus-off }`) no
    /// PDO gets through and nothing is recorded (as the tap recorded nothing then before): the
    /// inverters keep the words they had (and lose the interface once their monitoring of its
    /// heartbeat trips, [`Device::tick`]), and the field bus gets the status of the last TPDOs
    /// received, 0 if none came yet. The parameter access still reaches the nodes then (see
    /// `Device::gateway_access`), because the cases that inject it read the inverters' errors
    /// through it; what they see of the process data is the status only, which they do not
    /// assert.
    pub(crate) fn process_monitored(
        &mut self,
        inverter: Inverter,
        control: u16,
        setpoints: &[u16],
        now: Duration,
    ) -> Result<[u16; 6], DeviceError> {
        if !self.gateway.reaches(inverter) {
            return self.drive_process(inverter, control, setpoints, now);
        }
        let pause = self.pdo_pause_us();
        let off_bus = self.can_state.off_since.is_some();
        let count = self.config.inverters;
        let unit = self
            .inverters
            .get_mut(usize::from(inverter.get()) - 1)
            .ok_or(DeviceError::NoSuchInverter(inverter.get(), count))?;
        let process = self.gateway.process_data();
        if off_bus {
            return Ok(process.received(inverter));
        }
        let mut words = [0u16; 6];
        words[0] = control;
        for (d, w) in words[1..].iter_mut().zip(setpoints) {
            *d = *w;
        }
        let exchange = process.exchange(inverter, &words, pause, now, |control, setpoints, at| {
            unit.process(control, setpoints, at)
        });
        if let (Some(tap), Some(share)) = (self.tap.as_mut(), &exchange.share) {
            tap.cycle(share);
        }
        Ok(exchange.answer)
    }

    /// One process-data cycle of inverter `inverter`'s drive itself: the control word and
    /// setpoints in, the status word and actual values out. For its node on a CAN segment
    /// (`crate::can`), which is the inverter; the field buses go through
    /// [`Device::process_monitored`].
    pub(crate) fn drive_process(
        &mut self,
        inverter: Inverter,
        control: u16,
        setpoints: &[u16],
        now: Duration,
    ) -> Result<[u16; 6], DeviceError> {
        Ok(self
            .inverter_mut(inverter)?
            .process(control, setpoints, now))
    }

    /// Time passes without a frame: telegram monitoring runs.
    pub fn tick(&mut self, now: Duration) {
        self.monitor(now);
    }

    /// The interface word an SK xU4-EIP receives in output assembly 110 (BU 2100 §6.2.1, p. 32:
    /// DO1 bit 0, DO2 bit 1): shown in P176 [-01] "Bus module outputs"; on the SK TU4-EIP it
    /// sets the digital outputs while P150 "Set relay" is 0 "Via bus".
    pub fn set_module_outputs(&mut self, word: u16) {
        self.module_outputs = word;
        self.interface
            .store
            .set_info(176, 1, i32::from(word as i16));
        self.show_relays();
    }

    /// P175 "Relay status" of the SK TU4-EIP (BU 2100 §7.1.3, p. 52: bit 0 DO1, bit 1 DO2) as
    /// P150 "Set relay" sets them (§7.1.1, p. 45): 0 via bus, 1 both off, 2 DO1 on, 3 DO2 on,
    /// 4 both on.
    fn show_relays(&mut self) {
        if self.config.product != Product::Tu4Eip {
            return;
        }
        let p150 = ParamNumber::new(150)
            .ok()
            .and_then(|n| self.interface.store.read(n, None, None).ok())
            .unwrap_or(0);
        let relays = match p150 {
            1 => 0,
            2 => 0b01,
            3 => 0b10,
            4 => 0b11,
            _ => i32::from(self.module_outputs & 0b11),
        };
        self.interface.store.set_info(175, 1, relays);
    }

    /// A unit's parameter store, for protocol endpoints that address parameters themselves
    /// (CIP classes 100–108).
    pub fn store(&mut self, unit: Unit) -> Result<&mut ParamStore, DeviceError> {
        match unit {
            Unit::Interface => Ok(&mut self.interface.store),
            Unit::Inverter(i) => Ok(&mut self.inverter_mut(i)?.params.store),
        }
    }

    /// The Ethernet telegram time-out of `inverter` (P513 [-04]), `None` when it ignores
    /// field-bus errors.
    pub fn ethernet_timeout(&self, inverter: Inverter) -> Option<Duration> {
        let unit = self
            .inverters
            .get(usize::from(inverter.get()).checked_sub(1)?)?;
        ethernet_timeout(&unit.params.store)
    }

    /// Raises an inverter error unless one is present (a bus watchdog, E10.x) or the inverter
    /// ignores communication errors (P513 = -0.1 "No error", BU 2100 §8.1).
    pub fn raise(&mut self, inverter: Inverter, code: FaultCode) -> Result<(), DeviceError> {
        let unit = self.inverter_mut(inverter)?;
        if unit.drive.fault().is_none() && !ignores_communication_errors(&unit.params.store) {
            unit.drive.inject_fault(code);
            unit.show_fault();
        }
        Ok(())
    }

    /// While the interface is off the system bus, its heartbeat stops: once the inverters'
    /// consumer time has passed (`proto::nord::can::InterfaceWatch`, 600 ms), each inverter on
    /// the system bus whose P120 [-01] watches (1 "Auto", having heard the running interface, or
    /// 2) loses it, "a system-bus fault is registered in both" (BU 2200 §8.1). The SK 550P's
    /// FI 1 is the interface itself.
    fn lose_behind_bus_off(&mut self, now: Duration) {
        let Some(since) = self.can_state.off_since else {
            return;
        };
        let watch = proto::nord::can::interface_watch(self.config.product);
        if self.can_state.lost || now < since + Duration::from_millis(u64::from(watch.ms)) {
            return;
        }
        self.can_state.lost = true;
        let first = match self.config.product.family() {
            proto::nord::Family::Integrated => 2,
            proto::nord::Family::Module => 1,
        };
        for n in first..=self.config.inverters {
            let Ok(fi) = Inverter::new(i64::from(n)) else {
                continue;
            };
            let watching = self.inverter_mut(fi).is_ok_and(|u| {
                let p120 = ParamNumber::new(120).ok().and_then(|p| {
                    let first = proto::nord::ArrayElement::new(1).ok();
                    u.params.store.read(p, None, first).ok()
                });
                matches!(p120, Some(1 | 2))
            });
            if watching {
                let _ = self.lose_interface(fi);
            }
        }
    }

    /// FI `inverter`'s P120 monitoring lost the interface on the system bus: the error of
    /// `proto::nord::can::interface_loss_error`, P700 [-04] its extended code, unless an error
    /// is present or the inverter ignores system-bus errors (P513 [-03] "CANopen" = -0.1, BU 0620
    /// §4.5 p. 90 and §5.1 p. 92; P513 itself where it has no elements).
    pub fn lose_interface(&mut self, inverter: Inverter) -> Result<(), DeviceError> {
        let (p700, extended) = proto::nord::can::interface_loss_error(self.config.product);
        let code = FaultCode {
            group: p700 / 10,
            sub: (p700 % 10) as u8,
        };
        let unit = self.inverter_mut(inverter)?;
        let store = &unit.params.store;
        let element =
            proto::nord::ArrayElement::new(i64::from(proto::nord::can::P513_CANOPEN_ELEMENT)).ok();
        let p513 = store
            .read(P513, None, element)
            .or_else(|_| store.read(P513, None, None));
        if unit.drive.fault().is_some() || p513 == Ok(proto::nord::can::P513_NO_ERROR) {
            return Ok(());
        }
        unit.extended = extended.map(|x| (code, x));
        unit.drive.inject_fault(code);
        unit.show_fault();
        Ok(())
    }

    /// FI `inverter` is lost from the system bus (switched off, cable cut): the bus status
    /// shows it by each product's manual (`bus_status`): 11 "lost or switched off" in the
    /// modules' P173 pairs (BU 2100 §7.1.3, BU 2200 §7.1.3), "not online" in the SK 550P's
    /// P872, 00 "FI is offline" in the SK TU3-PNT's P173 bits 9–8 (BU 0590 §5.1.3).
    pub fn lose(&mut self, inverter: Inverter) {
        self.lost |= 1 << (inverter.get() - 1);
        self.monitor(self.now);
    }

    /// FI 1..=n on the system bus: the SK TU3-PNT's up to the first one lost (its one FI reads
    /// "offline" then), the others' all configured ones (a lost one is shown by `lost`).
    fn online(&self) -> u8 {
        if self.config.product != Product::Tu3Pnt {
            return self.config.inverters;
        }
        (0..self.config.inverters)
            .find(|n| self.lost & 1 << n != 0)
            .unwrap_or(self.config.inverters)
    }

    /// Marks the module's configuration as refused (P173 [-01] bit 5 "Allgemeiner
    /// Konfigurationsfehler", BU 2200 §7.1.3) or accepted.
    pub fn set_config_error(&mut self, refused: bool) {
        self.config_error = refused;
        // Shown at once: the node reads its configuration in outside the process-data cycle.
        let flags = BusFlags {
            config_error: refused,
            ..self.shown.unwrap_or(BusFlags {
                online: self.online(),
                lost: self.lost,
                ..BusFlags::default()
            })
        };
        for (number, element, value) in bus_status::status_parameters(self.config.product, flags) {
            self.interface.store.set_info(number, element, value);
        }
        self.shown = Some(flags);
    }

    /// What the module's P151 switches, by its product's manual (`None` without a P151: the
    /// SK TU3-* and the SK 550P, whose field-bus monitoring is the inverters' P513).
    pub fn p151_monitoring(&self) -> Option<proto::nord::can::P151Monitoring> {
        let value = match self.config.product.family() {
            proto::nord::Family::Module => self.interface.store.read(P151, None, None).ok()?,
            proto::nord::Family::Integrated => return None,
        };
        proto::nord::can::p151_monitoring(self.config.product, value)
    }

    /// The module's P151 has switched all monitoring off (BU 2100 §7.1.1 -1 "Monitoring Off",
    /// BU 2200 §7.1.1 0 "Überwachung Aus"): a lost master raises no inverter error.
    pub fn fieldbus_monitoring_off(&self) -> bool {
        self.p151_monitoring() == Some(proto::nord::can::P151Monitoring::Off)
    }

    /// Marks the field-bus watchdog (P872/P173 bit 2) as tripped or clear.
    pub fn set_fieldbus_timeout(&mut self, tripped: bool) {
        self.fieldbus_timeout = tripped;
    }

    /// The inverters whose present error (P700 [-01], tenths: 10.2 → 102) is no longer what
    /// `seen` holds for them, with the value now, in FI order; `seen` follows. What a bus
    /// signals errors with (CoE emergencies, the POWERLINK error history) starts from here.
    pub fn fault_changes(&mut self, seen: &mut [i32; 8]) -> Vec<(Inverter, i32)> {
        let mut changed = Vec::new();
        for (i, unit) in self.inverters.iter().enumerate().take(seen.len()) {
            // What `show_fault` last wrote, else the store (this runs on every bus frame).
            let value = unit.p700.unwrap_or_else(|| {
                unit.params
                    .store
                    .read(P700, None, proto::nord::ArrayElement::new(1).ok())
                    .unwrap_or(0)
            });
            if value != seen[i] {
                seen[i] = value;
                if let Ok(fi) = Inverter::new(i as i64 + 1) {
                    changed.push((fi, value));
                }
            }
        }
        changed
    }

    /// Raises an inverter error, as P700 shows it (`"10.0"`), or puts the interface's CAN
    /// controller on the system bus into "Bus Warning" (`bus-warning`) or "Bus Off" (`bus-off`:
    /// no 24 V on the bus, wrong connections, BU 2200 §8.4), or drops the inverter off the
    /// system bus (`lost`, see [`Device::lose`]).
    pub fn inject_fault(&mut self, inverter: Inverter, error: &str) -> Result<(), String> {
        match error {
            "lost" => {
                self.inverter_mut(inverter).map_err(|e| e.to_string())?;
                self.lose(inverter);
                return Ok(());
            }
            "bus-warning" => {
                self.can_state.warning = true;
                self.monitor(self.now);
                return Ok(());
            }
            "bus-off" => {
                self.can_state.off_since.get_or_insert(self.now);
                self.monitor(self.now);
                return Ok(());
            }
            _ => {}
        }
        let code: FaultCode = error.parse()?;
        let unit = self.inverter_mut(inverter).map_err(|e| e.to_string())?;
        unit.drive.inject_fault(code);
        unit.show_fault();
        Ok(())
    }

    /// The status-machine state of an inverter, as the manual names it.
    pub fn state_name(&mut self, inverter: Inverter) -> Result<String, String> {
        Ok(self
            .inverter_mut(inverter)
            .map_err(|e| e.to_string())?
            .drive
            .state()
            .to_string())
    }

    /// The "DEV" and "BUS" LEDs of an inverter at `now` (BU 0620 §5.5.1): process data counts as
    /// active while valid control words arrived within [`PROCESS_DATA_WINDOW`]; the system bus's
    /// state is its node's controller ([`Device::set_node_bus`]), and for FI 1 of the SK 550P,
    /// whose integrated interface is FI 1's own controller, also the interface's
    /// (`inject: { error: bus-warning | bus-off }`).
    pub fn leds(
        &mut self,
        inverter: Inverter,
        now: Duration,
    ) -> Result<(led::Row, led::Row), String> {
        let own =
            self.config.product.family() == proto::nord::Family::Integrated && inverter.get() == 1;
        let interface = match (self.can_state.off_since, self.can_state.warning) {
            _ if !own => led::BusState::Active,
            (Some(_), _) => led::BusState::Off,
            (None, true) => led::BusState::Warning,
            (None, false) => led::BusState::Active,
        };
        let unit = self.inverter_mut(inverter).map_err(|e| e.to_string())?;
        let fault = unit.drive.fault();
        let e10 = |subs: &[u8]| fault.is_some_and(|f| f.group == 10 && subs.contains(&f.sub));
        let bus = led::BusLed {
            process_data: unit
                .last_process
                .is_some_and(|t| now.saturating_sub(t) <= PROCESS_DATA_WINDOW),
            telegram_timeout: e10(&[2, 3]),
            monitoring_error: e10(&[0, 9]),
            bus: interface.max(unit.node_bus),
        };
        Ok((
            led::dev(unit.drive.state(), fault.map(|f| f.group)),
            led::bus(bus),
        ))
    }

    /// FI `inverter`'s own node's CAN controller as the segment it is on found it
    /// (`sim::can`): the "BUS" LED shows it.
    pub(crate) fn set_node_bus(&mut self, inverter: Inverter, state: led::BusState) {
        if let Ok(unit) = self.inverter_mut(inverter) {
            unit.node_bus = state;
        }
    }

    /// EEPROM writes of an inverter's parameter store (the bus interface's for `None`).
    pub fn eeprom_writes(&mut self, inverter: Option<Inverter>) -> Result<u64, String> {
        Ok(match inverter {
            None => self.interface.store.eeprom_writes(),
            Some(i) => self
                .inverter_mut(i)
                .map_err(|e| e.to_string())?
                .params
                .store
                .eeprom_writes(),
        })
    }
}

/// P175's bits for a P150 setting (BU 2200 §7.1.1: 1 "Ausgänge aus" both low, 2 DO1 high and DO2
/// low, 3 DO2 high and DO1 low, 4 both high); `None` for 0 "Über Bus".
fn relays_of(p150: i32) -> Option<i32> {
    match p150 {
        1 => Some(0b00),
        2 => Some(0b01),
        3 => Some(0b10),
        4 => Some(0b11),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proto::nord::pkw::PkwRepr;
    use rstest::rstest;

    fn ms(n: u64) -> Duration {
        Duration::from_millis(n)
    }

    fn frame(record: u8, ppo: u8, payload: &[u8]) -> Vec<u8> {
        let mut f = vec![record, ppo];
        f.extend_from_slice(payload);
        f
    }

    fn pkw_frame(record: u8, order: PkwRepr) -> Vec<u8> {
        let ppo = PpoRepr {
            pkw: Some(order),
            pzd: vec![0x047E, 0],
        };
        frame(record, 1, &ppo.emit(PpoType::TYPE_1))
    }

    #[test]
    fn malformed_frames_are_typed_errors() {
        let mut d = Device::new(DeviceConfig::new(Product::Sk550p));
        assert!(matches!(d.handle(&[101], ms(0)), Err(DeviceError::Link(_))));
        assert!(matches!(
            d.handle(&frame(99, 1, &[0; 12]), ms(0)),
            Err(DeviceError::Link(_))
        ));
        assert!(matches!(
            d.handle(&frame(101, 5, &[0; 12]), ms(0)),
            Err(DeviceError::Ppo(_))
        ));
        assert!(matches!(
            d.handle(&frame(101, 1, &[0; 11]), ms(0)),
            Err(DeviceError::Ppo(_))
        ));
        let mut small = Device::new(DeviceConfig {
            inverters: 2,
            ..DeviceConfig::new(Product::Sk550p)
        });
        assert_eq!(
            small.handle(&frame(103, 3, &[0; 4]), ms(0)),
            Err(DeviceError::NoSuchInverter(3, 2))
        );
        // Every byte sequence up to 20 bytes is answered or refused, never a panic.
        for len in 0..20 {
            for b in [0u8, 1, 2, 6, 100, 101, 108, 255] {
                let _ = d.handle(&vec![b; len], ms(0));
            }
        }
    }

    #[test]
    fn a_setting_written_between_cycles_counts_from_the_next_cycle() {
        // The drive's settings are kept between cycles (`Settings`); a write must reach it.
        let mut d = Device::new(DeviceConfig::new(Product::Sk550p));
        let fi = Inverter::new(1).unwrap();
        let actual_2 = |d: &mut Device, t| d.process(fi, 0x047E, &[0x2000], ms(t)).unwrap()[2];
        assert_eq!(actual_2(&mut d, 40), 0, "P543 [-02] = 4 (factory) sends 0");
        d.store(Unit::Inverter(fi))
            .unwrap()
            .write(
                ParamNumber::new(543).unwrap(),
                None,
                proto::nord::ArrayElement::new(2).ok(),
                8,
                crate::store::Persist::RamOnly,
            )
            .unwrap();
        assert_eq!(
            actual_2(&mut d, 44),
            0x2000,
            "P543 [-02] = 8 sends the setpoint frequency"
        );
    }

    #[test]
    fn an_order_is_answered_one_cycle_later_and_only_once() {
        let mut d = Device::new(DeviceConfig::new(Product::Sk550p));
        let write = PkwRepr {
            ak: 2,
            pnu: 1102,
            pwe: 300,
            ..Default::default()
        };
        let first = PpoRepr::parse(
            &d.handle(&pkw_frame(101, write), ms(0)).unwrap()[2..],
            PpoType::TYPE_1,
        )
        .unwrap();
        assert_eq!(first.pkw.map(|p| p.ak), Some(0), "no response yet");
        let second = PpoRepr::parse(
            &d.handle(&pkw_frame(101, write), ms(4)).unwrap()[2..],
            PpoType::TYPE_1,
        )
        .unwrap();
        assert_eq!(second.pkw.map(|p| (p.ak, p.value())), Some((1, 300)));
        d.handle(&pkw_frame(101, write), ms(8)).unwrap();
        assert_eq!(
            d.eeprom_writes(Some(Inverter::new(1).unwrap())),
            Ok(1),
            "a repeated order is not executed twice"
        );
    }

    /// Sends `order` to the interface until it is answered.
    fn interface_order(d: &mut Device, order: PkwRepr, t: u64) {
        d.handle(&pkw_frame(100, order), ms(t)).unwrap();
        d.handle(&pkw_frame(100, order), ms(t + 4)).unwrap();
    }

    fn read_interface(d: &mut Device, number: i64, element: i64) -> i32 {
        let store = d.store(Unit::Interface).unwrap();
        let element = proto::nord::ArrayElement::new(element).ok();
        store
            .read(ParamNumber::new(number).unwrap(), None, element)
            .unwrap()
    }

    fn read_fi(d: &mut Device, fi: i64, number: i64, element: i64) -> i32 {
        let store = d.store(Unit::Inverter(Inverter::new(fi).unwrap())).unwrap();
        let element = proto::nord::ArrayElement::new(element).ok();
        store
            .read(ParamNumber::new(number).unwrap(), None, element)
            .unwrap()
    }

    #[test]
    fn p700_extended_code_and_p701_last_error() {
        let mut d = Device::new(DeviceConfig::new(Product::Sk550p));
        let fi1 = Inverter::new(1).unwrap();
        d.inject_fault(fi1, "10.3").unwrap();
        assert_eq!(read_fi(&mut d, 1, 700, 1), 103);
        assert_eq!(read_fi(&mut d, 1, 700, 4), 0x7592, "BU 0620 §5.3");
        assert_eq!(read_fi(&mut d, 1, 701, 1), 103);
        d.inject_fault(Inverter::new(2).unwrap(), "3.0").unwrap();
        assert_eq!(read_fi(&mut d, 2, 700, 4), 0x2310, "§5.4.1.2 code");
        // The XU5 extension: FI 1 has the Industrial Ethernet interface, FI 2 none.
        assert_eq!(read_fi(&mut d, 1, 744, 2), 2);
        assert_eq!(read_fi(&mut d, 2, 744, 2), 0);
        assert_eq!(read_fi(&mut d, 1, 746, 3), 1);
        assert_eq!(
            (read_fi(&mut d, 1, 745, 7), read_fi(&mut d, 1, 745, 8)),
            (11, 1)
        );
    }

    #[test]
    fn a_lost_inverter_reads_11_in_the_modules_p173() {
        // BU 2200 §7.1.3 / BU 2100 §7.1.3: "1 1 Frequenzumrichter verloren oder ausgeschaltet".
        for product in [Product::Tu4Pol, Product::Tu3Eip] {
            let mut d = Device::new(DeviceConfig::new(product));
            d.inject_fault(Inverter::new(2).unwrap(), "lost").unwrap();
            assert_eq!(
                read_interface(&mut d, 173, 1) & 0xFF00,
                0xAE00,
                "{product:?}"
            );
        }
        // BU 0590 §5.1.3 has no 11: the SK TU3-PNT's one FI reads 00 "offline".
        let mut d = Device::new(DeviceConfig::new(Product::Tu3Pnt));
        d.inject_fault(Inverter::new(1).unwrap(), "lost").unwrap();
        assert_eq!(read_interface(&mut d, 173, 1) & 0x0300, 0);
        // An inverter the device does not have cannot be lost.
        let mut d = Device::new(DeviceConfig::new(Product::Tu4Pol));
        assert!(d.inject_fault(Inverter::new(5).unwrap(), "lost").is_err());
    }

    #[test]
    fn bus_off_shows_in_p170_and_p173_and_the_inverters_lose_the_interface() {
        let mut d = Device::new(DeviceConfig::new(Product::Tu4Pol));
        let fi1 = Inverter::new(1).unwrap();
        // P120 [-02]: not watching (0) on FI 2 only.
        d.store(Unit::Inverter(Inverter::new(2).unwrap()))
            .unwrap()
            .set_info(120, 1, 0);
        d.inject_fault(fi1, "bus-warning").unwrap();
        assert_eq!(read_interface(&mut d, 173, 1) & 0xC0, 0x40);
        assert_eq!(read_interface(&mut d, 170, 1), 0);
        d.inject_fault(fi1, "bus-off").unwrap();
        assert_eq!(read_interface(&mut d, 173, 1) & 0xC0, 0xC0);
        assert_eq!(read_interface(&mut d, 170, 1), 1030, "103.0 System bus Off");
        d.tick(Duration::from_millis(599));
        assert_eq!(
            read_fi(&mut d, 1, 700, 1),
            0,
            "the heartbeat is not late yet"
        );
        d.tick(Duration::from_millis(600));
        assert_eq!(
            read_fi(&mut d, 1, 700, 1),
            109,
            "E10.9 behind an SK TU4-POL"
        );
        assert_eq!(read_fi(&mut d, 2, 700, 1), 0, "P120 = 0 does not watch");
        // The SK TU3-POL has no bits 6/7, and its inverters show E10.8.
        let mut d = Device::new(DeviceConfig::new(Product::Tu3Pol));
        d.inject_fault(fi1, "bus-off").unwrap();
        assert_eq!(read_interface(&mut d, 173, 1) & 0xC0, 0);
        d.tick(Duration::from_millis(600));
        assert_eq!(read_fi(&mut d, 1, 700, 1), 108);
    }

    #[test]
    fn the_next_firmware_leaves_the_factory_with_dhcp_addressing() {
        let mut release = Device::new(DeviceConfig::new(Product::Sk550p));
        assert_eq!(read_interface(&mut release, 856, 1), 1, "BOOTP");
        let mut next = Device::new(DeviceConfig {
            firmware: Firmware::Next,
            ..DeviceConfig::new(Product::Sk550p)
        });
        assert_eq!(read_interface(&mut next, 856, 1), 2, "DHCP");
        let module = |firmware| {
            let mut d = Device::new(DeviceConfig {
                firmware,
                ..DeviceConfig::new(Product::Tu3Pnt)
            });
            (
                read_interface(&mut d, 171, 1),
                read_interface(&mut d, 171, 2),
            )
        };
        // V 1.0 R4 (BU 0590's version list), and the next revision.
        assert_eq!(module(Firmware::Release), (10, 4));
        assert_eq!(module(Firmware::Next), (10, 5));
    }

    #[test]
    fn every_module_shows_its_editions_software_in_p171() {
        for product in Product::ALL {
            let mut d = Device::new(DeviceConfig::new(product));
            let Some((version, revision)) = software_version(product) else {
                assert_eq!(product, Product::Sk550p);
                continue;
            };
            let shown = (
                read_interface(&mut d, 171, 1),
                read_interface(&mut d, 171, 2),
                read_interface(&mut d, 171, 3),
            );
            assert_eq!(shown, (version, revision, 0), "{}", product.name());
            assert!(version >= 10, "{}: no module is V 0.x", product.name());
        }
        // The POWERLINK modules' P171 and their IdentResponse's revision (1018h:03h, 00VVMMRRh)
        // tell one version (BU 2200 §1.1.2).
        for product in [Product::Tu3Pol, Product::Tu4Pol, Product::Cu4Pol] {
            let r = proto::nord::epl::revision(product);
            let from_epl = (((r >> 16) & 0xFF) * 10 + ((r >> 8) & 0xFF), r & 0xFF);
            let (version, revision) = software_version(product).unwrap();
            assert_eq!(
                from_epl,
                (version as u32, revision as u32),
                "{}",
                product.name()
            );
        }
    }

    #[test]
    fn p877_shows_p852_once_element_4_is_written() {
        let mut d = Device::new(DeviceConfig::new(Product::Sk550p));
        let write = |sub: u16, value: u32| PkwRepr {
            ak: 7,
            pnu: 1852,
            ind: sub << 8,
            pwe: value,
            ..Default::default()
        };
        interface_order(&mut d, write(0, 192), 0);
        assert_eq!(read_interface(&mut d, 877, 1), 0, "not saved before [-04]");
        interface_order(&mut d, write(3, 1), 10);
        assert_eq!(read_interface(&mut d, 877, 1), 192);
        assert_eq!(read_interface(&mut d, 877, 4), 1);
    }

    #[test]
    fn p875_p876_follow_p850_p851_under_profinet_once_element_4_is_written() {
        let mut d = Device::new(DeviceConfig::new(Product::Sk550p));
        d.interface.store.set_info(870, 1, 1);
        let write = |pnu: u16, sub: u16, value: u32| PkwRepr {
            ak: 7,
            pnu,
            ind: sub << 8,
            pwe: value,
            ..Default::default()
        };
        let before = read_interface(&mut d, 875, 1);
        for (sub, v) in [(0, 10), (1, 1), (2, 2)] {
            interface_order(&mut d, write(1850, sub, v), u64::from(sub) * 10);
        }
        assert_eq!(
            read_interface(&mut d, 875, 1),
            before,
            "not saved before [-04]"
        );
        interface_order(&mut d, write(1850, 3, 3), 40);
        assert_eq!(read_interface(&mut d, 875, 1), 10);
        // 255.0.0.0 conforms with 10.1.2.3 (class A) and is saved with [-04].
        for (sub, t) in [(1, 50), (2, 60), (3, 70)] {
            interface_order(&mut d, write(1851, sub, 0), t);
        }
        assert_eq!(read_interface(&mut d, 876, 2), 0);
        // 192.168.20.201 (class C) corrects the mask to 255.255.255.0.
        for (sub, v, t) in [(0, 192, 80), (1, 168, 90), (2, 20, 100), (3, 201, 110)] {
            interface_order(&mut d, write(1850, sub, v), t);
        }
        assert_eq!(read_interface(&mut d, 851, 3), 255);
        assert_eq!(read_interface(&mut d, 876, 3), 255);
        // 255.0.0.0 does not conform with it: not saved.
        for (sub, t) in [(1, 120), (2, 130), (3, 140)] {
            interface_order(&mut d, write(1851, sub, 0), t);
        }
        assert_eq!(read_interface(&mut d, 851, 2), 255);
        assert_eq!(read_interface(&mut d, 876, 2), 255);
    }

    #[test]
    fn modules_show_their_process_data() {
        let mut d = Device::new(DeviceConfig::new(Product::Tu4Pol));
        let ppo = PpoRepr {
            pkw: None,
            pzd: vec![0x047E, 0x2000],
        };
        // FI 2: P176 [-08] control word, [-09] setpoint 1; P177 [-08] status word.
        d.handle(&frame(102, 3, &ppo.emit(PpoType::TYPE_3)), ms(40))
            .unwrap();
        assert_eq!(read_interface(&mut d, 176, 8), 0x047E);
        assert_eq!(read_interface(&mut d, 176, 9), 0x2000);
        assert_eq!(read_interface(&mut d, 177, 8) & 0xFF, 0x31);
        assert_eq!(read_interface(&mut d, 181, 1), 0xF0);
        let mut pnt = Device::new(DeviceConfig::new(Product::Tu3Pnt));
        pnt.handle(&frame(101, 3, &ppo.emit(PpoType::TYPE_3)), ms(40))
            .unwrap();
        assert_eq!(read_interface(&mut pnt, 180, 3), 3, "PPO3");
        assert_eq!(read_interface(&mut pnt, 172, 1), 2);
    }

    #[test]
    fn tu4_eip_relays_follow_p150_or_the_bus() {
        // BU 2100 §7.1.1 P150 (p. 45), §7.1.3 P175 (p. 52), §6.2.1 instance 110 (p. 32).
        let mut d = Device::new(DeviceConfig::new(Product::Tu4Eip));
        d.set_module_outputs(0xFFFE);
        assert_eq!(read_interface(&mut d, 175, 1), 0b10, "via bus: DO2 (bit 1)");
        assert_eq!(
            read_interface(&mut d, 176, 1),
            -2,
            "P176 [-01] the outputs word"
        );
        for (p150, relays) in [(1, 0), (2, 0b01), (3, 0b10), (4, 0b11)] {
            let n = ParamNumber::new(150).unwrap();
            d.interface
                .store
                .write(n, None, None, p150, crate::store::Persist::Eeprom)
                .unwrap();
            d.tick(ms(10));
            assert_eq!(read_interface(&mut d, 175, 1), relays, "P150 = {p150}");
        }
    }

    #[test]
    fn p513_no_error_ignores_a_lost_master() {
        // BU 2100 §8.1: P513 = -0.1 "No error" → no E10.2 when the connection times out.
        let mut d = Device::new(DeviceConfig::new(Product::Tu3Eip));
        let fi1 = Inverter::new(1).unwrap();
        let p513 = ParamNumber::new(513).unwrap();
        d.store(Unit::Inverter(fi1))
            .unwrap()
            .write(
                p513,
                None,
                ELEMENT_ETHERNET,
                -1,
                crate::store::Persist::Eeprom,
            )
            .unwrap();
        d.raise(fi1, FaultCode { group: 10, sub: 2 }).unwrap();
        assert_eq!(d.fault_changes(&mut [0; 8]), vec![], "P700 [-01] stays 0");
    }

    #[test]
    fn a_p151_time_out_set_after_a_long_silence_watches_from_the_next_valid_telegram() {
        // Process data stopped long ago; P151 = 200 ms set now trips nothing until valid
        // process data has run again, then 200 ms of silence do (BU 0590 §4.1.7).
        let mut d = Device::new(DeviceConfig::new(Product::Tu4Pol));
        let fi1 = Inverter::new(1).unwrap();
        let ppo = PpoRepr {
            pkw: None,
            pzd: vec![0x047E, 0],
        };
        let valid = frame(101, 3, &ppo.emit(PpoType::TYPE_3));
        d.handle(&valid, ms(0)).unwrap();
        d.monitor(ms(10_000));
        d.store(Unit::Interface)
            .unwrap()
            .write(P151, None, None, 200, crate::store::Persist::Eeprom)
            .unwrap();
        d.monitor(ms(10_010));
        d.monitor(ms(11_000));
        assert_eq!(d.fault_changes(&mut [0; 8]), vec![], "not armed yet");
        d.handle(&valid, ms(11_010)).unwrap();
        d.monitor(ms(11_150));
        assert_eq!(d.fault_changes(&mut [0; 8]), vec![], "150 ms of silence");
        d.monitor(ms(11_250));
        assert_eq!(
            d.fault_changes(&mut [0; 8]),
            vec![(fi1, 103)],
            "E10.3 after 200 ms"
        );
    }

    /// P151 by each product's manual with the inverter's P513 [-04] at 0.5 s: BU 2200 §7.1.1
    /// "0 = Überwachung Aus" leaves the SK TU4-POL's field bus unwatched (no E10.3 from
    /// P513 either, §8.1), BU 2100 §7.1.1's 0 only switches the control-word monitoring off
    /// (the inverter's P513 still trips), and -1 switches everything off.
    #[rstest]
    #[case::pol_0_off(Product::Tu4Pol, 0, vec![])]
    #[case::pol_time_out(Product::Tu4Pol, 2000, vec![(Inverter::new(1).unwrap(), 103)])]
    #[case::eip_0_bus_only(Product::Tu4Eip, 0, vec![(Inverter::new(1).unwrap(), 103)])]
    #[case::eip_minus_1_off(Product::Tu4Eip, -1, vec![])]
    fn p151_follows_each_products_manual(
        #[case] product: Product,
        #[case] p151: i32,
        #[case] faults: Vec<(Inverter, i32)>,
    ) {
        let mut d = Device::new(DeviceConfig::new(product));
        d.store(Unit::Interface)
            .unwrap()
            .write(P151, None, None, p151, crate::store::Persist::Eeprom)
            .unwrap();
        d.store(Unit::Inverter(Inverter::new(1).unwrap()))
            .unwrap()
            .write(
                P513,
                None,
                ELEMENT_ETHERNET,
                5,
                crate::store::Persist::Eeprom,
            )
            .unwrap();
        let ppo = PpoRepr {
            pkw: None,
            pzd: vec![0x047E, 0],
        };
        // A time-out just set watches from the next valid telegram on: two telegrams, then
        // silence.
        let valid = frame(101, 3, &ppo.emit(PpoType::TYPE_3));
        d.handle(&valid, ms(10)).unwrap();
        d.handle(&valid, ms(20)).unwrap();
        d.monitor(ms(1000));
        assert_eq!(d.fault_changes(&mut [0; 8]), faults);
    }

    #[test]
    fn the_interface_answers_on_record_100() {
        let mut d = Device::new(DeviceConfig::new(Product::Sk550p));
        let read = PkwRepr {
            ak: 6,
            pnu: 1850,
            ind: 0x0300,
            ..Default::default()
        };
        d.handle(&pkw_frame(100, read), ms(0)).unwrap();
        let answer = d.handle(&pkw_frame(100, read), ms(4)).unwrap();
        assert_eq!(answer[0], 100);
        let ppo = PpoRepr::parse(&answer[2..], PpoType::TYPE_1).unwrap();
        assert_eq!(ppo.pkw.map(|p| (p.ak, p.value())), Some((4, 100)));
    }

    #[test]
    fn p150_sets_the_outputs_of_p175() {
        // BU 2200 §7.1.1 P150 table; 0 leaves the outputs to the bus.
        let got: Vec<_> = (0..=4).map(relays_of).collect();
        assert_eq!(got, [None, Some(0), Some(1), Some(2), Some(3)]);
    }

    #[test]
    fn process_data_on_the_system_bus_are_the_frames_the_node_answered() {
        // FI 2 behind the SK 550P: its words go as RPDOs to node 34, its status comes back in
        // its TPDO1. FI 1 is the SK 550P itself: no system-bus frame.
        let mut d = Device::new(DeviceConfig {
            inverters: 2,
            ..DeviceConfig::new(Product::Sk550p)
        });
        let (fi1, fi2) = (Inverter::new(1).unwrap(), Inverter::new(2).unwrap());
        assert!(d.tap_system_bus().is_empty());
        d.process(fi1, 0x047E, &[0x2000], ms(0)).unwrap();
        let status = d.process(fi2, 0x047E, &[0x2000], ms(0)).unwrap()[0];
        let frames = d.tap_system_bus();
        let ids: Vec<u16> = frames.iter().map(|(_, f)| f.id()).collect();
        assert_eq!(ids, [0x222, 0x322, 0x080, 0x1A2, 0x2A2]);
        assert_eq!(frames[0].1.data()[..4], [0x7E, 0x04, 0x00, 0x20]);
        assert_eq!(frames[3].1.data()[..2], status.to_le_bytes());
        // 2 ms later, within the 5 ms update cycle: no frame, the drive keeps the words it had
        // (P740 [-01] shows them), the field bus gets the last TPDO's status.
        let lagging = d.process(fi2, 0x0406, &[], ms(2)).unwrap()[0];
        assert_eq!(lagging, status);
        assert!(d.tap_system_bus().is_empty());
        let p740 = |d: &mut Device| {
            let first = proto::nord::ArrayElement::new(1).ok();
            d.store(Unit::Inverter(fi2))
                .unwrap()
                .read(ParamNumber::new(740).unwrap(), None, first)
        };
        assert_eq!(p740(&mut d), Ok(0x047E));
        // At the next cycle the words reach the drive.
        d.process(fi2, 0x0406, &[], ms(6)).unwrap();
        assert_eq!(p740(&mut d), Ok(0x0406));
        assert_eq!(d.tap_system_bus()[0].1.data()[..2], [0x06, 0x04]);
        // Off the bus, nothing gets through.
        d.inject_fault(fi2, "bus-off").unwrap();
        let off = d.process(fi2, 0x047E, &[], ms(20)).unwrap();
        assert_eq!(p740(&mut d), Ok(0x0406));
        assert!(d.tap_system_bus().is_empty());
        assert_eq!(d.process(fi2, 0x047E, &[], ms(40)).unwrap(), off);
    }
}
