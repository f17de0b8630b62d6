//! What one step can do to a real device, judged from its bytes alone: make a motor turn, or
//! write the device's EEPROM. Each bus's steps report theirs with these functions; the case
//! as a whole, and what a run allows, is [`crate::effect`]'s.

use proto::nord::pkw::{OrderLabel, PkwRepr};
use proto::nord::Inverter;

/// What a step can do to a real device.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct Effect {
    /// Why it can make a motor turn, if it can (the first reason found).
    pub(crate) motion: Option<String>,
    /// Parameter writes the device may store in its EEPROM.
    pub(crate) eeprom_writes: u32,
}

impl Effect {
    /// Neither.
    pub(crate) const NONE: Effect = Effect {
        motion: None,
        eeprom_writes: 0,
    };

    /// Can make a motor turn, because `why`.
    pub(crate) fn motion(why: impl Into<String>) -> Effect {
        Effect {
            motion: Some(why.into()),
            eeprom_writes: 0,
        }
    }

    /// `n` EEPROM writes.
    pub(crate) fn eeprom(n: u32) -> Effect {
        Effect {
            motion: None,
            eeprom_writes: n,
        }
    }

    /// Both effects: the first motion reason, the writes added.
    pub(crate) fn and(self, other: Effect) -> Effect {
        Effect {
            motion: self.motion.or(other.motion),
            eeprom_writes: self.eeprom_writes.saturating_add(other.eeprom_writes),
        }
    }
}

/// Why a control word can make a motor turn, if it can (BU 0620 §6.1.2.1 p. 106, the same
/// table in BU 2100 §6.2.2 and BU 2200 §6.3.1):
///
/// - bits 0–3 all set: "Set the frequency inverter to standby", no "Disable voltage", no
///   "Emergency stop", and bit 3 "Enable operation": "Enable output voltage Acceleration of
///   the frequency inverter to the present setpoint" (047Fh, and 047Eh's neighbour 040Fh);
/// - bit 7 "Acknowledge the error" without "Disable voltage" (bit 1 = 0, priority 1, which
///   takes the drive to "Switch-on block" whatever else the word says): a drive whose enable
///   stays on — from this bus, or from the terminals — starts again once its fault is gone;
/// - bit 8 or 9, "Start function 480.11/480.12": what they do is parameter P480's choice
///   ("Parameter P480 in the frequency inverter manual"), which may be an enable.
///
/// Bit 10 "Control data valid" is not looked at: a word the manual says is ignored is no safe
/// word to send to firmware whose conformance is in question.
pub(crate) fn control_word(word: u16) -> Option<String> {
    const ENABLE: u16 = 0x000F;
    const DISABLE_VOLTAGE_OFF: u16 = 1 << 1;
    const ACKNOWLEDGE: u16 = 1 << 7;
    const BUS_BITS: u16 = 1 << 8 | 1 << 9;
    if word & ENABLE == ENABLE {
        Some(format!(
            "control word {word:04X}h enables operation (bits 0–3: \"Enable output voltage\", BU 0620 §6.1.2.1)"
        ))
    } else if word & ACKNOWLEDGE != 0 && word & DISABLE_VOLTAGE_OFF != 0 {
        Some(format!(
            "control word {word:04X}h acknowledges a fault (bit 7) without \"Disable voltage\": a drive whose enable stays on starts again"
        ))
    } else if word & BUS_BITS != 0 {
        Some(format!(
            "control word {word:04X}h sets bus bit 8 or 9, whose function P480 chooses (BU 0620 §6.1.2.1)"
        ))
    } else {
        None
    }
}

/// A `process` step's words: the control word as [`control_word`] says, and a setpoint other
/// than 0, which turns a motor whenever the drive is enabled — and it may be enabled from
/// elsewhere than this bus (P509 "Control word source" giving control to the terminals while
/// P510 "Setpoint source" takes the bus's setpoints, BU 0620 §4.5 p. 90).
pub(crate) fn process(control: u16, setpoints: &[u16]) -> Effect {
    if let Some(why) = control_word(control) {
        return Effect::motion(why);
    }
    match setpoints.iter().find(|s| **s != 0) {
        Some(s) => Effect::motion(format!(
            "setpoint {s:04X}h: a drive enabled from elsewhere (P509/P510) follows it"
        )),
        None => Effect::NONE,
    }
}

/// Output process data whose layout the step does not give (raw frames, assembly or process
/// object writes): data of zero bytes only carry no control bit and no setpoint; anything else
/// counts as able to make a motor turn, since any of its words may be a control word or a
/// setpoint.
pub(crate) fn output_data(what: &str, data: &[u8]) -> Effect {
    if data.iter().all(|b| *b == 0) {
        Effect::NONE
    } else {
        Effect::motion(format!(
            "{what} may carry output process data (bytes not all zero, any word of which may be a control word or a setpoint)"
        ))
    }
}

