//! The inverter and interface parameters that set the system bus up (P509, P510, the SK TU3
//! gateway's P512/P513, P154, P748) and the commissioning examples of the three manuals.

use serde::Serialize;

use super::super::product::Product;
use super::super::types::{Inverter, RangeError};
use super::{check_inverter, has_p153_p154, serves, CanError, InverterSeries};

/// P509 "Control word source" values for the system bus and the field bus.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum ControlSource {
    /// 3 = "System bus" (BU 2100/BU 2200 §7.2, §5.3 step 5, §8.1; BU 0590 §5.2.1 p. 38 names 3
    /// "CAN" on the SK 5xxE).
    SystemBus,
    /// 6 = "CANopen" (BU 0620 §4.5 p. 90, §5.1; BU 2100/BU 2200 §7.2: "SK 511E … and above").
    CanOpen,
    /// 8 = "Ethernet" (BU 0620 §4.5) / "Ethernet TU" (BU 2100/BU 2200 §7.2, BU 0590 §3.2.2).
    Ethernet,
}

impl ControlSource {
    /// The P509 value.
    pub fn value(self) -> i32 {
        match self {
            ControlSource::SystemBus => 3,
            ControlSource::CanOpen => 6,
            ControlSource::Ethernet => 8,
        }
    }

    /// The source of a P509 value, `None` for values not about these buses.
    pub fn from_value(v: i64) -> Option<Self> {
        [Self::SystemBus, Self::CanOpen, Self::Ethernet]
            .into_iter()
            .find(|s| i64::from(s.value()) == v)
    }
}

/// P510 [-01]/[-02] "Setpoint source" = 0 "Auto" "if P509 is set to 3, 6 or 8" (BU 2100 §7.2
/// p. 54, BU 2200 §7.2 p. 59; examples step 5).
pub const P510_AUTO: i32 = 0;

/// The P509 values the manuals give an inverter of `series` behind `product`. `host`: the
/// inverter that carries the interface (the SK 550P itself, the SK 5xxE an SK TU3 is mounted
/// on), which takes its control word from the field bus (8); the others take it over the system
/// bus: 6 (CANopen) from SK 511E and on SK 5x0P, 3 (system bus) on SK 1x0E/2xxE (BU 0620 §4.5
/// p. 90; BU 2100 §7.2 p. 54; BU 2200 §7.2 p. 59).
pub fn control_sources(
    product: Product,
    series: InverterSeries,
    host: bool,
) -> Result<&'static [ControlSource], CanError> {
    serves(product, series)?;
    let xu4 = has_p153_p154(product);
    Ok(match series {
        InverterSeries::Sk1x0e | InverterSeries::Sk2xxe => &[ControlSource::SystemBus],
        _ if host && !xu4 => &[ControlSource::Ethernet],
        _ => &[ControlSource::CanOpen],
    })
}

/// The gateway conditions of an SK TU3-EIP with more than one inverter (BU 2100 §4.3 p. 22):
/// P513 "600 ms" (tenths of a second: 6) and P512 USS address 0 on every inverter, CANopen
/// and the same baud rate on all, interface software V1.3 R0 or later.
pub const TU3_GATEWAY_P513: i32 = 6;
/// See [`TU3_GATEWAY_P513`].
pub const TU3_GATEWAY_P512: i32 = 0;

/// One parameter setting of a commissioning example.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Setting {
    /// P-number.
    pub param: u16,
    /// Array element, 1-based.
    pub element: Option<u8>,
    /// Value.
    pub value: i32,
    /// The meaning the example prints.
    pub meaning: &'static str,
}

const fn set(param: u16, element: Option<u8>, value: i32, meaning: &'static str) -> Setting {
    Setting {
        param,
        element,
        value,
        meaning,
    }
}

