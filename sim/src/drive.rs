//! The inverter's drive model: status machine, ramp, setpoints and actual values, faults.
//!
//! Sans-IO and deterministic: time only comes in as `now`. The status machine is
//! `proto::nord::state_machine` (BU 0620 §6.1.2.3); setpoints and actual values follow
//! §6.1.2.4 (4000h = 100 % of P105) and the function codes of P546/P543
//! (`proto::nord::scaling`); the ramp follows P102/P103 (time from 0 to P105).
//!
//! What the model does with the control bits (§6.1.2.1, p. 106):
//! - transitions chain within one telegram (047Fh from "Ready for switch-on" takes 3 then 4:
//!   §6.1.3 answers it with xx37h at once);
//! - in "Operation enabled" bit 4 = 0 sets the ramp generator to zero, bit 5 = 0 holds the
//!   frequency, bit 6 = 0 ramps to setpoint 0; bit 12 (priority over 11) turns left;
//! - "Shut down" (bit 0 = 0) brakes with P103 ("Reverse with brake ramp"); bit 3 = 0 or
//!   "Disable voltage" switches the output off at once; "Quick stop" brakes with P426
//!   (P103 when absent) and ends in "Switch-on block" at f = 0;
//! - a fault blocks all functions (state G, then H after [`FAULT_REACTION`]).
//!
//! Setpoint functions (P546): 1 setpoint frequency, 4 frequency addition, 5 frequency
//! subtraction, 23/24 setpoint position low/high word (BU 0620 §3.9, §6.1.2.4; BU 2100 §5.3:
//! "a single speed and a single position specification"); others have no effect. With a
//! position setpoint the drive in "Operation enabled" travels towards the position at the
//! setpoint frequency (ramping with P102/P103) and stops there: a plain model of positioning
//! (POSICON, BU 0510, is not among the manuals), in which "setpoint reached" (status bit 8)
//! means the position is reached. A low word alone is a signed 16-bit position, ±32.767
//! rotations (§6.1.2.4 p. 113). Actual-value functions
//! (P543): 1, 21, 23, 24 actual frequency (no slip in the model), 8, 19 setpoint frequency,
//! 20 setpoint after the ramp, 9 error number (as P700 [-01] shows it), 10/15 position
//! low/high word; others send 0.

use std::fmt;
use std::str::FromStr;
use std::time::Duration;

use proto::nord::control::ControlWord;
use proto::nord::scaling::{self, Transmission, INCREMENTS_PER_ROTATION, POSITION_LIMIT};
use proto::nord::state_machine::{self, State, Transition, EMERGENCY_STOP_COMPLETE};

/// Parameters the drive reads (the device implements it over the inverter's store).
pub trait DriveParams {
    /// Value of `number` (element 1-based for arrays) in the parameter set the control word
    /// selects, or `None` when the inverter has no such parameter.
    fn get(&self, number: u16, element: Option<u8>) -> Option<i32>;
}

/// The parameters [`Drive::cycle`] reads on every cycle (number, element): P105 maximum
/// frequency, P506 auto acknowledge, P102/P103/P426 ramps, P543 and P546 [-01]…[-05] bus actual
/// values and setpoints, P607/P608 gear ratio. A caller may keep their values while they
/// cannot have changed (the device does, per parameter set).
pub const CYCLE_PARAMETERS: [(u16, Option<u8>); 17] = [
    (105, None),
    (506, None),
    (102, None),
    (103, None),
    (426, None),
    (543, Some(1)),
    (543, Some(2)),
    (543, Some(3)),
    (543, Some(4)),
    (543, Some(5)),
    (546, Some(1)),
    (546, Some(2)),
    (546, Some(3)),
    (546, Some(4)),
    (546, Some(5)),
    (607, None),
    (608, None),
];

/// How long the error reaction (state G) lasts before "Fault" (H, transition 14).
pub const FAULT_REACTION: Duration = Duration::from_millis(20);
/// How long after power-on the charging relay engages (transition 1).
pub const CHARGING: Duration = Duration::from_millis(20);

