//! Process data: the switching example of BU 0620 §6.1.3 over SM2/SM3 and the FMMUs, the
//! states that evaluate it, the SM watchdog.

use super::*;
use crate::link::Unit;
use proto::nord::{ArrayElement, Inverter, ParamNumber};

/// One LRW cycle: outputs for each inverter (control word, setpoint 1) at logical 0, inputs
/// read at logical 100h; returns the inputs and the working counters (LRW, LRD).
fn cycle(m: &mut Master, outputs: &[(u16, u16)]) -> (Vec<[u16; 6]>, u16) {
    let mut data = Vec::new();
    for (control, setpoint) in outputs {
        data.extend(control.to_le_bytes());
        data.extend(setpoint.to_le_bytes());
        data.extend([0; 8]);
    }
    let len = data.len();
    let backs = m.send(&[
        dg(12, 0x0000, 0x0000, &data),
        dg(10, 0x0100, 0x0000, &vec![0; len]),
    ]);
    let inputs = backs[1]
        .data
        .chunks_exact(12)
        .map(|c| std::array::from_fn(|w| u16::from_le_bytes([c[2 * w], c[2 * w + 1]])))
        .collect();
    (inputs, backs[0].wkc)
}

fn p700(m: &mut Master, fi: i64) -> i32 {
    let store = m
        .slave
        .device_mut()
        .store(Unit::Inverter(Inverter::new(fi).unwrap()))
        .unwrap();
    store
        .read(
            ParamNumber::new(700).unwrap(),
            None,
            ArrayElement::new(1).ok(),
        )
        .unwrap()
}

#[test]
fn the_switching_example_over_pdos() {
    let mut m = Master::new(2);
    m.go_op(2);
    // LRW writes the outputs (FMMU0, +2) and reads nothing there (+0): WKC 2.
    let (_, wkc) = cycle(&mut m, &[(0x047E, 0), (0x047E, 0)]);
    assert_eq!(wkc, 2);
    // §6.1.3: 047Eh → xx31h "Ready for switch-on" (the inputs follow one cycle later).
    let (inputs, _) = cycle(&mut m, &[(0x047E, 0), (0x0000, 0)]);
    assert_eq!(inputs[0][0] & 0xFF, 0x31);
    // 047Fh with setpoint 2000h (50 %) → xx37h "Operation enabled", ramping to 2000h.
    for _ in 0..3 {
        cycle(&mut m, &[(0x047F, 0x2000), (0x0000, 0)]);
    }
    let (inputs, _) = cycle(&mut m, &[(0x047F, 0x2000), (0x0000, 0)]);
    assert_eq!(inputs[0][0] & 0xFF, 0x37);
    assert_eq!(inputs[1][0] & 0x0200, 0, "FI 2 got no valid control word");
    for _ in 0..1100 {
        cycle(&mut m, &[(0x047F, 0x2000), (0x0000, 0)]);
    }
    let (inputs, _) = cycle(&mut m, &[(0x047F, 0x2000), (0x0000, 0)]);
    assert_eq!(inputs[0][1], 0x2000, "actual value 1: the setpoint reached");
    // The objects and P873/P874 show the words.
    assert_eq!(m.upload(0x7000, 1), Ok(vec![0x7F, 0x04]));
    assert_eq!(m.upload(0x6000, 2), Ok(vec![0x00, 0x20]));
    assert_eq!(m.upload(0x2000 + 873, 1), Ok(vec![0x7F, 0x04]));
}

#[test]
fn safe_op_produces_inputs_and_ignores_outputs() {
    let mut m = Master::new(1);
    m.preop();
    m.pd_sms(1);
    assert_eq!(m.request(0x04), (0x04, 0));
    let (inputs, wkc) = cycle(&mut m, &[(0x047E, 0)]);
    assert_eq!(wkc, 2, "the ESC takes the outputs");
    assert_eq!(
        inputs[0][0] & 0x4F,
        0x40,
        "switch-on block: 047Eh not evaluated"
    );
    assert_eq!(inputs[0][0] & 0x0200, 0);
}

#[test]
fn the_sm_watchdog_raises_e10_2_when_p513_monitors() {
    let mut m = Master::new(1);
    m.preop();
    // P513 [-04] of FI 1 (2000h + 513 = 2201h, sub-index 4) = 0.5 s.
    assert_eq!(m.download(0x2201, 4, &[5, 0]), Ok(()));
    m.pd_sms(1);
    m.request(0x04);
    m.request(0x08);
    cycle(&mut m, &[(0x047E, 0)]);
    let t = m.now;
    // Outputs stop: the watchdog (100 ms) expires.
    assert!(m.slave.poll(t + ms(90)).is_some());
    assert_eq!(m.slave.al_state(), EcState::Operational);
    m.slave.poll(t + ms(101));
    assert_eq!(
        (m.slave.al_status(), m.slave.al_status_code()),
        (0x14, 0x001B)
    );
    assert_eq!(p700(&mut m, 1), 102, "E10.2");
    // P872 bit 2 "Field bus timeout"; the watchdog status register shows it expired.
    m.now = t + ms(102);
    // The emergency comes first: 7591h "Time-out through PLC", P700 = 102.
    let emcy = m.mbx_read().expect("an emergency");
    assert_eq!(emcy[6..12], [0x00, 0x10, 0x91, 0x75, 0x11, 102]);
    assert_eq!(m.upload(0x2000 + 872, 0).unwrap()[0] & 0x04, 0x04);
    assert_eq!(m.u16_at(0x0440) & 1, 0);
    assert_eq!(m.slave.err_led().pattern, Pattern::DoubleFlashRed);
    // Back to Op after acknowledging: the indication clears.
    assert_eq!(m.request(0x18), (0x08, 0));
}

#[test]
fn without_p513_the_watchdog_raises_no_inverter_error() {
    let mut m = Master::new(1);
    m.go_op(1);
    cycle(&mut m, &[(0x047E, 0)]);
    let t = m.now;
    m.slave.poll(t + ms(200));
    assert_eq!(m.slave.al_status_code(), 0x001B);
    assert_eq!(
        p700(&mut m, 1),
        0,
        "P513 [-04] off: the inverter keeps its state"
    );
}