/// The frequency inverter parameters whose change can start a drive, with the manual's word.
const STARTING: &[(u16, &str)] = &[
    (
        420,
        "P420 digital inputs: an input given an enable function starts the drive when it is live (BU 0620 §5.2, BU 0590 §6.3)",
    ),
    (421, "P421 digital input function (BU 0590 §6.3: P420 … P425)"),
    (422, "P422 digital input function (BU 0590 §6.3: P420 … P425)"),
    (423, "P423 digital input function (BU 0590 §6.3: P420 … P425)"),
    (424, "P424 digital input function (BU 0590 §6.3: P420 … P425)"),
    (425, "P425 digital input function (BU 0590 §6.3: P420 … P425)"),
    (470, "P470 digital input function (BU 0590 §6.3: P470)"),
    (
        480,
        "P480 function of the bus I/O in bits, control bits 8 and 9 (BU 0620 §6.1.2.1)",
    ),
    (
        506,
        "P506 automatic error acknowledgement: a drive whose enable stays on starts again (BU 0620 §5.2)",
    ),
    (
        509,
        "P509 control word source: control goes to another source, e.g. terminals that hold the enable (BU 0620 §4.5)",
    ),
    (
        510,
        "P510 setpoint source: setpoints from another source drive an enabled motor (BU 0620 §4.5)",
    ),
];

/// Why writing frequency inverter parameter `number` can start a drive, if it can.
fn starting(number: u16) -> Option<&'static str> {
    STARTING.iter().find(|(n, _)| *n == number).map(|(_, w)| *w)
}

/// A parameter write (to an inverter, or to the interface: `None`): it may start the drive (a frequency inverter parameter of
/// [`STARTING`]), and it is an EEPROM write unless `ram_only` ("Change parameter value …
/// without writing to the EEPROM", order labels 11–14, BU 0620 §2.5.6 p. 51). Writes without
/// a parameter channel (CIP, CoE, POWERLINK SDO) have no such label, and the manuals name no
/// other way to keep them out of the EEPROM than P560 "Save in EEPROM" on the device, which
/// the harness cannot see: they count.
pub(crate) fn parameter_write(inverter: Option<Inverter>, number: u16, ram_only: bool) -> Effect {
    let motion = inverter.and_then(|_| starting(number)).map(str::to_string);
    Effect {
        motion,
        eeprom_writes: u32::from(!ram_only),
    }
}

/// A raw PKW order (8 bytes: PKE, IND, PWE; BU 0620 §2.5.6): a change order is a parameter
/// write, to EEPROM unless its label is 11–14. The PNU may carry the +1000 offset or not
/// (BU 0620 §2.5.6.2, BU 0590 §4.2.4.4): both readings are checked.
pub(crate) fn pkw(bytes: &[u8]) -> Effect {
    // The label and the PNU are in the first two bytes: a short order is still one.
    let mut padded = [0u8; 8];
    for (p, b) in padded.iter_mut().zip(bytes) {
        *p = *b;
    }
    let Ok(order) = PkwRepr::parse(&padded) else {
        return Effect::NONE;
    };
    let label = OrderLabel(order.ak);
    if !label.is_change() {
        return Effect::NONE;
    }
    let motion = [order.pnu, order.parameter()]
        .into_iter()
        .find_map(starting)
        .map(str::to_string);
    Effect {
        motion,
        eeprom_writes: u32::from(!label.is_ram_only()),
    }
}