/// Step 5 of the modules' example, "on each frequency inverter" (BU 2100 §5.3 p. 29, BU 2200
/// §5.3 p. 27): 3 inverters in positioning operation with one speed and one position value.
pub const MODULE_EXAMPLE_STEP5: [Setting; 9] = [
    set(509, None, 3, "system bus"),
    set(510, Some(1), 0, "Auto"),
    set(510, Some(2), 0, "Auto"),
    set(543, Some(1), 1, "actual frequency"),
    set(543, Some(2), 10, "actual position inc. low word"),
    set(543, Some(3), 15, "actual position inc. high word"),
    set(546, Some(1), 1, "setpoint frequency"),
    set(546, Some(2), 23, "setpoint position inc. low word"),
    set(546, Some(3), 24, "setpoint position inc. high word"),
];

/// Step 7 of all three examples: P120 [-01] = 1 "Auto" or 2 "monitoring active immediately"
/// on each inverter (BU 0620 §3.9 p. 74, BU 2100 §5.3 p. 29, BU 2200 §5.3 p. 28).
pub const EXAMPLE_STEP7: [Setting; 2] = [
    set(120, Some(1), 1, "Auto"),
    set(120, Some(1), 2, "monitoring active immediately"),
];

/// Step 8 of all three examples (same pages): the information parameters show P740 [-01]
/// control word 047Eh and P741 [-01] status word 0B31h "Ready for switch-on"; P748 the system
/// bus status.
pub const EXAMPLE_STEP8: [Setting; 2] = [
    set(740, Some(1), 0x047E, "control word: ready for switch-on"),
    set(741, Some(1), 0x0B31, "status word: ready for switch-on"),
];

/// Step 5 of the example for FI `fi` behind `product`. The SK 550P's (BU 0620 §3.9 p. 74)
/// prints P509 6 "(CANopen)" for each inverter; FI 1, the SK 550P itself, takes 8 (Ethernet),
/// as §4.5 says (case bu0620/params-inverter-info/example-step-5-control-sources); its P546
/// [-02]/[-03] print "Setpoint Frequency incl. Low/HighWord" for 23/24, which the modules'
/// example names setpoint position (cases in bu0620/drive-scaling and drive-switching).
pub fn example_step5(product: Product, fi: Inverter) -> Result<Vec<Setting>, CanError> {
    check_inverter(product, fi)?;
    let mut steps = MODULE_EXAMPLE_STEP5.to_vec();
    if product == Product::Sk550p {
        steps[0] = if fi.get() == 1 {
            set(509, None, 8, "Ethernet")
        } else {
            set(509, None, 6, "CANopen")
        };
    }
    Ok(steps)
}

/// P154 "TB-IO access": which inverters use the interface's 2 inputs and 2 outputs, [-01]
/// inputs, [-02] outputs, factory 0, SK CU4/TU4 only (BU 2100 §7.1.1 p. 46, BU 2200 §7.1.1
/// p. 49).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum TbIoAccess {
    /// 0 "No access": no influence by the inverter.
    None,
    /// 1 "Broadcast (inputs)": all inverters read the inputs; in [-02] no function.
    Broadcast,
    /// 2…5: FI 1…4 reads and writes the inputs and outputs.
    Inverter(Inverter),
}

impl TbIoAccess {
    /// The setting of a P154 value (0…5).
    pub fn from_value(v: i64) -> Result<Self, RangeError> {
        match v {
            0 => Ok(Self::None),
            1 => Ok(Self::Broadcast),
            2..=5 => Ok(Self::Inverter(Inverter::new(v - 1)?)),
            _ => Err(RangeError {
                what: "P154",
                value: v,
                min: 0,
                max: 5,
            }),
        }
    }

    /// The P154 value.
    pub fn value(self) -> i32 {
        match self {
            Self::None => 0,
            Self::Broadcast => 1,
            Self::Inverter(fi) => i32::from(fi.get()) + 1,
        }
    }
}

/// The inverter parameters (number, element) that evaluate the interface's inputs 1/2: P480
/// "Funct. BusIO In Bits" [-11]/[-12]; and its outputs 1/2: P481 "Funct. BusIO Out Bits"
/// [-09]/[-10] (BU 2100 §7.1.1 p. 46, BU 2200 §7.1.1 p. 49).
pub const TB_IO_INPUTS: [(u16, u8); 2] = [(480, 11), (480, 12)];
/// See [`TB_IO_INPUTS`].
pub const TB_IO_OUTPUTS: [(u16, u8); 2] = [(481, 9), (481, 10)];