/// Defaults when a parameter is absent: P102/P103 2.00 s, P105 50.0 Hz (BU 0620 §6.1.3),
/// P543 [-01..-05] = 1, 4, 9, 0, 0 and P546 [-01] = 1 (BU 0590 §5, p. 39–40).
const DEFAULT_RAMP: i32 = 200;
const DEFAULT_MAX_FREQUENCY: i32 = 500;
const DEFAULT_P543: [i32; 5] = [1, 4, 9, 0, 0];

/// A malformed error number.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("`{0}` is not an error number like 10.3 (group 1..999, sub-number 0..9)")]
pub struct FaultCodeError(pub String);

impl From<FaultCodeError> for String {
    fn from(e: FaultCodeError) -> String {
        e.to_string()
    }
}

/// An inverter error as P700 shows it, e.g. `10.0` (group 10, sub-number 0).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FaultCode {
    /// Error group (E10).
    pub group: u16,
    /// Sub-number (.3).
    pub sub: u8,
}

impl FaultCode {
    /// The P700 [-01] value: 10.3 is shown as 103 (BU 0620 §5.4.2: "P700, Index 1 = 103").
    pub fn p700(self) -> u16 {
        self.group * 10 + u16::from(self.sub)
    }
}

impl FromStr for FaultCode {
    type Err = FaultCodeError;
    fn from_str(s: &str) -> Result<Self, FaultCodeError> {
        let bad = || FaultCodeError(s.to_string());
        let t = s.trim().trim_start_matches(['E', 'e']);
        let (g, sub) = t.split_once('.').ok_or_else(bad)?;
        let group: u16 = g.parse().map_err(|_| bad())?;
        let sub: u8 = sub.parse().map_err(|_| bad())?;
        if group == 0 || group > 999 || sub > 9 {
            return Err(bad());
        }
        Ok(FaultCode { group, sub })
    }
}

impl fmt::Display for FaultCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "E{:03}.{}", self.group, self.sub)
    }
}

/// What one cycle returns.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DriveOutput {
    /// The status word.
    pub status: u16,
    /// Actual values 1..5 per P543.
    pub actuals: [u16; 5],
}

/// One inverter's drive.
#[derive(Debug, Clone)]
pub struct Drive {
    state: State,
    entered: Duration,
    last: Option<Duration>,
    /// The last control word the inverter evaluated (bit 10 set).
    previous: ControlWord,
    /// Output frequency in Hz, negative = left.
    frequency: f64,
    /// Setpoint frequency in Hz from the bus setpoints, signed.
    setpoint: f64,
    /// Frequency the ramp heads for this cycle.
    goal: f64,
    /// Motor position in rotations (one rotation per hertz-second: the model has no pole
    /// pairs or gear), for the actual-position functions of P543.
    position: f64,
    /// Setpoint position in increments from the setpoints of functions 23/24, if any.
    target: Option<i32>,
    fault: Option<FaultCode>,
    pending_fault: Option<FaultCode>,
    last_transition: Option<u8>,
}

impl Default for Drive {
    fn default() -> Self {
        Self::new()
    }
}

impl Drive {
    /// A drive just switched on (state A).
    pub fn new() -> Self {
        Drive {
            state: State::NotReadyForSwitchOn,
            entered: Duration::ZERO,
            last: None,
            previous: ControlWord(0),
            frequency: 0.0,
            setpoint: 0.0,
            goal: 0.0,
            position: 0.0,
            target: None,
            fault: None,
            pending_fault: None,
            last_transition: None,
        }
    }

    /// The status-machine state.
    pub fn state(&self) -> State {
        self.state
    }

    /// Output frequency in Hz (negative: rotation left).
    pub fn frequency_hz(&self) -> f64 {
        self.frequency
    }

