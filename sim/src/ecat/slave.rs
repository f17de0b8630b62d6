//! The slave: ESC, AL state machine, mailbox with CoE, process data — around one [`Device`].

use std::time::Duration;

use proto::ecat::al::AlStatusCode;
use proto::ecat::frame::{EcatFrame, FrameType, HEADER_LEN};
use proto::ecat::mailbox::MailboxType;
use proto::ecat::{Command, Datagram};
use proto::eth::{EthernetFrame, ETHERTYPE_ECAT};
use proto::nord::ecat as def;
use proto::nord::led::Row;
use proto::nord::nmt::EcState;

use super::al::{self, Al, Outcome};
use super::esc::{reg, Done, Esc, Event, Op};
use super::mailbox::Mailbox;
use super::od::{Context, Dictionary};
use super::pdo::{self, ProcessWords};
use super::sii;
use super::sm::{SmConfig, SmEvent};
use crate::device::Device;
use crate::link::Unit;

/// How often the slave wants [`Slave::poll`] while process data may run (drive model, P513
/// monitoring).
pub const POLL_PERIOD: Duration = Duration::from_millis(10);

/// What the slave did with a frame.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Processed {
    /// An EtherCAT frame, processed in place: send it on (back to the master).
    Forwarded,
    /// Not an EtherCAT command frame (another EtherType or frame type): passed on
    /// unprocessed, with only the source address marked as every frame leaving port 0 is.
    Passed,
    /// A malformed EtherCAT frame: not processed, counted in the invalid frame counter
    /// (0300h), and not sent on (an ESC destroys it).
    Dropped(DropReason),
}

impl Processed {
    /// Whether the frame is to be sent on.
    pub fn send_back(&self) -> bool {
        !matches!(self, Processed::Dropped(_))
    }
}

/// How the slave is set up beyond its device.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SlaveConfig {
    /// P850 "Second Address" at power-on (BU 0620 §4.2.1: 0…4096; the DIP-switch address of
    /// Hot Connect, §2.2.4), answered to an ID request in the AL status code register.
    pub second_address: u16,
}

/// A device that cannot be an EtherCAT slave.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SlaveError {
    /// The product has no EtherCAT interface.
    #[error("{0} has no EtherCAT interface")]
    NoEthercat(&'static str),
}

/// The SK 550P's EtherCAT slave (sans-IO).
#[derive(Debug)]
pub struct Slave {
    device: Device,
    inverters: u8,
    esc: Esc,
    image: Vec<u16>,
    al: Al,
    mailbox: Mailbox,
    od: Dictionary,
    words: ProcessWords,
    /// P850 as set now (adopted at the next power-on).
    second_address: u16,
    /// The Hot Connect ID adopted at power-on.
    id: u16,
    dropped: u64,
    faults: [i32; 8],
    /// What the last [`Slave::poll`] said, for [`crate::endpoint::Endpoint::next_deadline`].
    pub(super) next_poll: Option<Duration>,
}

impl Slave {
    /// The slave of `device` with the factory second address 0.
    pub fn new(device: Device) -> Result<Slave, SlaveError> {
        Slave::with_config(device, SlaveConfig::default())
    }

    /// The slave of `device`.
    pub fn with_config(mut device: Device, config: SlaveConfig) -> Result<Slave, SlaveError> {
        let product = device.config().product;
        if !product
            .protocols()
            .contains(&proto::nord::Protocol::Ethercat)
        {
            return Err(SlaveError::NoEthercat(product.name()));
        }
        let inverters = device.config().inverters;
        // P870 "Present bus protocol" (BU 0620 §4.3): 2 = EtherCAT.
        if let Ok(s) = device.store(Unit::Interface) {
            s.set_info(870, 1, 2);
        }
        let second = config.second_address.min(def::SECOND_ADDRESS_MAX);
        let mut slave = Slave {
            device,
            inverters,
            esc: Esc::new(),
            image: sii::image(inverters, 0),
            al: Al::default(),
            mailbox: Mailbox::default(),
            od: Dictionary::new(inverters),
            words: ProcessWords::default(),
            second_address: second,
            id: second,
            dropped: 0,
            faults: [0; 8],
            next_poll: None,
        };
        sii::load(&mut slave.esc, &slave.image);
        slave.show_al();
        Ok(slave)
    }

