//! Process data (BU 0620 §2.2.6): SM2 carries each inverter's control word and setpoints 1..5,
//! SM3 its status word and actual values 1..5, 12 bytes per inverter in FI order (RxPDO
//! 1600h + FI−1, TxPDO 1A00h + FI−1, `proto::nord::ecat`), little-endian words as CoE maps them.
//!
//! States (BU 0620 §5.5.2.1, ETG.1000.6 §6.4.1): in Safe Operational the inputs are produced
//! ("no restrictions to actual values") and the setpoints are not evaluated — the inverters see
//! no valid control word (bit 10 clear), so they keep their state; in Operational every
//! completed output buffer drives the inverters and refreshes the inputs.
//!
//! The SM watchdog (ESC registers 0400h/0420h, default 100 ms) runs in Operational from the
//! state's entry and from every completed output buffer. When it expires the slave falls back
//! to Safe Operational with AL status code 001Bh (ERR LED double flash, "Application Watchdog
//! Timeout"), P872 bit 2 "Field bus timeout" is set, and each inverter whose monitoring is on
//! (P513 [-04] > 0, BU 0620 §4.5/§5.1) raises E10.2 "Telegram timeout for field bus interface
//! (Time-out through PLC)" (§5.3, DS402 7591h) — the rule of the EtherNet/IP adapter's
//! connection timeout. Without process data the device's own P513 monitoring raises E10.3.

use std::time::Duration;

use proto::nord::ecat::{self as def, WORDS_PER_INVERTER};
use proto::nord::Inverter;

use crate::device::Device;
use crate::drive::FaultCode;

/// E10.2: telegram time-out through the PLC (BU 0620 §5.3, 7591h).
pub(crate) const E10_2: FaultCode = FaultCode { group: 10, sub: 2 };

const WORDS: usize = WORDS_PER_INVERTER as usize;

/// The words last exchanged per FI 1..8 (objects 7000h/6000h + 10h per FI show them).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct ProcessWords {
    /// Control word and setpoints 1..5 as received.
    pub(crate) outputs: [[u16; WORDS]; 8],
    /// Status word and actual values 1..5 as produced.
    pub(crate) inputs: [[u16; WORDS]; 8],
}

impl ProcessWords {
    /// The input image (SM3 buffer) of `inverters` inverters.
    pub(crate) fn input_image(&self, inverters: u8) -> Vec<u8> {
        let n = usize::from(inverters.clamp(1, def::MAX_INVERTERS));
        self.inputs[..n]
            .iter()
            .flatten()
            .flat_map(|w| w.to_le_bytes())
            .collect()
    }
}

fn inverters(n: u8) -> impl Iterator<Item = (usize, Inverter)> {
    (1..=n.clamp(1, def::MAX_INVERTERS))
        .filter_map(|i| Inverter::new(i64::from(i)).ok())
        .map(|fi| (usize::from(fi.get()) - 1, fi))
}

/// One process data cycle at `now`: `outputs` (the SM2 image) drives the inverters when
/// `evaluate` (Operational), otherwise they get an invalid control word; the inputs are
/// refreshed. Also shows the words in P873/P874 (BU 0620 §4.3: 6 elements per FI; the modules' P176/P177, BU 2200 §7.1.3).
pub(crate) fn cycle(
    device: &mut Device,
    words: &mut ProcessWords,
    outputs: Option<&[u8]>,
    evaluate: bool,
    now: Duration,
) {
    let count = device.config().inverters;
    device.tick(now);
    for (i, fi) in inverters(count) {
        if let Some(data) = outputs {
            for (w, chunk) in data
                .get(i * 12..(i + 1) * 12)
                .unwrap_or_default()
                .chunks_exact(2)
                .enumerate()
            {
                words.outputs[i][w] = u16::from_le_bytes([chunk[0], chunk[1]]);
            }
        }
        let (control, setpoints) = if evaluate {
            (words.outputs[i][0], &words.outputs[i][1..])
        } else {
            (0, &[][..])
        };
        if let Ok(answer) = device.process_monitored(fi, control, setpoints, now) {
            words.inputs[i] = [0; WORDS];
            for (d, s) in words.inputs[i].iter_mut().zip(answer) {
                *d = s;
            }
        }
        show(device, i, words);
    }
}

/// The words of FI `i + 1` in the interface's display parameters (P873/P874 on the SK 550P,
/// P176/P177 on the POWERLINK modules: [`Device::show_process_data`]).
fn show(device: &mut Device, i: usize, words: &ProcessWords) {
    if let Ok(fi) = Inverter::new(i as i64 + 1) {
        device.show_process_data(fi, None, &words.outputs[i], &words.inputs[i]);
    }
}

/// The SM watchdog expired in Operational (the POWERLINK node: the SoC lost): P872/P173 bit 2,
/// and E10.2 on every inverter whose monitoring (P513 [-04]) is on — none where the module's
/// P151 switches all monitoring off (SK TU4/CU4-POL: P151 = 0 "Überwachung Aus", BU 2200
/// §7.1.1; "the inverter itself does not monitor the field bus", §8.1).
pub(crate) fn watchdog_expired(device: &mut Device) {
    device.set_fieldbus_timeout(true);
    if device.fieldbus_monitoring_off() {
        return;
    }
    for (_, fi) in inverters(device.config().inverters) {
        if device.ethernet_timeout(fi).is_some() {
            let _ = device.raise(fi, E10_2);
        }
    }
}