    /// Setpoint frequency in Hz from the bus setpoints.
    pub fn setpoint_hz(&self) -> f64 {
        self.setpoint
    }

    /// Position in increments (1000 per rotation), limited to ±50000.00 rotations.
    pub fn position_increments(&self) -> i32 {
        let limit = f64::from(POSITION_LIMIT);
        (self.position * f64::from(INCREMENTS_PER_ROTATION))
            .round()
            .clamp(-limit, limit) as i32
    }

    /// The present error, if any.
    pub fn fault(&self) -> Option<FaultCode> {
        self.fault
    }

    /// An error raised but not yet taken into the status machine (it is, with the next cycle).
    pub fn pending_fault(&self) -> Option<FaultCode> {
        self.pending_fault
    }

    /// Number of the last transition taken (0 = emergency stop complete), if any.
    pub fn last_transition(&self) -> Option<u8> {
        self.last_transition
    }

    /// Raises an error; the next cycle takes transition 13.
    pub fn inject_fault(&mut self, code: FaultCode) {
        self.pending_fault = Some(code);
    }

    fn take(&mut self, t: &Transition, now: Duration) {
        self.state = t.to;
        self.entered = now;
        self.last_transition = Some(t.number);
    }

    fn take_automatic(&mut self, number: u8, now: Duration) {
        if let Some(t) = state_machine::automatic(number) {
            if t.from.contains(&self.state) {
                self.take(t, now);
            }
        }
    }

    /// One bus cycle: control word and setpoints in, status word and actual values out.
    pub fn cycle(
        &mut self,
        control: u16,
        setpoints: &[u16],
        params: &dyn DriveParams,
        now: Duration,
    ) -> DriveOutput {
        let control = ControlWord(proto::nord::mutant::CONTROL_BITS.apply(control));
        let dt = self
            .last
            .map_or(Duration::ZERO, |l| now.saturating_sub(l))
            .as_secs_f64();
        self.last = Some(now);
        let max_hz = f64::from(params.get(105, None).unwrap_or(DEFAULT_MAX_FREQUENCY)) / 10.0;

        self.automatic_transitions(now);
        self.auto_acknowledge(params, now);
        if control.valid() {
            self.evaluate(control, now);
            let functions = setpoint_functions(params);
            self.setpoint = setpoint_hz(control, setpoints, &functions, max_hz);
            self.target = setpoint_position(setpoints, &functions);
        }
        self.run(params, max_hz, dt);
        if self.state == State::EmergencyStopActive && self.frequency == 0.0 {
            self.take(&EMERGENCY_STOP_COMPLETE, now);
        }
        DriveOutput {
            status: proto::nord::mutant::STATUS_BITS.apply(self.status_word(control)),
            actuals: self.actuals(params, max_hz),
        }
    }

    /// Transitions 13 (a fault), 1 (charging relay) and 14 (end of the fault reaction).
    fn automatic_transitions(&mut self, now: Duration) {
        if let Some(code) = self.pending_fault.take() {
            if self.fault.is_none() {
                self.fault = Some(code);
            }
            self.take_automatic(13, now);
        }
        if now >= CHARGING {
            self.take_automatic(1, now);
        }
        if now.saturating_sub(self.entered) >= FAULT_REACTION {
            self.take_automatic(14, now);
        }
    }

    /// P506 "Auto. Acknowledge Error" (BU 0620 §5.2): when activated (not 0), an error is
    /// acknowledged without the bus once its reaction is complete — transition 15 from
    /// "Fault" to "Switch-on block", as the acknowledge edge of control bit 7 takes it.
    fn auto_acknowledge(&mut self, params: &dyn DriveParams, now: Duration) {
        if self.state == State::Fault && params.get(506, None).unwrap_or(0) != 0 {
            if let Some(t) = state_machine::TRANSITIONS
                .iter()
                .find(|t| t.number == 15 && t.from.contains(&State::Fault))
            {
                self.fault = None;
                self.take(t, now);
            }
        }
    }

