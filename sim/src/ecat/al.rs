//! The application layer state machine (BU 0620 §2.2.5 "NMT status machine"; ETG.1000.6
//! §6.4.1): the master writes AL control (0120h), the slave answers in AL status (0130h) and AL
//! status code (0134h).
//!
//! The transitions are `proto::nord::nmt::ETHERCAT_TRANSITIONS`. A request the table does not
//! allow leaves the state, sets the error indication (AL status bit 4) and AL status code 0011h;
//! a state value that is none of 1, 2, 3, 4, 8 gives 0012h. A configuration the slave cannot
//! work with refuses the transition with its own code (mailbox 0016h, bootstrap mailbox 0015h,
//! outputs 001Dh, inputs 001Eh). While the error indication is set, a request without the
//! acknowledge bit (0120h bit 4) for a higher state is ignored; a lower state is entered (the
//! indication stays); an acknowledge clears indication and code.
//!
//! Explicit device identification (ETG.1020 §4.2.2, BU 0620 §2.2.4/§3.6.2 "Second Address",
//! "ADO 0x134"): AL control bit 5 asks for the ID; the slave puts it into the AL status code
//! register and sets AL status bit 5 while no error is shown.

use proto::ecat::al::{AlControl, AlStatus, AlStatusCode};
use proto::nord::ecat::{self as def, SmRole};
use proto::nord::led::{self, Pattern, Row};
use proto::nord::nmt::{ethercat_next, EcState};

use super::sm::SmConfig;

/// The AL state and its indications.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Al {
    /// Present state.
    pub(crate) state: EcState,
    /// Error indication (AL status bit 4).
    pub(crate) error: bool,
    /// AL status code.
    pub(crate) code: AlStatusCode,
    /// The device ID is shown in the AL status code register (AL status bit 5).
    pub(crate) id_loaded: bool,
    /// The slave changed state by itself (for the ERR LED).
    pub(crate) unsolicited: bool,
}

impl Default for Al {
    fn default() -> Self {
        Al {
            state: EcState::Init,
            error: false,
            code: AlStatusCode::NO_ERROR,
            id_loaded: false,
            unsolicited: false,
        }
    }
}

/// What a write of AL control did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Outcome {
    /// The state changed.
    Changed(EcState, EcState),
    /// No state change (same state, ignored or refused).
    Stayed,
}

impl Al {
    /// The AL status register value.
    pub(crate) fn status(&self) -> u16 {
        AlStatus {
            device_id: self.id_loaded && !self.error,
            ..AlStatus::new(self.state, self.error)
        }
        .to_word()
    }

    /// The AL status code register value: the error code, or the device ID when asked for.
    pub(crate) fn status_code(&self, id: u16) -> u16 {
        if self.id_loaded && !self.error {
            id
        } else {
            self.code.0
        }
    }

    fn refuse(&mut self, code: AlStatusCode) -> Outcome {
        self.error = true;
        self.code = code;
        self.unsolicited = false;
        Outcome::Stayed
    }

    /// The master wrote `control` to AL control; `check` says whether the configuration allows
    /// entering a state (or the AL status code refusing it).
    pub(crate) fn control(
        &mut self,
        control: u16,
        check: impl FnOnce(EcState) -> Result<(), AlStatusCode>,
    ) -> Outcome {
        let control = AlControl::from_word(control);
        self.id_loaded = control.device_id;
        if self.error {
            if control.ack {
                self.error = false;
                self.code = AlStatusCode::NO_ERROR;
                self.unsolicited = false;
            } else if control.state >= self.state.code() {
                return Outcome::Stayed;
            }
        }
        let Some(to) = control.ec_state() else {
            return self.refuse(AlStatusCode::UNKNOWN_STATE);
        };
        if to == self.state {
            return Outcome::Stayed;
        }
        if ethercat_next(self.state, to).is_err() {
            return self.refuse(AlStatusCode::INVALID_STATE_CHANGE);
        }
        // Going down needs no configuration.
        if to.code() > self.state.code() || to == EcState::Bootstrap {
            if let Err(c) = check(to) {
                return self.refuse(c);
            }
        }
        let from = self.state;
        self.state = to;
        Outcome::Changed(from, to)
    }

    /// The slave leaves a state by itself (a watchdog), with an error code.
    pub(crate) fn fall_back(&mut self, to: EcState, code: AlStatusCode) -> Outcome {
        let from = self.state;
        self.state = to;
        self.error = true;
        self.code = code;
        self.unsolicited = true;
        Outcome::Changed(from, to)
    }