    /// Processes one whole Ethernet II frame in place at `now`, as an ESC does on the fly.
    pub fn process(&mut self, frame: &mut [u8], now: Duration) -> Processed {
        let Some(start) = ethercat_offset(frame) else {
            return passed(frame);
        };
        let got = frame.len() - start;
        let mut ecat = EcatFrame::new_unchecked(&mut frame[start..]);
        let checked = match check(&ecat, got) {
            Ok(Some(())) => ecat.datagrams_mut(),
            Ok(None) => return passed(frame),
            Err(e) => Err(e),
        };
        let datagrams = match checked {
            // A frame of type 1 holds at least one datagram (ETG.1000.4 "EtherCAT frame").
            Ok(d) if d.is_empty() => Err(DropReason::DatagramTruncated {
                index: 0,
                need: DATAGRAM_MIN,
                got: 0,
            }),
            other => other,
        };
        let datagrams = match datagrams {
            Ok(d) => d,
            Err(reason) => {
                self.esc.count_invalid_frame();
                self.dropped += 1;
                return Processed::Dropped(reason);
            }
        };
        self.tick(now);
        for d in datagrams {
            self.datagram(d, now);
        }
        mark_source(frame);
        Processed::Forwarded
    }

    fn datagram(&mut self, mut d: Datagram<&mut [u8]>, now: Duration) {
        let cmd = d.command();
        let (adp, ado, logical) = (d.adp(), d.ado(), d.address());
        let station = self.esc.u16(reg::STATION_ADDRESS);
        let alias_on = self.esc.u8(reg::DL_CONTROL + 3) & 0x01 != 0;
        let fixed = adp == station || (alias_on && adp == self.esc.u16(reg::STATION_ALIAS));
        let mut events = Vec::new();
        let data = d.data_mut();
        let (op, done, next_adp) = match cmd.0 {
            1..=3 => {
                let op = op_of(cmd.0 - Command::APRD.0);
                let done = if adp == 0 {
                    self.esc.physical(ado, data, op, false, now, &mut events)
                } else {
                    Done::default()
                };
                (op, done, Some(adp.wrapping_add(1)))
            }
            4..=6 => {
                let op = op_of(cmd.0 - Command::FPRD.0);
                let done = if fixed {
                    self.esc.physical(ado, data, op, false, now, &mut events)
                } else {
                    Done::default()
                };
                (op, done, None)
            }
            7..=9 => {
                let op = op_of(cmd.0 - Command::BRD.0);
                let done = self.esc.physical(ado, data, op, true, now, &mut events);
                (op, done, Some(adp.wrapping_add(1)))
            }
            10..=12 => {
                let op = op_of(cmd.0 - Command::LRD.0);
                (
                    op,
                    self.esc.logical(logical, data, op, now, &mut events),
                    None,
                )
            }
            13 | 14 => {
                // ARMW/FRMW: the addressed slave reads, every other one writes.
                let armw = cmd == Command::ARMW;
                let addressed = if armw { adp == 0 } else { fixed };
                let op = if addressed { Op::Read } else { Op::Write };
                let done = self.esc.physical(ado, data, op, false, now, &mut events);
                (op, done, armw.then(|| adp.wrapping_add(1)))
            }
            // NOP and unknown commands: not processed, passed on.
            _ => return,
        };
        if let Some(a) = next_adp {
            d.set_adp(a);
        }
        let add = u16::from(done.read)
            + if done.write {
                if op == Op::ReadWrite {
                    2
                } else {
                    1
                }
            } else {
                0
            };
        d.add_wkc(add);
        for e in events {
            self.event(e, now);
        }
    }