/// P746 "Module status" of an inverter behind an EtherNet/IP or POWERLINK module, as the
/// inverter shows the bus interface (BU 2100 §7.2 p. 55, BU 2200 §7.2 p. 60): bit 0 "Bus
/// interface initialised", bit 1 "Cyclic communication", bits 4…6 "Error 1…3" (the error
/// table, [`P746Error`]), bits 8…15 the bus interface ID ([`p746_interface_id`]); bits 2, 3
/// and 7 reserved.
pub const P746: u16 = 746;

/// The error field of P746, bits 6…4 ("Error 3 2 1"), as the error table prints it (BU 2100
/// §7.2 p. 55: all eight rows; BU 2200 §7.2 p. 60: the first four).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum P746Error {
    /// 000 "No error" / "Kein Fehler".
    None,
    /// 001 "No communication with ASIC" / "ASIC nicht erreichbar".
    NoAsic,
    /// 010 "Bus timeout" / "Bus-Timeout".
    BusTimeout,
    /// 011 "P513 timeout" / "P513 Timeout".
    P513Timeout,
}

impl P746Error {
    /// The three bits 6…4 as a number.
    pub fn code(self) -> u8 {
        match self {
            P746Error::None => 0,
            P746Error::NoAsic => 1,
            P746Error::BusTimeout => 2,
            P746Error::P513Timeout => 3,
        }
    }
}

/// The bus interface ID P746 bits 8…15 carry: EtherNet/IP "23" (BU 2100 §7.2 p. 55),
/// POWERLINK "24" (BU 2200 §7.2 p. 60). `None` where the manuals print none: BU 0590 (SK
/// TU3-PNT) gives only the example 0603h with high byte 06h "Profibus" (§5.2.2 p. 43), no
/// PROFINET ID; the SK 550P's P746 is the XU5 status array of BU 0620 §4.5.
pub fn p746_interface_id(product: Product) -> Option<u8> {
    match product {
        Product::Tu3Eip | Product::Tu4Eip | Product::Cu4Eip => Some(23),
        Product::Tu3Pol | Product::Tu4Pol | Product::Cu4Pol => Some(24),
        Product::Tu3Pnt | Product::Sk550p => None,
    }
}

/// P746 of an inverter behind `product` ([`P746`]); `None` where [`p746_interface_id`] is.
pub fn p746_status(
    product: Product,
    initialised: bool,
    cyclic: bool,
    error: P746Error,
) -> Option<i32> {
    let id = p746_interface_id(product)?;
    Some(
        i32::from(id) << 8
            | i32::from(error.code()) << 4
            | i32::from(cyclic) << 1
            | i32::from(initialised),
    )
}

/// P748 "CANopen status" of every inverter, [-01] "Displays the system bus status" (BU 0620
/// §4.5 p. 91, §3.9 step 8 p. 75; BU 2100 §7.2 p. 55 and §5.3 step 8 "System bus status";
/// BU 2200 §7.2 p. 60 "CANopen Zustand"). Its bits are not stated by the manuals (they refer
/// to BU 0600 / BU 0200). This project's choice, not stated by the manuals: [-01] is the
/// node's NMT state as its heartbeat codes it (CiA 301 §7.2.8.3.2.1: 0 boot-up, 4 stopped,
/// 5 operational, 127 pre-operational), [`p748_status`].
pub const P748: u16 = 748;

/// P748 [-01] of a node in `state` (the choice named at [`P748`]).
pub fn p748_status(state: crate::canopen::nmt::NmtState) -> i32 {
    i32::from(state.code().0)
}

#[cfg(test)]
mod tests {
    use super::super::OptionMonitoring;
    use super::*;

    fn fi(n: i64) -> Inverter {
        Inverter::new(n).unwrap()
    }

