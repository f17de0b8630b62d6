//! Each node's CAN controller as ISO 11898-1's fault confinement has it, for the faults a case
//! injects into the segment: a transceiver that destroys the node's frames (every other node
//! sees each as an error: an error frame), a controller driven error passive, and one in bus
//! off.
//!
//! ISO 11898-1 (fault confinement; Bosch CAN Specification 2.0 part A/B §8): each node counts
//! its transmit errors (TEC) — plus 8 for each transmission destroyed by an error, minus 1 for
//! each one that succeeds. At a TEC of 128 or more the node is **error passive** (it still
//! transmits and receives); back at 127 or less it is error active again. Above 255 it is **bus
//! off**: it takes no part in the bus at all, neither transmitting nor acknowledging; it may
//! become error active again, with both counters at 0, after 128 occurrences of 11 consecutive
//! recessive bits, at the system bus's 250 kBaud (P514) at least 128 · 11 · 4 µs = 5.632 ms.
//! A transmission destroyed by an error is retransmitted automatically (ISO 11898-1 "automatic
//! retransmission").
//!
//! CiA 301 V4.2 §7.2.7.1 (emergency object usage, its table of emergency error codes) gives the EMCY a
//! node sends: 8120h "CAN in error passive mode", 8140h "recovered from bus off"; the error
//! register (1001h) with its generic and communication bits.
//!
//! What neither the manuals nor CiA 301 state, and the simulator chooses (each "not stated by
//! the manuals"):
//! - Recovery from bus off is automatic, [`RECOVERY`] = 200 ms after the node went bus off
//!   (the node's software restarts its controller after 200 ms, as Linux's `restart-ms` or a
//!   CANopen stack's timer would; ISO 11898-1's 5.632 ms is the least it could be). On recovery
//!   the node sends EMCY 8140h and its heartbeat resumes; what it missed meanwhile it missed
//!   (the consumed heartbeat too: its inverter's P120 monitoring counts that silence), and
//!   what it had to send meanwhile is lost (its heartbeats, answers), except the EMCY of an
//!   inverter error that came while bus off: sent once it is back, after its 8140h.
//! - [`ERROR_FRAMES`]: the node's transceiver destroys its next [`BURST`] transmission attempts
//!   (the first frame it sends after the injection, retransmitted each time), then the frame
//!   goes through: TEC + 8 · 8 − 1. Each destroyed attempt is reported by every other node's
//!   controller as a bus error: to a SocketCAN listener (the harness) an error frame of class
//!   `CAN_ERR_PROT | CAN_ERR_BUSERROR` with a stuff error (`CAN_ERR_PROT_STUFF`) in the data
//!   field (`CAN_ERR_PROT_LOC_DATA`). Injected again and again, the counter climbs to error
//!   passive and bus off by the rules above.
//! - [`ERROR_PASSIVE`]: the TEC set to 255, the highest below bus off (128 successful frames
//!   bring it back to error active); EMCY 8120h at once. No EMCY when it is error active again
//!   (CiA 301 leaves it open).
//! - [`BUS_OFF`]: the TEC above 255 at once: the node is bus off from the injection on.
//!
//! What the manuals state: an SK 5x0P inverter (the SK 550P's FI 1…8) whose CAN is bus off
//! reports E10.0 with P700 [-04] 7585h "CAN in Bus Off state" (BU 0620 §5.3 p. 94), when it
//! goes bus off (`Segment`; unless an error is present or P513 ignores communication errors).
//! For the SK 54xE behind a module the manuals here do not say: the simulated one reports
//! nothing for its own bus off (only its P120 monitoring of the silence).

use std::time::Duration;

use proto::can::socketcan::{prot, ErrorClass, ErrorFrame};
use proto::can::CanFrame;
use proto::nord::led::BusState;

/// The fault that puts a node's controller bus off (`inject: { inverter: N, error:
/// node-bus-off }`). Not `bus-off`: that name, with no inverter or any, is the interface's own
/// controller (`Device::inject_fault`), and a suite's `inject` names FI 1 when it names none.
pub const BUS_OFF: &str = "node-bus-off";
/// The fault that drives a node's controller error passive (`error: error-passive`).
pub const ERROR_PASSIVE: &str = "error-passive";
/// The fault of a transceiver that destroys the node's frames (`error: error-frames`).
pub const ERROR_FRAMES: &str = "error-frames";

/// The error warning limit (ISO 11898-1 leaves it to the implementation; 96 is the usual one,
/// SocketCAN's CAN_ERR_CRTL_TX_WARNING): the "Bus warning" of BU 0620 §5.5.1.2.
const WARNING_FROM: u16 = 96;
/// Error passive from this TEC on (ISO 11898-1: "greater than 127").
const PASSIVE_FROM: u16 = 128;
/// Bus off from this TEC on (ISO 11898-1: "greater than 255").
const BUS_OFF_FROM: u16 = 256;
/// What a destroyed transmission adds to the TEC.
const TX_ERROR: u16 = 8;