    fn event(&mut self, e: Event, now: Duration) {
        match e {
            Event::AlControl => self.al_control(now),
            Event::EepromCommand => sii::command(&mut self.esc, &mut self.image),
            Event::Sm(SmEvent::MailboxWritten(0)) => {
                if let Some(buf) = self.esc.take_mailbox(0) {
                    let room = SmConfig::read(self.esc.mem(), 1).len;
                    let mut cx = Context {
                        device: &mut self.device,
                        words: &self.words,
                        second_address: &mut self.second_address,
                    };
                    self.mailbox
                        .receive(&buf, room, self.al.state, &self.od, &mut cx);
                }
                self.fill_mailbox();
            }
            Event::Sm(SmEvent::MailboxRead(1)) => self.fill_mailbox(),
            Event::Sm(SmEvent::OutputsWritten(2)) => {
                if self.al.state == EcState::Operational {
                    let sm = SmConfig::read(self.esc.mem(), 2);
                    let out = self.esc.bytes(sm.start, sm.len).to_vec();
                    pdo::cycle(&mut self.device, &mut self.words, Some(&out), true, now);
                    self.show_inputs();
                }
            }
            Event::Sm(SmEvent::Repeat(1)) => {
                if !self.esc.sms.is_full(1) {
                    if let Some(m) = self.mailbox.last_sent.clone() {
                        self.esc.put_mailbox(1, &m);
                    }
                }
                self.esc.ack_repeat(1);
            }
            Event::Sm(SmEvent::Repeat(n)) => self.esc.ack_repeat(n),
            Event::Sm(_) => {}
        }
    }

    /// Moves queued replies into the send mailbox while it is free.
    fn fill_mailbox(&mut self) {
        if !matches!(
            self.al.state,
            EcState::PreOperational
                | EcState::SafeOperational
                | EcState::Operational
                | EcState::Bootstrap
        ) {
            return;
        }
        while !self.esc.sms.is_full(1) {
            let Some(m) = self.mailbox.next() else { break };
            if self.esc.put_mailbox(1, &m) {
                self.mailbox.last_sent = Some(m);
            } else {
                self.mailbox.unsend(m);
                break;
            }
        }
    }

    fn show_inputs(&mut self) {
        let sm = SmConfig::read(self.esc.mem(), 3);
        if sm.active() {
            let image = self.words.input_image(self.inverters);
            self.esc.put(sm.start, &image[..image.len().min(sm.len)]);
        }
    }

    fn show_al(&mut self) {
        self.esc.set_u16(reg::AL_STATUS, self.al.status());
        self.esc
            .set_u16(reg::AL_STATUS_CODE, self.al.status_code(self.id));
    }

    fn al_control(&mut self, now: Duration) {
        let control = self.esc.u16(reg::AL_CONTROL);
        let (mem, inverters) = (self.esc.mem(), self.inverters);
        let outcome = self.al.control(control, |to| match to {
            EcState::PreOperational => al::check_mailbox(mem, false),
            EcState::Bootstrap => al::check_mailbox(mem, true),
            EcState::SafeOperational => al::check_process_data(mem, inverters),
            _ => Ok(()),
        });
        if let Outcome::Changed(from, to) = outcome {
            self.enter(from, to, now);
        }
        self.show_al();
    }

    /// What entering `to` from `from` does to the SyncManagers, the mailbox and the watchdog.
    fn enter(&mut self, from: EcState, to: EcState, now: Duration) {
        match to {
            EcState::Init => {
                for n in 0..4 {
                    self.esc.deactivate(n, true);
                }
                self.mailbox.reset();
            }
            EcState::PreOperational | EcState::Bootstrap => {
                if from == EcState::Init {
                    self.esc.deactivate(0, false);
                    self.esc.deactivate(1, false);
                }
                self.esc.deactivate(2, true);
                self.esc.deactivate(3, true);
            }
            EcState::SafeOperational => {
                if from == EcState::PreOperational {
                    self.esc.deactivate(2, false);
                    self.esc.deactivate(3, false);
                    pdo::cycle(&mut self.device, &mut self.words, None, false, now);
                    self.show_inputs();
                }
            }
            EcState::Operational => {
                self.esc.wd_trigger = Some(now);
                self.esc.set_u16(reg::WD_SM_STATUS, 1);
                self.device.set_fieldbus_timeout(false);
            }
        }
    }