    /// LED A "RUN" (BU 0620 §5.5.2.1). Bootstrap is not in the manual's table: ETG.1300 shows
    /// it flickering (10 Hz).
    pub(crate) fn run_led(&self) -> Row {
        let name = self.state.name();
        led::ETHERCAT_RUN
            .iter()
            .copied()
            .find(|r| r.meaning == name)
            .unwrap_or(Row {
                pattern: Pattern::FlashingGreen { tenths_hz: 100 },
                meaning: "Bootstrap",
            })
    }

    /// LED B "ERR" (BU 0620 §5.5.2.1): off without an error; double flash on a watchdog
    /// ("Application Watchdog Timeout"); single flash when the slave changed state by itself
    /// ("Unsolicited State Change"); flashing for a refused configuration ("Invalid
    /// Configuration").
    pub(crate) fn err_led(&self) -> Row {
        let want = if !self.error {
            Pattern::Off
        } else if self.code == AlStatusCode::SM_WATCHDOG {
            Pattern::DoubleFlashRed
        } else if self.unsolicited {
            Pattern::SingleFlashRed
        } else {
            Pattern::FlashingRed { tenths_hz: 25 }
        };
        led::ETHERCAT_ERR
            .iter()
            .copied()
            .find(|r| r.pattern == want)
            .unwrap_or(led::ETHERCAT_ERR[0])
    }
}

/// The smallest mailbox the slave works with: a mailbox header, a CoE header and an SDO
/// header (6 + 2 + 8 bytes).
pub(crate) const MIN_MAILBOX: usize = 16;

/// Whether SyncManagers 0 and 1 are set up as mailboxes the slave can work with: activated,
/// mailbox mode in the right direction, within the process RAM, no larger than the SII's
/// (ETG.1000.6 §6.4.2; 0015h for Bootstrap, 0016h otherwise).
pub(crate) fn check_mailbox(mem: &[u8], boot: bool) -> Result<(), AlStatusCode> {
    let fail = if boot {
        AlStatusCode::INVALID_MAILBOX_BOOT
    } else {
        AlStatusCode::INVALID_MAILBOX_PREOP
    };
    let out = SmConfig::read(mem, 0);
    let inn = SmConfig::read(mem, 1);
    let ok = |sm: &SmConfig, want: &def::SyncManager| {
        sm.enabled
            && sm.control & 0x0F == want.control & 0x0F
            && (MIN_MAILBOX..=usize::from(want.len)).contains(&sm.len)
            && sm.start >= super::esc::RAM_START
            && sm.start + sm.len <= super::esc::RAM_END
    };
    let disjoint = out.start + out.len <= inn.start || inn.start + inn.len <= out.start;
    if ok(&out, &def::SM_MAILBOX_OUT) && ok(&inn, &def::SM_MAILBOX_IN) && disjoint {
        Ok(())
    } else {
        Err(fail)
    }
}

/// Whether SyncManagers 2 and 3 are set up for the process data of `inverters` inverters:
/// 3-buffer mode in the right direction, 12 bytes per inverter, their three buffers within the
/// process RAM and clear of the mailboxes (0016h…: outputs 001Dh, inputs 001Eh).
pub(crate) fn check_process_data(mem: &[u8], inverters: u8) -> Result<(), AlStatusCode> {
    let sms = def::sync_managers(inverters);
    let mbx: Vec<SmConfig> = (0..2).map(|n| SmConfig::read(mem, n)).collect();
    for want in &sms[2..] {
        let sm = SmConfig::read(mem, usize::from(want.index));
        let fail = match want.role {
            SmRole::Outputs => AlStatusCode::INVALID_OUTPUT_CONFIG,
            _ => AlStatusCode::INVALID_INPUT_CONFIG,
        };
        let end = sm.start + 3 * sm.len;
        let clear = mbx
            .iter()
            .all(|m| end <= m.start || m.start + m.len <= sm.start);
        let ok = sm.enabled
            && sm.control & 0x0F == want.control & 0x0F
            && sm.len == usize::from(want.len)
            && sm.start >= super::esc::RAM_START
            && end <= super::esc::RAM_END
            && clear;
        if !ok {
            return Err(fail);
        }
    }
    Ok(())
}