    /// Applies a valid control word: transitions by priority, chained within the telegram.
    fn evaluate(&mut self, control: ControlWord, now: Duration) {
        let mut previous = self.previous;
        for _ in 0..State::ALL.len() {
            let Some(t) = state_machine::next(self.state, control, previous) else {
                break;
            };
            if t.to == State::SwitchOnBlock && self.state == State::Fault {
                self.fault = None;
            }
            self.take(t, now);
            previous = control;
        }
        self.previous = control;
    }

    /// Moves the output frequency one cycle towards its goal.
    fn run(&mut self, params: &dyn DriveParams, max_hz: f64, dt: f64) {
        let c = self.previous;
        let before = self.frequency;
        let ramp =
            |number: u16| f64::from(params.get(number, None).unwrap_or(DEFAULT_RAMP)) / 100.0;
        let (goal, ramp_s) = match self.state {
            State::OperationEnabled if !c.bit(ControlWord::ENABLE_PULSES) => (0.0, 0.0),
            State::OperationEnabled if !c.bit(ControlWord::ENABLE_RAMP) => (self.frequency, 0.0),
            State::OperationEnabled if !c.bit(ControlWord::ENABLE_SETPOINT) => (0.0, ramp(103)),
            State::OperationEnabled => {
                let goal = match self.target {
                    Some(t) => {
                        let remaining = rotations(t) - self.position;
                        if remaining == 0.0 {
                            0.0
                        } else {
                            self.setpoint.abs() * remaining.signum()
                        }
                    }
                    None => self.setpoint,
                };
                let up = goal.abs() > self.frequency.abs() && goal * self.frequency >= 0.0;
                (goal, ramp(if up { 102 } else { 103 }))
            }
            State::EmergencyStopActive => (
                0.0,
                params
                    .get(426, None)
                    .map_or_else(|| ramp(103), |v| f64::from(v) / 100.0),
            ),
            State::ReadyForSwitchOn | State::SwitchedOn
                if c.bit(ControlWord::ENABLE_OPERATION_BIT) =>
            {
                (0.0, ramp(103))
            }
            _ => (0.0, 0.0),
        };
        let step = if ramp_s <= 0.0 {
            f64::INFINITY
        } else {
            max_hz * dt / ramp_s
        };
        let diff = goal - self.frequency;
        self.frequency = if diff.abs() <= step {
            goal
        } else {
            self.frequency + step * diff.signum()
        };
        self.goal = goal;
        let from = self.position;
        self.position += (before + self.frequency) / 2.0 * dt * gear_factor(params);
        if let (State::OperationEnabled, Some(t)) = (self.state, self.target) {
            // Reached or passed within this cycle: stop at the position.
            let target = rotations(t);
            if (target - self.position) * (target - from) <= 0.0 {
                self.position = target;
                self.frequency = 0.0;
                self.goal = 0.0;
            }
        }
    }

    /// Whether the setpoint is reached (status bit 8): the frequency its goal, and with a
    /// position setpoint in "Operation enabled" the position.
    fn setpoint_reached(&self) -> bool {
        let at_position = match (self.state, self.target) {
            (State::OperationEnabled, Some(t)) => self.position_increments() == t,
            _ => true,
        };
        (self.frequency - self.goal).abs() < 1e-6 && at_position
    }

    fn status_word(&self, control: ControlWord) -> u16 {
        let (_, base) = self.state.status_bits();
        let c = self.previous;
        let mut s = base;
        if !matches!(
            self.state,
            State::ReadyForSwitchOn
                | State::SwitchedOn
                | State::OperationEnabled
                | State::EmergencyStopActive
        ) {
            // Bits 4 and 5 are X in these states: they show the commands present (§6.1.2.2) in
            // the last control word the inverter evaluated.
            s |= u16::from(c.bit(ControlWord::DISABLE_VOLTAGE)) << 4
                | u16::from(c.bit(ControlWord::EMERGENCY_STOP)) << 5;
        }
        s |= u16::from(self.setpoint_reached()) << 8;
        s |= u16::from(control.valid()) << 9;
        s |= if c.left() { 1 << 12 } else { 1 << 11 };
        s |= u16::from(c.parameter_set() - 1) << 14;
        s
    }