    /// Timers: the SM watchdog in Operational, the inputs in Safe Operational, the device's
    /// monitoring, emergencies for new inverter errors.
    fn tick(&mut self, now: Duration) {
        if self.al.state == EcState::Operational {
            let sm2 = SmConfig::read(self.esc.mem(), 2);
            let watched = sm2.control & 0x40 != 0;
            if let (true, Some(t), Some(limit)) =
                (watched, self.esc.wd_trigger, self.esc.sm_watchdog())
            {
                if now.saturating_sub(t) > limit {
                    self.esc.wd_trigger = None;
                    self.esc.set_u16(reg::WD_SM_STATUS, 0);
                    let c = self.esc.u8(reg::WD_SM_COUNTER);
                    self.esc.set_u8(reg::WD_SM_COUNTER, c.saturating_add(1));
                    if let Outcome::Changed(from, to) = self
                        .al
                        .fall_back(EcState::SafeOperational, AlStatusCode::SM_WATCHDOG)
                    {
                        self.enter(from, to, now);
                    }
                    pdo::watchdog_expired(&mut self.device);
                    self.show_al();
                }
            }
        }
        if self.al.state == EcState::SafeOperational {
            pdo::cycle(&mut self.device, &mut self.words, None, false, now);
            self.show_inputs();
        } else {
            self.device.tick(now);
        }
        self.emergencies();
    }

    /// A CoE emergency for each inverter error that appeared (P700 [-01] from 0 to a value;
    /// `crate::objects::emergency_of`).
    fn emergencies(&mut self) {
        for (fi, value) in self.device.fault_changes(&mut self.faults) {
            if value == 0 || self.al.state == EcState::Init {
                continue;
            }
            let emergency = crate::objects::emergency_of(value, None, fi);
            self.mailbox.send(MailboxType::COE, emergency.emit_coe());
            self.fill_mailbox();
        }
    }

    /// Puts a CoE emergency for an inverter error that is not there into the send mailbox, as
    /// [`Slave::emergencies`] does for one that appeared: E10.2 "telegram time-out" of FI 1
    /// (BU 0620 §5.3: 7591h, error register 11h, P700 102 and the FI in the manufacturer
    /// field), numbered with the mailbox's next counter (ETG.1000.6 §5.6: 1..7). The master
    /// fetches it (SM1 status "mailbox full"); nothing is sent unasked. `None` while the
    /// mailbox does not run (Init), or runs without CoE (Bootstrap): a slave then has nowhere
    /// to put one. What it raised, for the log.
    pub fn raise_spurious_emergency(&mut self) -> Option<String> {
        if matches!(self.al.state, EcState::Init | EcState::Bootstrap) {
            return None;
        }
        let fi = proto::nord::Inverter::new(1).ok()?;
        let e = crate::objects::emergency_of(102, None, fi);
        self.mailbox.send(MailboxType::COE, e.emit_coe());
        let counter = self.mailbox.counter();
        self.fill_mailbox();
        Some(format!(
            "CoE emergency {:04X}h, error register {:02X}h, data {} (E10.2 on FI 1, which it \
             does not have) queued as mailbox #{counter}",
            e.code,
            e.register,
            e.data
                .iter()
                .map(|b| format!("{b:02X}"))
                .collect::<Vec<_>>()
                .join(" "),
        ))
    }

    /// Runs the timers due at `now`; returns when to call again at the latest (`None`: nothing
    /// pending).
    pub fn poll(&mut self, now: Duration) -> Option<Duration> {
        self.tick(now);
        self.fill_mailbox();
        let mut next = None;
        if self.al.state == EcState::Operational {
            if let (Some(t), Some(limit)) = (self.esc.wd_trigger, self.esc.sm_watchdog()) {
                next = Some(t + limit + Duration::from_micros(1));
            }
        }
        if self.al.state != EcState::Init {
            let p = now + POLL_PERIOD;
            next = Some(next.map_or(p, |n: Duration| n.min(p)));
        }
        next
    }

    /// The AL state.
    pub fn al_state(&self) -> EcState {
        self.al.state
    }