    #[test]
    fn p746_module_status() {
        // BU 2100 §7.2: EtherNet/IP = 23 in bits 8…15; BU 2200 §7.2: POWERLINK = 24.
        assert_eq!(
            p746_status(Product::Tu4Eip, true, true, P746Error::None),
            Some(0x1703)
        );
        assert_eq!(
            p746_status(Product::Cu4Pol, true, false, P746Error::P513Timeout),
            Some(0x1831)
        );
        assert_eq!(
            p746_status(Product::Tu3Eip, true, false, P746Error::BusTimeout),
            Some(0x1721)
        );
        assert_eq!(
            p746_status(Product::Tu3Pnt, true, true, P746Error::None),
            None
        );
    }

    #[test]
    fn control_sources_per_series() {
        use ControlSource::*;
        use InverterSeries::*;
        // BU 0620 §4.5: 8 on the SK 550P, 6 on further inverters.
        assert_eq!(
            control_sources(Product::Sk550p, Sk5x0p, true),
            Ok(&[Ethernet][..])
        );
        assert_eq!(
            control_sources(Product::Sk550p, Sk5x0p, false),
            Ok(&[CanOpen][..])
        );
        // BU 2100 / BU 2200 §7.2: 3 on SK 1x0E/2xxE, 8 on the SK TU3's own, 6 from SK 511E.
        assert_eq!(
            control_sources(Product::Tu4Eip, Sk2xxe, true),
            Ok(&[SystemBus][..])
        );
        assert_eq!(
            control_sources(Product::Tu4Pol, Sk54xe, true),
            Ok(&[CanOpen][..])
        );
        assert_eq!(
            control_sources(Product::Tu3Pol, Sk500To535e, true),
            Ok(&[Ethernet][..])
        );
        assert_eq!(
            control_sources(Product::Tu3Eip, Sk54xe, false),
            Ok(&[CanOpen][..])
        );
        assert!(control_sources(Product::Tu3Eip, Sk2xxe, false).is_err());
        assert_eq!(ControlSource::from_value(3), Some(SystemBus));
        assert_eq!(ControlSource::from_value(5), None);
    }

    #[test]
    fn commissioning_examples() {
        // BU 2100 §5.3 / BU 2200 §5.3 step 5.
        let m = example_step5(Product::Tu4Eip, fi(2)).unwrap();
        let values: Vec<_> = m.iter().map(|s| (s.param, s.element, s.value)).collect();
        assert_eq!(
            values,
            [
                (509, None, 3),
                (510, Some(1), 0),
                (510, Some(2), 0),
                (543, Some(1), 1),
                (543, Some(2), 10),
                (543, Some(3), 15),
                (546, Some(1), 1),
                (546, Some(2), 23),
                (546, Some(3), 24)
            ]
        );
        assert_eq!(m[0].value, ControlSource::SystemBus.value());
        assert!(m[1..3].iter().all(|s| s.value == P510_AUTO));
        // BU 0620 §3.9: 6 (CANopen) on FI 2/3, 8 on FI 1 (erratum), same P543/P546.
        let sk = |n| example_step5(Product::Sk550p, fi(n)).unwrap()[0].value;
        assert_eq!((sk(1), sk(2), sk(3)), (8, 6, 6));
        // Step 7: P120 [-01] 1 or 2.
        let p120: Vec<_> = EXAMPLE_STEP7
            .iter()
            .map(|s| OptionMonitoring::from_value(s.value.into()))
            .collect();
        assert_eq!(
            p120,
            [
                Some(OptionMonitoring::Auto),
                Some(OptionMonitoring::Immediate)
            ]
        );
        assert_eq!(
            (EXAMPLE_STEP8[0].value, EXAMPLE_STEP8[1].value),
            (0x047E, 0x0B31)
        );
    }

    #[test]
    fn tb_io_access() {
        assert_eq!(TbIoAccess::from_value(1), Ok(TbIoAccess::Broadcast));
        assert_eq!(TbIoAccess::from_value(5), Ok(TbIoAccess::Inverter(fi(4))));
        assert_eq!(TbIoAccess::from_value(2).map(TbIoAccess::value), Ok(2));
        assert!(TbIoAccess::from_value(6).is_err());
        assert_eq!(TB_IO_INPUTS, [(480, 11), (480, 12)]);
        assert_eq!(TB_IO_OUTPUTS, [(481, 9), (481, 10)]);
    }
}