/// The least time a bus-off node needs to recover: 128 · 11 recessive bits at 250 kBaud.
pub const MIN_RECOVERY: Duration = Duration::from_micros(128 * 11 * 4);
/// When a bus-off node is error active again (not stated by the manuals, see the module).
pub const RECOVERY: Duration = Duration::from_millis(200);
/// The transmission attempts an [`ERROR_FRAMES`] injection destroys.
pub const BURST: u16 = 8;

/// CiA 301 emergency error code 8120h "CAN in error passive mode".
pub(super) const EMCY_PASSIVE: u16 = 0x8120;
/// CiA 301 emergency error code 8140h "recovered from bus off".
pub(super) const EMCY_RECOVERED: u16 = 0x8140;

/// The error frame a listener's controller reports for each destroyed transmission (see the
/// module).
pub fn bus_error() -> ErrorFrame {
    let mut data = [0; 8];
    data[2] = prot::STUFF;
    data[3] = prot::LOC_DATA;
    ErrorFrame {
        class: ErrorClass(ErrorClass::PROT.0 | ErrorClass::BUSERROR.0),
        data,
    }
}

/// One node's controller.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Controller {
    /// The transmit error counter.
    tec: u16,
    /// Transmission attempts the transceiver still destroys.
    corrupt: u16,
    /// Since when the node is bus off.
    off_since: Option<Duration>,
    /// Reported error passive (its EMCY due or sent).
    passive: bool,
    /// An EMCY to send (8120h, 8140h) at the node's next chance.
    emcy: Option<u16>,
    /// Went bus off since [`Controller::went_bus_off`] last said so.
    went_off: bool,
}

impl Controller {
    /// Takes an injected fault (one of this module's names); `false`: not a controller fault.
    pub(super) fn inject(&mut self, error: &str, now: Duration) -> bool {
        match error {
            ERROR_FRAMES => self.corrupt += BURST,
            ERROR_PASSIVE if self.off_since.is_none() => {
                self.tec = BUS_OFF_FROM - 1;
                self.check();
            }
            ERROR_PASSIVE => {}
            BUS_OFF => self.go_bus_off(now),
            _ => return false,
        }
        true
    }

    /// Whether the controller went bus off since the last call (once per bus off).
    pub(super) fn went_bus_off(&mut self) -> bool {
        std::mem::take(&mut self.went_off)
    }

    /// Bus off: takes no part in the bus.
    pub(super) fn is_bus_off(&self) -> bool {
        self.off_since.is_some()
    }

    /// Its state as the "BUS" LED tells it apart: bus off, past the error warning limit (a
    /// counter at [`WARNING_FROM`] or more, error passive included), or active.
    pub(super) fn bus_state(&self) -> BusState {
        match (self.off_since, self.tec) {
            (Some(_), _) => BusState::Off,
            (None, tec) if tec >= WARNING_FROM => BusState::Warning,
            _ => BusState::Active,
        }
    }

    /// When the controller wants the node polled: its recovery from bus off, or now for an
    /// EMCY to send.
    pub(super) fn next_due(&self, now: Duration) -> Option<Duration> {
        match self.off_since {
            Some(since) => Some(since + RECOVERY),
            None => self.emcy.map(|_| now),
        }
    }

    /// At `now`: back from bus off once [`RECOVERY`] has passed (counters at 0, EMCY 8140h
    /// due). Then the EMCY due, if any, taken.
    pub(super) fn wake(&mut self, now: Duration) -> Option<u16> {
        if self.off_since.is_some_and(|t| now >= t + RECOVERY) {
            *self = Controller {
                emcy: Some(EMCY_RECOVERED),
                ..Controller::default()
            };
        }
        match self.off_since {
            Some(_) => None,
            None => self.emcy.take(),
        }
    }

    /// The node transmits `frame` at `now`: the frame on the bus, or `None` when it never got
    /// there (bus off, or bus off on the way); each destroyed attempt an error frame in
    /// `errors`.
    pub(super) fn transmit(
        &mut self,
        frame: CanFrame,
        now: Duration,
        errors: &mut Vec<(Duration, ErrorFrame)>,
    ) -> Option<CanFrame> {
        while self.off_since.is_none() && self.corrupt > 0 {
            self.corrupt -= 1;
            self.tec += TX_ERROR;
            errors.push((now, bus_error()));
            if self.tec >= BUS_OFF_FROM {
                self.go_bus_off(now);
            } else {
                self.check();
            }
        }
        if self.off_since.is_some() {
            return None;
        }
        self.tec = self.tec.saturating_sub(1);
        self.check();
        Some(frame)
    }

