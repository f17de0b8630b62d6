//! The inverter's drive model: status machine, ramp, setpoints and actual values, faults.
//!
//! Sans-IO and deterministic: time only comes in as `now`. The status machine is
//! `proto::nord::state_machine` (BU 0620 §6.1.2.3); setpoints and actual values follow
//! §6.1.2.4 (4000h = 100 % of P105); the ramp follows P102/P103 (time from 0 to P105).
//! Actual-value functions (P543): 1 frequency, 10/15 position low/high word. Setpoint functions
//! (P546): 1 frequency; the position setpoints 23/24 need positioning (POSICON), which the model
//! does not have, so they are read as "no function".

use std::fmt;
use std::str::FromStr;
use std::time::Duration;

use proto::nord::control::ControlWord;
use proto::nord::state_machine::{self, State};

/// Parameters the drive reads (the device implements it over the inverter's store).
pub trait DriveParams {
    /// Value of `number` (element 1-based for arrays), parameter set 1.
    fn get(&self, number: u16, element: Option<u8>) -> Option<i32>;
}

/// How long the error reaction (state G) lasts before "Fault" (H).
const FAULT_REACTION: Duration = Duration::from_millis(20);
/// How long after power-on the charging relay engages (transition 1).
const CHARGING: Duration = Duration::from_millis(20);
/// 100 % in process data (§6.1.2.4).
const FULL_SCALE: f64 = 16384.0;

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
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("`{s}` is not an error number like 10.3");
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
    pub actuals: Vec<u16>,
}