    fn actuals(&self, params: &dyn DriveParams, max_hz: f64) -> [u16; 5] {
        let hz = |f: f64| scaling::value_to_raw_saturating(f, max_hz) as u16;
        let (low, high) =
            scaling::position_words(i64::from(self.position_increments())).unwrap_or_default();
        let mut element = 0u8;
        DEFAULT_P543.map(|default| {
            element += 1;
            let code = params.get(543, Some(element)).unwrap_or(default);
            let transmission = scaling::actual_function(code).map(|f| f.transmission);
            match (code, transmission) {
                (_, Some(Transmission::PositionLow)) => low,
                (_, Some(Transmission::PositionHigh)) => high,
                (1 | 21 | 23 | 24, _) => hz(self.frequency),
                (8 | 19, _) => hz(self.setpoint),
                (20, _) => hz(self.goal),
                (9, _) => self.fault.map_or(0, FaultCode::p700),
                _ => 0,
            }
        })
    }
}

/// The P546 function of each bus setpoint 1..5: [-01] "setpoint frequency" (1) unless set,
/// the others off (0).
fn setpoint_functions(params: &dyn DriveParams) -> [i32; 5] {
    std::array::from_fn(|n| {
        let element = n as u8 + 1;
        params
            .get(546, Some(element))
            .unwrap_or(i32::from(element == 1))
    })
}

/// The setpoint frequency the bus setpoints give per their P546 `functions` (§6.1.2.4;
/// BU 0590 §5 p. 40): 1 setpoint frequency, 4 addition, 5 subtraction, as percentages of
/// P105; bit 12 turns left.
fn setpoint_hz(control: ControlWord, setpoints: &[u16], functions: &[i32; 5], max_hz: f64) -> f64 {
    let sum: f64 = setpoints
        .iter()
        .zip(functions)
        .map(|(raw, code)| {
            let hz = scaling::raw_to_value(*raw as i16, max_hz);
            match code {
                1 | 4 => hz,
                5 => -hz,
                _ => 0.0,
            }
        })
        .sum();
    if control.left() {
        -sum
    } else {
        sum
    }
}

/// The gear ratio factor P607 / P608 (BU 0590 §4.1.5: with it the low word's position range
/// "can be extended … an according reduction in the resolution"): positions count rotations
/// of the output, motor rotations × P607 / P608; 1 where the inverter has neither.
fn gear_factor(params: &dyn DriveParams) -> f64 {
    match (params.get(607, None), params.get(608, None)) {
        (Some(n), Some(d)) if n > 0 && d > 0 => f64::from(n) / f64::from(d),
        _ => 1.0,
    }
}

/// Rotations of a position in increments.
fn rotations(increments: i32) -> f64 {
    f64::from(increments) / f64::from(INCREMENTS_PER_ROTATION)
}