    fn go_bus_off(&mut self, now: Duration) {
        self.tec = BUS_OFF_FROM;
        self.corrupt = 0;
        self.emcy = None;
        if self.off_since.is_none() {
            self.off_since = Some(now);
            self.went_off = true;
        }
    }

    /// Error passive or active as the TEC stands; entering error passive makes EMCY 8120h due.
    fn check(&mut self) {
        let passive = self.tec >= PASSIVE_FROM;
        if passive && !self.passive {
            self.emcy = Some(EMCY_PASSIVE);
        }
        self.passive = passive;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: Duration = Duration::from_millis(1);

    fn frame() -> CanFrame {
        CanFrame::new(0x722, &[0x7F]).unwrap()
    }

    #[test]
    fn the_least_recovery_is_128_times_11_bits_at_250_kbaud() {
        assert_eq!(MIN_RECOVERY, Duration::from_micros(5632));
        assert!(RECOVERY >= MIN_RECOVERY);
    }

    #[test]
    fn a_burst_of_destroyed_attempts_shows_as_error_frames_then_the_frame_goes() {
        let mut c = Controller::default();
        let mut errors = Vec::new();
        assert!(c.inject(ERROR_FRAMES, MS));
        assert_eq!(c.transmit(frame(), MS, &mut errors), Some(frame()));
        assert_eq!(errors.len(), usize::from(BURST));
        assert_eq!(errors[0].1.class, ErrorClass(0x088));
        assert_eq!(errors[0].1.data, [0, 0, 0x04, 0x0A, 0, 0, 0, 0]);
        // 8 errors (+64) and a success (−1): error active, no EMCY.
        assert_eq!(c.tec, 63);
        assert_eq!(c.wake(MS), None);
        // The next frame goes through untouched.
        errors.clear();
        assert_eq!(c.transmit(frame(), MS, &mut errors), Some(frame()));
        assert!(errors.is_empty());
        assert_eq!(c.tec, 62);
    }

    #[test]
    fn errors_again_and_again_lead_to_error_passive_then_bus_off() {
        let mut c = Controller::default();
        let mut errors = Vec::new();
        // 62 + 64 = 126 − 1: still active; then 125 + 64 = 189: passive, EMCY 8120h.
        c.tec = 62;
        c.inject(ERROR_FRAMES, MS);
        c.transmit(frame(), MS, &mut errors);
        assert_eq!((c.tec, c.passive, c.wake(MS)), (125, false, None));
        c.inject(ERROR_FRAMES, MS);
        assert!(c.transmit(frame(), MS, &mut errors).is_some());
        assert_eq!((c.tec, c.passive), (188, true));
        assert_eq!(c.wake(MS), Some(EMCY_PASSIVE));
        assert_eq!(c.wake(MS), None, "once");
        // 188 + 64 = 252: passive still; then bus off on the ninth… the next burst.
        c.inject(ERROR_FRAMES, MS);
        assert!(c.transmit(frame(), MS, &mut errors).is_some());
        c.inject(ERROR_FRAMES, 2 * MS);
        assert_eq!(c.transmit(frame(), 2 * MS, &mut errors), None);
        assert!(c.is_bus_off());
        assert_eq!(c.next_due(3 * MS), Some(2 * MS + RECOVERY));
    }

    #[test]
    fn bus_off_is_silent_until_it_recovers_with_emcy_8140h() {
        let mut c = Controller::default();
        let mut errors = Vec::new();
        assert!(c.inject(BUS_OFF, 10 * MS));
        assert!(c.is_bus_off());
        assert!(c.went_bus_off());
        assert!(!c.went_bus_off(), "once");
        c.inject(BUS_OFF, 20 * MS);
        assert!(!c.went_bus_off(), "still the same bus off");
        assert_eq!(c.transmit(frame(), 11 * MS, &mut errors), None);
        assert!(
            errors.is_empty(),
            "a bus-off node sends no error frames either"
        );
        assert_eq!(c.wake(10 * MS + RECOVERY - MS), None);
        assert!(c.is_bus_off());
        assert_eq!(c.wake(10 * MS + RECOVERY), Some(EMCY_RECOVERED));
        assert!(!c.is_bus_off());
        assert_eq!((c.tec, c.passive), (0, false));
        assert_eq!(c.transmit(frame(), 300 * MS, &mut errors), Some(frame()));
        // Error passive: EMCY 8120h, and the node keeps transmitting.
        assert!(c.inject(ERROR_PASSIVE, 400 * MS));
        assert_eq!(c.next_due(400 * MS), Some(400 * MS));
        assert_eq!(c.wake(400 * MS), Some(EMCY_PASSIVE));
        assert_eq!(c.transmit(frame(), 400 * MS, &mut errors), Some(frame()));
        assert!(c.passive);
        assert!(!c.inject("off-bus", MS));
    }
}