/// An SDO download (EtherCAT CoE, POWERLINK) to `index`: the NORD parameter objects from 2000h
/// on (2000h + 600h·(FI−1) + P on an SK 550P, 2000h + 800h·n + P on a module, BU 0620
/// §2.2.7, BU 2200) are parameter writes (EEPROM, and a start where the parameter is one);
/// "Store parameters" (1010h) and "Restore default parameters" (1011h) write the EEPROM; the
/// process-data objects (POWERLINK 5000h–5003h, EtherCAT outputs 7000h on) are output data.
/// Without the product the parameter is read both ways.
pub(crate) fn sdo_download(index: u16, data: &[u8]) -> Effect {
    match index {
        0x1010 | 0x1011 => Effect::eeprom(1),
        0x2000.. => {
            let offset = index - 0x2000;
            let motion = [offset % 0x600, offset % 0x800]
                .into_iter()
                .find_map(starting)
                .map(|w| format!("SDO download {index:04X}h may be {w}"));
            let param = Effect {
                motion,
                eeprom_writes: u32::from(index < 0x6800),
            };
            if index >= 0x5000 {
                param.and(output_data(&format!("SDO download {index:04X}h"), data))
            } else {
                param
            }
        }
        _ => Effect::NONE,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rstest::rstest;

    #[rstest]
    // BU 0620 §6.1.2.1: "047Fh … Operation enabled … controlled with a 50 % setpoint".
    #[case(0x047F, true)]
    // Bits 0–3 enable the output voltage whatever bits 4–6 and 10 say.
    #[case(0x000F, true)]
    #[case(0x447F, true)]
    // "the first control command 047Eh" → "Ready for switch-on": no output voltage.
    #[case(0x047E, false)]
    // Bit 1 = 0 "Disable voltage"; bit 2 = 0 "Emergency stop"; bit 3 = 0 "Block voltage".
    #[case(0x047D, false)]
    #[case(0x047B, false)]
    #[case(0x0477, false)]
    #[case(0x0000, false)]
    // The cleanup's words (binding::settle): "disable voltage", and with the acknowledgement.
    #[case(0x0400, false)]
    #[case(0x0480, false)]
    // An acknowledgement without "disable voltage" restarts a drive whose enable stays on.
    #[case(0x04FE, true)]
    #[case(0x0482, true)]
    // Bits 8 and 9: "Start function 480.11/480.12", P480 decides.
    #[case(0x057E, true)]
    #[case(0x067E, true)]
    fn control_words_that_can_turn_a_motor(#[case] word: u16, #[case] motion: bool) {
        assert_eq!(control_word(word).is_some(), motion, "{word:04X}h");
    }

    #[test]
    fn a_setpoint_counts_even_with_a_word_that_does_not_enable() {
        assert_eq!(process(0x047E, &[0, 0]), Effect::NONE);
        let e = process(0x047E, &[0x2000]);
        assert!(e.motion.unwrap().contains("setpoint 2000h"));
        let e = process(0x047F, &[]);
        assert!(e.motion.unwrap().contains("enables operation"));
    }

    #[test]
    fn parameter_writes_that_start_a_drive_are_inverter_parameters_of_the_manuals() {
        let fi = Some(Inverter::new(1).unwrap());
        for n in [420, 425, 470, 480, 506, 509, 510] {
            assert!(parameter_write(fi, n, false).motion.is_some(), "P{n}");
            // An interface parameter of the same number is not the inverter's.
            assert_eq!(parameter_write(None, n, true), Effect::NONE);
        }
        assert_eq!(parameter_write(fi, 102, false), Effect::eeprom(1));
        assert_eq!(parameter_write(fi, 102, true), Effect::NONE);
    }

    #[rstest]
    // BU 0590 §4.2.4.4: `70 66 …` orders P102 (AK 7 "change array word"): an EEPROM write.
    #[case([0x70, 0x66, 0, 0, 0, 0, 0x03, 0xE8], None, 1)]
    // AK 14 "Change parameter value (word) without writing to the EEPROM" (BU 0620 §2.5.6).
    #[case([0xE0, 0x66, 0, 0, 0, 0, 0x03, 0xE8], None, 0)]
    // AK 1 "Order parameter value": a read.
    #[case([0x10, 0x66, 0, 0, 0, 0, 0, 0], None, 0)]
    // AK 2 to PNU 509 + 1000 = 5E5h: P509 control word source.
    #[case([0x25, 0xE5, 0, 0, 0, 0, 0, 0x03], Some("P509"), 1)]
    // AK 14 to PNU 506 without the offset: RAM only, but still a start.
    #[case([0xE1, 0xFA, 0, 0, 0, 0, 0, 0x01], Some("P506"), 0)]
    fn raw_pkw_orders(#[case] bytes: [u8; 8], #[case] starts: Option<&str>, #[case] eeprom: u32) {
        let e = pkw(&bytes);
        assert_eq!(e.eeprom_writes, eeprom);
        match starts {
            Some(p) => assert!(e.motion.as_deref().unwrap().starts_with(p), "{e:?}"),
            None => assert_eq!(e.motion, None),
        }
    }

    #[test]
    fn sdo_downloads() {
        // P102 of FI 1 on an SK 550P (2000h + 102 = 2066h): an EEPROM write, no start.
        assert_eq!(sdo_download(0x2066, &[0xE8, 0x03]), Effect::eeprom(1));
        // P509 of FI 1 on a module (2000h + 800h + 509).
        let e = sdo_download(0x2800 + 509, &[8, 0]);
        assert!(e.motion.unwrap().contains("P509"));
        // Store parameters; a communication object.
        assert_eq!(sdo_download(0x1010, b"save"), Effect::eeprom(1));
        assert_eq!(sdo_download(0x1C12, &[1]), Effect::NONE);
        // FI 1's outputs (7000h): zero is no command, 047Eh may be a setpoint.
        assert_eq!(sdo_download(0x7000, &[0, 0]), Effect::NONE);
        assert!(sdo_download(0x7000, &[0x7E, 0x04]).motion.is_some());
    }
}
