//! AL states (BU 0620 §2.2.5 "NMT status machine"; ETG.1000.6 §6.4.1): the master writes AL
//! control (0120h: state bits 0–3, error acknowledge bit 4, ID request bit 5) and reads AL
//! status (0130h: state bits 0–3, error indication bit 4, ID loaded bit 5) and the AL status
//! code (0134h) until the slave shows the requested state or refuses it.
//!
//! Any byte can be requested, also no state at all (the harness tests refusals); the typed
//! [`Master::set_state`] turns a refusal into [`Refusal::Al`].

use std::time::Duration;

use proto::ecat::al::{AlControl, AlStatus, AlStatusCode, EcState};
use proto::ecat::register::{AL_CONTROL, AL_STATUS};

use super::engine::Master;
use super::error::{AlRefused, Awaited, ProtocolError, Refusal, Result};
use super::segment::Segment;

/// How long a slave may take for an AL state change: the ESI's `StateMachine/Timeout`, by
/// ETG.2000's defaults (BU 0620 and the SK 550P's device description print no others).
/// Init → PreOp or Bootstrap.
const PREOP_TIMEOUT: Duration = Duration::from_millis(3000);
/// PreOp → SafeOp, SafeOp → Op.
const SAFEOP_OP_TIMEOUT: Duration = Duration::from_millis(10_000);
/// Back to Init, or SafeOp/Op back to PreOp.
const BACK_TO_INIT_TIMEOUT: Duration = Duration::from_millis(5000);

/// The limit of a request for the state bits `requested`. The master does not read the state
/// the slave is in first, so a request that can be two transitions takes the longer limit
/// (PreOp: up from Init 3000 ms or back 5000 ms; SafeOp: up 10 000 ms or back from Op
/// 200 ms); bits that name no state, which a slave refuses, take the longest of all.
pub(crate) fn al_limit(requested: u8) -> Duration {
    match EcState::from_code(requested) {
        Some(EcState::Bootstrap) => PREOP_TIMEOUT,
        Some(EcState::Init | EcState::PreOperational) => BACK_TO_INIT_TIMEOUT,
        Some(EcState::SafeOperational | EcState::Operational) | None => SAFEOP_OP_TIMEOUT,
    }
}

/// AL status (0130h) and AL status code (0134h) as read at once.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct AlReading {
    /// The AL status register.
    pub(crate) status: AlStatus,
    /// The AL status code register (the device ID while the status says it is loaded).
    pub(crate) code: AlStatusCode,
}

impl AlReading {
    /// The state bits (0–3), defined or not.
    pub(crate) fn state_bits(&self) -> u8 {
        self.status.state
    }

    /// The state, if the bits name one.
    pub(crate) fn state(&self) -> Option<EcState> {
        self.status.ec_state()
    }

    /// The error indication (bit 4).
    pub(crate) fn error(&self) -> bool {
        self.status.error
    }

    /// The device ID is loaded into the AL status code register (bit 5).
    pub(crate) fn id_loaded(&self) -> bool {
        self.status.device_id
    }
}

impl<S: Segment> Master<S> {
    /// Reads AL status and AL status code of `station`.
    pub(crate) fn al_status(&mut self, station: u16) -> Result<AlReading> {
        let b = self.read_register(station, AL_STATUS, 6)?;
        let (status, code) = AlStatus::parse_with_code(&b).map_err(ProtocolError::Malformed)?;
        Ok(AlReading { status, code })
    }

    /// Writes `control` to AL control of `station` (any value: state bits, acknowledge, ID
    /// request) and reads AL status until it shows the requested state bits or the error
    /// indication; returns that status. A slave that shows neither within the transition's
    /// limit ([`al_limit`]) is a timeout. The process data keep running while the master
    /// waits.
    pub(crate) fn request_state(&mut self, station: u16, control: u16) -> Result<AlReading> {
        self.write_register(station, AL_CONTROL, &control.to_le_bytes())?;
        let want = (control & 0x0F) as u8;
        if want == EcState::Init.code() {
            // Its mailbox stops: the next one counts from 1 again.
            if let Some(s) = self.slave_mut(station) {
                s.received = None;
            }
        }
        self.poll(al_limit(want), Awaited::AlState, |m| {
            let s = m.al_status(station)?;
            Ok((s.state_bits() == want || s.error()).then_some(s))
        })
    }

    /// Brings `station` into `state`; a refusal (error indication) is [`Refusal::Al`] with the
    /// AL status code.
    pub(crate) fn set_state(&mut self, station: u16, state: EcState) -> Result<()> {
        let requested = state.code();
        let s = self.request_state(station, u16::from(requested))?;
        if s.error() || s.state_bits() != requested {
            return Err(Refusal::Al(AlRefused {
                requested,
                state: s.state_bits(),
                code: s.code,
            })
            .into());
        }
        Ok(())
    }

    /// Acknowledges the error indication of `station`, staying in its present state; returns
    /// the status after.
    pub(crate) fn acknowledge_error(&mut self, station: u16) -> Result<AlReading> {
        let now = self.al_status(station)?;
        let control = AlControl {
            state: now.state_bits(),
            ack: true,
            ..AlControl::default()
        };
        self.write_register(station, AL_CONTROL, &control.emit())?;
        self.al_status(station)
    }

    /// Explicit device identification (ETG.1020; BU 0620 §2.2.4, §3.6.2 "ADO 0x134"): sets the
    /// ID request bit with the present state and returns the ID the slave shows in the AL
    /// status code register once AL status bit 5 says it is loaded.
    pub(crate) fn identify(&mut self, station: u16) -> Result<u16> {
        let now = self.al_status(station)?;
        let control = AlControl {
            state: now.state_bits(),
            device_id: true,
            ..AlControl::default()
        };
        self.write_register(station, AL_CONTROL, &control.emit())?;
        // ETG.1020 prints no limit for loading the ID: a harness limit, that of a change to
        // Init or PreOp.
        let s = self.poll(BACK_TO_INIT_TIMEOUT, Awaited::AlState, |m| {
            let s = m.al_status(station)?;
            Ok((s.id_loaded() || s.error()).then_some(s))
        })?;
        if s.error() {
            return Err(Refusal::Al(AlRefused {
                requested: control.state,
                state: s.state_bits(),
                code: s.code,
            })
            .into());
        }
        Ok(s.code.0)
    }
}
