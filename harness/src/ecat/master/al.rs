//! AL states (BU 0620 §2.2.5 "NMT status machine"; ETG.1000.6 §6.4.1): the master writes AL
//! control (0120h: state bits 0–3, error acknowledge bit 4, ID request bit 5) and reads AL
//! status (0130h: state bits 0–3, error indication bit 4, ID loaded bit 5) and the AL status
//! code (0134h) until the slave shows the requested state or refuses it.
//!
//! Any byte can be requested, also no state at all (the harness tests refusals); the typed
//! [`Master::set_state`] turns a refusal into [`Refusal::Al`].

use proto::nord::nmt::EcState;

use super::codes::AlStatusCode;
use super::engine::Master;
use super::error::{AlRefused, Awaited, Refusal, Result};
use super::segment::Segment;

/// AL control (0120h).
pub(crate) const AL_CONTROL: u16 = 0x0120;
/// AL status (0130h).
pub(crate) const AL_STATUS: u16 = 0x0130;
/// Error acknowledge (AL control bit 4).
pub(crate) const ACK: u16 = 0x0010;
/// ID request (AL control bit 5, ETG.1020 explicit device identification).
pub(crate) const ID_REQUEST: u16 = 0x0020;

/// The AL status state code of a state (ETG.1000.6 table 9: 1 Init, 2 Pre-Op, 3 Bootstrap,
/// 4 Safe-Op, 8 Op).
pub(crate) fn state_code(s: EcState) -> u8 {
    match s {
        EcState::Init => 1,
        EcState::PreOperational => 2,
        EcState::Bootstrap => 3,
        EcState::SafeOperational => 4,
        EcState::Operational => 8,
    }
}

/// The state of a state code, if it is one.
pub(crate) fn state_of(code: u8) -> Option<EcState> {
    EcState::ALL.into_iter().find(|s| state_code(*s) == code)
}

/// AL status (0130h) and AL status code (0134h) as read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct AlStatus {
    /// The AL status register.
    pub(crate) raw: u16,
    /// The AL status code register (the device ID while [`AlStatus::id_loaded`]).
    pub(crate) code: AlStatusCode,
}

impl AlStatus {
    fn parse(b: &[u8]) -> AlStatus {
        AlStatus {
            raw: u16::from_le_bytes([b[0], b[1]]),
            code: AlStatusCode(u16::from_le_bytes([b[4], b[5]])),
        }
    }

    /// The state bits (0–3).
    pub(crate) fn state_bits(&self) -> u8 {
        (self.raw & 0x0F) as u8
    }

    /// The state, if the bits name one.
    pub(crate) fn state(&self) -> Option<EcState> {
        state_of(self.state_bits())
    }

    /// The error indication (bit 4).
    pub(crate) fn error(&self) -> bool {
        self.raw & 0x10 != 0
    }

    /// The device ID is loaded into the AL status code register (bit 5).
    pub(crate) fn id_loaded(&self) -> bool {
        self.raw & 0x20 != 0
    }
}

impl<S: Segment> Master<S> {
    /// Reads AL status and AL status code of `station`.
    pub(crate) fn al_status(&mut self, station: u16) -> Result<AlStatus> {
        let b = self.read_register(station, AL_STATUS, 6)?;
        Ok(AlStatus::parse(&b))
    }

    /// Writes `control` to AL control of `station` (any value: state bits, acknowledge, ID
    /// request) and reads AL status until it shows the requested state bits or the error
    /// indication; returns that status. A slave that shows neither within
    /// [`super::MasterConfig::al_timeout`] is a timeout. The process data keep running while
    /// the master waits.
    pub(crate) fn request_state(&mut self, station: u16, control: u16) -> Result<AlStatus> {
        self.write_register(station, AL_CONTROL, &control.to_le_bytes())?;
        let want = (control & 0x0F) as u8;
        let timeout = self.config.al_timeout;
        self.poll(timeout, Awaited::AlState, |m| {
            let s = m.al_status(station)?;
            Ok((s.state_bits() == want || s.error()).then_some(s))
        })
    }

    /// Brings `station` into `state`; a refusal (error indication) is [`Refusal::Al`] with the
    /// AL status code.
    pub(crate) fn set_state(&mut self, station: u16, state: EcState) -> Result<()> {
        let requested = state_code(state);
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
    pub(crate) fn acknowledge_error(&mut self, station: u16) -> Result<AlStatus> {
        let now = self.al_status(station)?;
        self.write_register(
            station,
            AL_CONTROL,
            &(u16::from(now.state_bits()) | ACK).to_le_bytes(),
        )?;
        self.al_status(station)
    }

    /// Explicit device identification (ETG.1020; BU 0620 §2.2.4, §3.6.2 "ADO 0x134"): sets the
    /// ID request bit with the present state and returns the ID the slave shows in the AL
    /// status code register once AL status bit 5 says it is loaded.
    pub(crate) fn identify(&mut self, station: u16) -> Result<u16> {
        let now = self.al_status(station)?;
        let control = u16::from(now.state_bits()) | ID_REQUEST;
        self.write_register(station, AL_CONTROL, &control.to_le_bytes())?;
        let timeout = self.config.al_timeout;
        let s = self.poll(timeout, Awaited::AlState, |m| {
            let s = m.al_status(station)?;
            Ok((s.id_loaded() || s.error()).then_some(s))
        })?;
        if s.error() {
            return Err(Refusal::Al(AlRefused {
                requested: (control & 0xFF) as u8,
                state: s.state_bits(),
                code: s.code,
            })
            .into());
        }
        Ok(s.code.0)
    }
}