    /// The AL status register (0130h): state, error indication (bit 4), ID loaded (bit 5).
    pub fn al_status(&self) -> u16 {
        self.al.status()
    }

    /// The AL status code register (0134h).
    pub fn al_status_code(&self) -> u16 {
        self.al.status_code(self.id)
    }

    /// LED A "RUN" (BU 0620 §5.5.2.1).
    pub fn run_led(&self) -> Row {
        self.al.run_led()
    }

    /// LED B "ERR" (BU 0620 §5.5.2.1).
    pub fn err_led(&self) -> Row {
        self.al.err_led()
    }

    /// The simulated device.
    pub fn device(&self) -> &Device {
        &self.device
    }

    /// The simulated device, for fault injection and observation.
    pub fn device_mut(&mut self) -> &mut Device {
        &mut self.device
    }

    /// The configured station address (0010h).
    pub fn station_address(&self) -> u16 {
        self.esc.u16(reg::STATION_ADDRESS)
    }

    /// The Hot Connect ID adopted at power-on (P850 "Second Address").
    pub fn device_id(&self) -> u16 {
        self.id
    }

    /// P850 "Second Address" as set now (taken over at the next power-on).
    pub fn second_address_setting(&self) -> u16 {
        self.second_address
    }

    /// ESC registers or process RAM as the master would read them, without side effects.
    pub fn registers(&self, address: u16, len: usize) -> Vec<u8> {
        let mut v = self.esc.bytes(usize::from(address), len).to_vec();
        v.resize(len, 0);
        v
    }

    /// The SII EEPROM image, little-endian words as bytes.
    pub fn sii_image(&self) -> Vec<u8> {
        self.image.iter().flat_map(|w| w.to_le_bytes()).collect()
    }

    /// Frames dropped as malformed.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }

    /// Mailbox messages answered with a mailbox error.
    pub fn mailbox_errors(&self) -> u64 {
        self.mailbox.errors
    }
}

/// Why a frame was not processed: the EtherCAT codec's error (a lying frame or datagram
/// length, trailing bytes, a frame too short for its header).
pub type DropReason = proto::wire::Error;

/// The smallest datagram: header and working counter.
const DATAGRAM_MIN: usize = proto::ecat::datagram::HEADER_LEN + proto::ecat::datagram::WKC_LEN;

/// Where the EtherCAT payload of an Ethernet frame starts, if it is one (`None`: another
/// EtherType, or too short for an Ethernet header; one 802.1Q tag is skipped).
fn ethercat_offset(frame: &[u8]) -> Option<usize> {
    let eth = EthernetFrame::new_checked(frame).ok()?;
    (eth.inner_ethertype() == ETHERTYPE_ECAT).then(|| eth.header_len())
}

/// The header of an EtherCAT frame: `Ok(None)` for a frame type other than 1 (passed on
/// unprocessed), an error for a frame shorter than its header or its length field.
/// Sets the locally administered bit of the source address, as an ESC does to every frame it
/// sends out of port 0, processed or not (ETG.1000.4 §5.3): a master tells the frames that
/// went round the segment from its own.
fn mark_source(frame: &mut [u8]) {
    if frame.len() >= 12 {
        let mut eth = EthernetFrame::new_unchecked(frame);
        eth.set_src(eth.src().with_locally_administered());
    }
}

/// A frame passed on unprocessed: source marked, nothing else touched.
fn passed(frame: &mut [u8]) -> Processed {
    mark_source(frame);
    Processed::Passed
}

fn check<T: AsRef<[u8]>>(f: &EcatFrame<T>, got: usize) -> Result<Option<()>, DropReason> {
    if got < HEADER_LEN {
        return Err(DropReason::Truncated {
            what: "EtherCAT header",
            need: HEADER_LEN,
            got,
        });
    }
    if f.frame_type() != FrameType::DLPDU {
        return Ok(None);
    }
    f.check_len().map(Some)
}

fn op_of(n: u8) -> Op {
    match n {
        0 => Op::Read,
        1 => Op::Write,
        _ => Op::ReadWrite,
    }
}