/// One inverter's drive.
#[derive(Debug, Clone)]
pub struct Drive {
    state: State,
    entered: Duration,
    last: Option<Duration>,
    previous: ControlWord,
    frequency: f64,
    target: f64,
    /// Motor position in rotations (one rotation per hertz-second: the model has no pole
    /// pairs or gear), for the actual-position functions of P543.
    position: f64,
    fault: Option<FaultCode>,
    pending_fault: Option<FaultCode>,
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
            target: 0.0,
            position: 0.0,
            fault: None,
            pending_fault: None,
        }
    }

    /// The status-machine state.
    pub fn state(&self) -> State {
        self.state
    }

    /// Output frequency in Hz.
    pub fn frequency_hz(&self) -> f64 {
        self.frequency
    }

    /// The present error, if any.
    pub fn fault(&self) -> Option<FaultCode> {
        self.fault
    }

    /// Raises an error; the next cycle takes transition 13.
    pub fn inject_fault(&mut self, code: FaultCode) {
        self.pending_fault = Some(code);
    }

    fn enter(&mut self, state: State, now: Duration) {
        self.state = state;
        self.entered = now;
    }

    /// One bus cycle: control word and setpoints in, status word and actual values out.
    pub fn cycle(
        &mut self,
        control: u16,
        setpoints: &[u16],
        params: &dyn DriveParams,
        now: Duration,
    ) -> DriveOutput {
        let control = ControlWord(control);
        let dt = self
            .last
            .map_or(Duration::ZERO, |l| now.saturating_sub(l))
            .as_secs_f64();
        self.last = Some(now);
        let max_hz = f64::from(params.get(105, None).unwrap_or(500)) / 10.0;

        // Automatic transitions: 1 (charging relay), 13 (fault), 14 (end of fault reaction).
        if let Some(code) = self.pending_fault.take() {
            self.fault = Some(code);
            self.enter(State::ErrorReactionActive, now);
        }
        match self.state {
            State::NotReadyForSwitchOn if now >= CHARGING => self.enter(State::SwitchOnBlock, now),
            State::ErrorReactionActive if now.saturating_sub(self.entered) >= FAULT_REACTION => {
                self.enter(State::Fault, now)
            }
            _ => {}
        }
        // Commands chain within one telegram (047Fh from "Ready for switch-on" takes 3 then 4:
        // §6.1.3 answers it with xx37h); at most one pass per state.
        let mut previous = self.previous;
        for _ in 0..State::ALL.len() {
            let Some(t) = state_machine::next(self.state, control, previous) else {
                break;
            };
            if t.number == 15 {
                self.fault = None;
            }
            self.enter(t.to, now);
            previous = control;
        }
        if control.valid() {
            self.previous = control;
        }

        // Setpoint 1 per P546[-01] = 1 (setpoint frequency, §6.1.3), only with bit 10 and bit 6.
        if control.valid() {
            let raw = setpoints.first().copied().unwrap_or(0) as i16;
            let function = params.get(546, Some(1)).unwrap_or(1);
            self.target = if function == 1 && control.bit(6) {
                f64::from(raw) * max_hz / FULL_SCALE
            } else {
                0.0
            };
        }
        let goal = if self.state == State::OperationEnabled {
            self.target
        } else {
            0.0
        };
        let ramp_param = if goal.abs() > self.frequency.abs() {
            102
        } else {
            103
        };
        let ramp_s = f64::from(params.get(ramp_param, None).unwrap_or(200)) / 100.0;
        let step = if ramp_s <= 0.0 {
            f64::INFINITY
        } else {
            max_hz * dt / ramp_s
        };
        let diff = goal - self.frequency;
        let before = self.frequency;
        self.frequency = if diff.abs() <= step {
            goal
        } else {
            self.frequency + step * diff.signum()
        };
        self.position += (before + self.frequency) / 2.0 * dt;
        if self.state == State::EmergencyStopActive && self.frequency == 0.0 {
            // F: "the drive is stopped, the frequency inverter changes to Switch-on block".
            self.enter(State::SwitchOnBlock, now);
        }
        DriveOutput {
            status: self.status_word(control, goal),
            actuals: self.actuals(params, max_hz),
        }
    }

    fn status_word(&self, control: ControlWord, goal: f64) -> u16 {
        let (_, base) = self.state.status_pattern();
        let mut s = base;
        if !matches!(
            self.state,
            State::ReadyForSwitchOn
                | State::SwitchedOn
                | State::OperationEnabled
                | State::EmergencyStopActive
        ) {
            // Bits 4 and 5 are X in these states: they show the commands present (§6.1.2.2) in
            // the last control word the inverter evaluated (bit 10 set).
            s |= u16::from(self.previous.bit(1)) << 4 | u16::from(self.previous.bit(2)) << 5;
        }
        let reached = (self.frequency - goal).abs() < 1e-6;
        s |= u16::from(reached) << 8;
        s |= u16::from(control.valid()) << 9;
        s |= if control.left() { 1 << 12 } else { 1 << 11 };
        s |= u16::from(control.parameter_set() - 1) << 14;
        s
    }

    /// The position in increments (1000 per rotation), limited to ±50000.00 rotations.
    fn position_increments(&self) -> i32 {
        let limit = f64::from(proto::nord::scaling::POSITION_LIMIT);
        (self.position * 1000.0).round().clamp(-limit, limit) as i32
    }

    fn actuals(&self, params: &dyn DriveParams, max_hz: f64) -> Vec<u16> {
        (1..=5u8)
            .map(|i| match params.get(543, Some(i)).unwrap_or(0) {
                // 1 = actual frequency, as a percentage of P105 (§6.1.3).
                1 => (self.frequency * FULL_SCALE / max_hz)
                    .round()
                    .clamp(-32768.0, 32767.0) as i16 as u16,
                // 10 / 15 = actual position low / high word (BU 0620 §3.9 step 5, §6.1.2.4:
                // 1000 increments per rotation, 32 bits over two words).
                10 => proto::nord::scaling::position_words(self.position_increments()).0,
                15 => proto::nord::scaling::position_words(self.position_increments()).1,
                _ => 0,
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Defaults;
    impl DriveParams for Defaults {
        fn get(&self, number: u16, element: Option<u8>) -> Option<i32> {
            match (number, element) {
                (105, _) => Some(500),
                (102 | 103, _) => Some(200),
                (543 | 546, Some(1)) => Some(1),
                _ => None,
            }
        }
    }

    fn ms(n: u64) -> Duration {
        Duration::from_millis(n)
    }

    #[test]
    fn switching_example_of_bu0620_6_1_3() {
        let mut d = Drive::new();
        assert_eq!(d.cycle(0, &[], &Defaults, ms(0)).status & 0x7F, 0x00);
        assert_eq!(d.cycle(0, &[], &Defaults, ms(40)).status & 0xFF, 0x40);
        assert_eq!(d.cycle(0x047E, &[0], &Defaults, ms(44)).status & 0xFF, 0x31);
        // 047Fh with 2000h: operation enabled; after the 2 s ramp to 50 % the actual value is 2000h.
        let mut out = d.cycle(0x047F, &[0x2000], &Defaults, ms(48));
        assert_eq!(out.status & 0xFF, 0x37);
        for t in (52..=1200).step_by(4) {
            out = d.cycle(0x047F, &[0x2000], &Defaults, ms(t));
        }
        assert_eq!(out.actuals[0], 0x2000);
        assert_eq!(out.status & 0x100, 0x100, "setpoint reached");
        assert!((d.frequency_hz() - 25.0).abs() < 1e-9);
    }

    #[test]
    fn fault_and_acknowledge() {
        let mut d = Drive::new();
        d.cycle(0x047E, &[], &Defaults, ms(40));
        d.inject_fault("10.3".parse().unwrap());
        assert_eq!(d.cycle(0x047E, &[], &Defaults, ms(44)).status & 0x4F, 0x0F);
        assert_eq!(d.cycle(0x047E, &[], &Defaults, ms(80)).status & 0x4F, 0x08);
        assert_eq!(d.fault().map(FaultCode::p700), Some(103));
        d.cycle(0x0480, &[], &Defaults, ms(84));
        assert_eq!(d.state(), State::SwitchOnBlock);
        assert_eq!(d.fault(), None);
    }

    #[test]
    fn invalid_control_data_is_ignored() {
        let mut d = Drive::new();
        d.cycle(0x007E, &[], &Defaults, ms(40));
        assert_eq!(d.state(), State::SwitchOnBlock);
    }

    #[test]
    fn fault_codes_parse() {
        assert_eq!("E10.3".parse::<FaultCode>().map(|c| c.p700()), Ok(103));
        assert!("10".parse::<FaultCode>().is_err());
        assert!("x.1".parse::<FaultCode>().is_err());
    }
}