/// The setpoint position the bus setpoints give per P546 functions 23 (low word) and 24 (high
/// word) (§6.1.2.4 "Transmission of positions"), or `None` when no setpoint carries one. A low
/// word without a high word is a signed 16-bit position (±32.767 rotations).
fn setpoint_position(setpoints: &[u16], functions: &[i32; 5]) -> Option<i32> {
    let (mut low, mut high) = (None, None);
    for (raw, code) in setpoints.iter().zip(functions) {
        match scaling::setpoint_function(*code).map(|f| f.transmission) {
            Some(Transmission::PositionLow) => low = Some(*raw),
            Some(Transmission::PositionHigh) => high = Some(*raw),
            _ => {}
        }
    }
    match (low, high) {
        (None, None) => None,
        (Some(l), None) => Some(scaling::position_of_low_word(l)),
        (l, Some(h)) => Some(scaling::position_of(l.unwrap_or(0), h)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The settings of BU 0620 §6.1.3 (p. 114): P105 = 50 Hz, P543 [-01] = 1, P546 [-01] = 1;
    /// P102/P103 = 2.00 s; P543 [-02] = 9 (error number), [-03] = 10 (position low word).
    struct Example;
    impl DriveParams for Example {
        fn get(&self, number: u16, element: Option<u8>) -> Option<i32> {
            match (number, element) {
                (105, _) => Some(500),
                (102 | 103, _) => Some(200),
                (543, Some(1)) | (546, Some(1)) => Some(1),
                (543, Some(2)) => Some(9),
                (543, Some(3)) => Some(10),
                (543 | 546, Some(_)) => Some(0),
                _ => None,
            }
        }
    }

    fn ms(n: u64) -> Duration {
        Duration::from_millis(n)
    }

    /// Runs `word` with `setpoint` every 4 ms from `from` to `to` (ms), returning the last output.
    fn run(d: &mut Drive, word: u16, setpoint: u16, from: u64, to: u64) -> DriveOutput {
        let mut out = d.cycle(word, &[setpoint], &Example, ms(from));
        for t in (from + 4..=to).step_by(4) {
            out = d.cycle(word, &[setpoint], &Example, ms(t));
        }
        out
    }

    #[test]
    fn switching_example_of_bu0620_6_1_3() {
        // p. 114: 0000h, xx40h at power-on; 047Eh → xx31h; 047Fh + 2000h → xx37h, 2000h.
        let mut d = Drive::new();
        assert_eq!(d.cycle(0, &[], &Example, ms(0)).status & 0x7F, 0x00);
        assert_eq!(d.cycle(0, &[], &Example, ms(40)).status & 0xFF, 0x40);
        assert_eq!(d.last_transition(), Some(1));
        assert_eq!(d.cycle(0x047E, &[0], &Example, ms(44)).status, 0x0B31);
        let out = d.cycle(0x047F, &[0x2000], &Example, ms(48));
        assert_eq!(out.status & 0xFF, 0x37);
        assert_eq!(d.last_transition(), Some(4));
        let out = run(&mut d, 0x047F, 0x2000, 52, 1200);
        assert_eq!(out.actuals[0], 0x2000);
        assert_eq!(out.status & 0x100, 0x100, "setpoint reached");
        assert!((d.frequency_hz() - 25.0).abs() < 1e-9);
        // 047Eh: "Ready for switch-on" at once, braking along P103 to 0.
        let out = d.cycle(0x047E, &[0x2000], &Example, ms(1204));
        assert_eq!(out.status & 0xFF, 0x31);
        assert!(d.frequency_hz() > 24.0);
        let out = run(&mut d, 0x047E, 0x2000, 1208, 2300);
        assert_eq!(out.actuals[0], 0);
        // 047Fh + 1000h: 12.5 Hz.
        let out = run(&mut d, 0x047F, 0x1000, 2304, 3500);
        assert_eq!((out.status & 0xFF, out.actuals[0]), (0x37, 0x1000));
    }

    #[test]
    fn fault_and_acknowledge() {
        let mut d = Drive::new();
        d.cycle(0x047E, &[], &Example, ms(40));
        d.inject_fault("10.3".parse().unwrap());
        let out = d.cycle(0x047E, &[], &Example, ms(44));
        assert_eq!(out.status & 0x4F, 0x0F, "G: error reaction active");
        assert_eq!(out.actuals[1], 103, "P543 = 9: error number");
        assert_eq!(d.cycle(0x047E, &[], &Example, ms(80)).status & 0x4F, 0x08);
        assert_eq!(d.last_transition(), Some(14));
        assert_eq!(d.fault().map(FaultCode::p700), Some(103));
        // Acknowledge: bit 7 0 → 1 (transition 15); 0480h also disables voltage: stays in B.
        d.cycle(0x0480, &[], &Example, ms(84));
        assert_eq!(d.state(), State::SwitchOnBlock);
        assert_eq!(d.fault(), None);
    }

    #[test]
    fn p506_acknowledges_automatically() {
        struct AutoAck;
        impl DriveParams for AutoAck {
            fn get(&self, number: u16, element: Option<u8>) -> Option<i32> {
                match number {
                    506 => Some(1),
                    _ => Example.get(number, element),
                }
            }
        }
        let mut d = Drive::new();
        d.cycle(0x047E, &[], &AutoAck, ms(40));
        d.inject_fault("3.0".parse().unwrap());
        d.cycle(0x047E, &[], &AutoAck, ms(44));
        assert_eq!(d.state(), State::ErrorReactionActive);
        // After the reaction (14) P506 takes transition 15; 047Eh then shuts down (2).
        d.cycle(0x047E, &[], &AutoAck, ms(80));
        assert_eq!((d.state(), d.fault()), (State::ReadyForSwitchOn, None));
    }

    #[test]
    fn invalid_control_data_is_ignored() {
        let mut d = Drive::new();
        let out = d.cycle(0x007E, &[0x2000], &Example, ms(40));
        assert_eq!(d.state(), State::SwitchOnBlock);
        assert_eq!(out.status & 0x0200, 0, "bus control not active");
    }

    #[test]
    fn quick_stop_ends_in_switch_on_block() {
        let mut d = Drive::new();
        d.cycle(0x047E, &[], &Example, ms(40));
        run(&mut d, 0x047F, 0x4000, 44, 2100);
        let out = d.cycle(0x047B, &[0x4000], &Example, ms(2104));
        assert_eq!(out.status & 0x7F, 0x17, "F: emergency stop active");
        run(&mut d, 0x047B, 0x4000, 2108, 4200);
        assert_eq!(d.state(), State::SwitchOnBlock);
        assert_eq!(d.last_transition(), Some(0));
    }

    #[test]
    fn left_rotation_and_control_bits_4_to_6() {
        let mut d = Drive::new();
        d.cycle(0x047E, &[], &Example, ms(40));
        // Bit 12: left, negative frequency, status bit 12.
        let out = run(&mut d, 0x147F, 0x2000, 44, 1200);
        assert_eq!(out.actuals[0], 0xE000);
        assert_eq!(out.status & 0x1800, 0x1000);
        // Bit 5 = 0 holds the frequency although the setpoint changes.
        let out = run(&mut d, 0x145F, 0x4000, 1204, 1500);
        assert_eq!(out.actuals[0], 0xE000);
        // Bit 4 = 0: ramp generator to zero at once; still "Operation enabled".
        let out = d.cycle(0x146F, &[0x4000], &Example, ms(1504));
        assert_eq!((out.actuals[0], out.status & 0x7F), (0, 0x37));
    }

    #[test]
    fn disable_voltage_switches_off_at_once() {
        let mut d = Drive::new();
        d.cycle(0x047E, &[], &Example, ms(40));
        run(&mut d, 0x047F, 0x2000, 44, 1200);
        let out = d.cycle(0x047D, &[0x2000], &Example, ms(1204));
        assert_eq!((out.status & 0x4F, out.actuals[0]), (0x40, 0));
        assert_eq!(d.last_transition(), Some(9));
    }

    /// BU 0620 §3.9 (p. 73) / BU 2100 §5.3: P546 [-01] = 1 (speed), [-02] = 23, [-03] = 24
    /// (position low/high word); P543 [-01] = 1, [-02] = 10, [-03] = 15.
    struct Positioning;
    impl DriveParams for Positioning {
        fn get(&self, number: u16, element: Option<u8>) -> Option<i32> {
            match (number, element) {
                (105, _) => Some(500),
                (102 | 103, _) => Some(200),
                (543 | 546, Some(1)) => Some(1),
                (543, Some(2)) => Some(10),
                (543, Some(3)) => Some(15),
                (546, Some(2)) => Some(23),
                (546, Some(3)) => Some(24),
                (543 | 546, Some(_)) => Some(0),
                _ => None,
            }
        }
    }

    fn run_to(d: &mut Drive, word: u16, setpoints: &[u16], from: u64, to: u64) -> DriveOutput {
        let mut out = d.cycle(word, setpoints, &Positioning, ms(from));
        for t in (from + 4..=to).step_by(4) {
            out = d.cycle(word, setpoints, &Positioning, ms(t));
        }
        out
    }

    #[test]
    fn gear_ratio_factor_scales_the_position() {
        // BU 0590 §4.1.5: P607 / P608 = 1 / 10: 10 motor rotations are one output rotation.
        struct Gear;
        impl DriveParams for Gear {
            fn get(&self, number: u16, _: Option<u8>) -> Option<i32> {
                match number {
                    607 => Some(1),
                    608 => Some(10),
                    _ => None,
                }
            }
        }
        assert_eq!(gear_factor(&Gear), 0.1);
        assert_eq!(gear_factor(&Positioning), 1.0);
    }

    #[rstest::rstest]
    // 5.000 rotations = 5000 increments = 0000 1388h; -2.5 rotations = FFFF F63Ch.
    #[case(0x1388, 0x0000, 5000)]
    #[case(0xF63C, 0xFFFF, -2500)]
    fn travels_to_the_setpoint_position(#[case] low: u16, #[case] high: u16, #[case] at: i32) {
        let mut d = Drive::new();
        d.cycle(0x047E, &[], &Positioning, ms(40));
        // 50 % speed (25 Hz: 25 rotations per second in the model).
        let out = run_to(&mut d, 0x047F, &[0x2000, low, high], 44, 120);
        assert_eq!(out.status & 0x0100, 0, "on the way: not reached");
        let out = run_to(&mut d, 0x047F, &[0x2000, low, high], 124, 3000);
        assert_eq!(d.position_increments(), at);
        assert_eq!(
            (out.actuals[1], out.actuals[2]),
            (low, high),
            "P543 10/15 give the position back"
        );
        assert_eq!((out.actuals[0], out.status & 0x0100), (0, 0x0100));
    }

    #[test]
    fn low_word_alone_is_signed_and_no_speed_no_travel() {
        struct LowOnly;
        impl DriveParams for LowOnly {
            fn get(&self, number: u16, element: Option<u8>) -> Option<i32> {
                match (number, element) {
                    (546, Some(2)) => Some(23),
                    _ => Positioning.get(number, element),
                }
            }
        }
        assert_eq!(
            setpoint_position(&[0x2000, 0xFC18], &setpoint_functions(&LowOnly)),
            Some(-1000)
        );
        assert_eq!(
            setpoint_position(&[0x2000, 0x03E8, 0x0001], &setpoint_functions(&Positioning)),
            Some(0x1_03E8)
        );
        assert_eq!(
            setpoint_position(&[0x2000], &setpoint_functions(&Example)),
            None
        );
        // Speed setpoint 0: the drive stays where it is.
        let mut d = Drive::new();
        d.cycle(0x047E, &[], &Positioning, ms(40));
        run_to(&mut d, 0x047F, &[0, 0x1388, 0], 44, 1000);
        assert_eq!(d.position_increments(), 0);
    }

    #[test]
    fn fault_codes_parse() {
        assert_eq!("E10.3".parse::<FaultCode>().map(|c| c.p700()), Ok(103));
        assert!("10".parse::<FaultCode>().is_err());
        assert!("x.1".parse::<FaultCode>().is_err());
        assert!("10.10".parse::<FaultCode>().is_err());
        assert_eq!(FaultCode { group: 10, sub: 0 }.to_string(), "E010.0");
    }
}
