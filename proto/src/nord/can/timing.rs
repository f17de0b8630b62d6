//! The process-data update cycle and P153, the system bus's pause time.

use serde::Serialize;

use super::super::mutant::Constant;
use super::super::product::Product;
use super::super::types::{Inverter, RangeError};
use super::{check_inverter, CanError};

/// The shortest process-data cycle on the system bus, µs: "≥ 5 ms" (BU 0620 §2.5.1 p. 39
/// "Update interval ≥ 5 ms (exchange of process data with the frequency inverter)", §2.5.3
/// p. 44 "System bus … cycle time ≥ 5 ms"; P153 [-02] factory 5 ms).
pub static MIN_CYCLE_US: Constant<u32> = Constant::new(
    "can-min-cycle",
    5000,
    "shortest system bus process-data cycle, µs,",
    "BU 0620 §2.5.1 update interval",
)
.lower_bound();

/// The process-data update cycle over the system bus.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case", tag = "kind", content = "us")]
pub enum UpdateCycle {
    /// The manual's table gives the cycle (µs).
    Table(u32),
    /// Only the lower bound is stated (µs).
    AtLeast(u32),
}

/// The update cycle of `inverters` inverters behind `product`: the SK TU3-EIP's table (BU 2100
/// §4.3 p. 22, with its 6/5-inverter rows corrected, see the module errata); every other
/// product only "≥ 5 ms".
pub fn update_cycle(product: Product, inverters: u8) -> Result<UpdateCycle, CanError> {
    let fi = Inverter::new(i64::from(inverters))?;
    check_inverter(product, fi)?;
    Ok(match product {
        Product::Tu3Eip => UpdateCycle::Table(
            super::super::eip::tu3_update_cycle_us(inverters).unwrap_or(MIN_CYCLE_US.get()),
        ),
        _ => UpdateCycle::AtLeast(MIN_CYCLE_US.get()),
    })
}

/// One bit at the system bus's 250 kBaud (P514, BU 0620 §2.6), ns.
pub const BIT_TIME_NS: u32 = 1_000_000_000 / super::BAUD_RATE;

/// The bus time one process-data cycle of `inverters` inverters of `series` takes at the most,
/// µs: a SYNC, and for each inverter its RPDOs and TPDOs ([`super::pdo_words`]: 2 bytes a
/// word), each frame at its worst-case length with bit stuffing
/// ([`crate::can::frame::max_bits`]). The physical floor of the update cycle: a cycle shorter
/// than this cannot carry the process data, whatever the manuals allow.
pub fn cycle_bus_time_us(series: super::InverterSeries, inverters: u8) -> u32 {
    use crate::canopen::cob_id::Function;
    let per_inverter: u32 = (1..=4u8)
        .flat_map(|number| [Function::Rpdo { number }, Function::Tpdo { number }])
        .filter_map(|f| super::pdo_words(f, series))
        .map(|(_, words)| crate::can::frame::max_bits(2 * usize::from(words)))
        .sum();
    let bits = crate::can::frame::max_bits(0) + u32::from(inverters) * per_inverter;
    (u64::from(bits) * u64::from(BIT_TIME_NS)).div_ceil(1000) as u32
}

/// The period of a process-data cycle of `inverters` inverters of `series` behind `product`,
/// µs: the update cycle ([`update_cycle`]: the SK TU3-EIP's table, else "≥ 5 ms") unless
/// their frames need longer on the wire ([`cycle_bus_time_us`]), then that bus time rounded up
/// to the millisecond. Not stated by the manuals beyond the update cycle: a cycle shorter than
/// its frames cannot run on a real bus.
pub fn cycle_period_us(product: Product, series: super::InverterSeries, inverters: u8) -> u32 {
    let stated = match update_cycle(product, inverters) {
        Ok(UpdateCycle::Table(us) | UpdateCycle::AtLeast(us)) => us,
        Err(_) => MIN_CYCLE_US.get(),
    };
    stated.max(cycle_bus_time_us(series, inverters).div_ceil(1000) * 1000)
}

/// P153 "Min. system bus cycle", ms: range 0…250, [-01] "TxSDO Inhibit Time" {10}, [-02]
/// "TxPDO Inhibit Time" {5}; "the pause time for the system bus in order to reduce the bus
/// load"; SK CU4/TU4 only (BU 2100 §7.1.1 p. 46, BU 2200 §7.1.1 p. 49).
pub const P153_FACTORY_MS: [u16; 2] = [10, 5];
/// P153's largest value, ms.
pub const P153_MAX_MS: u16 = 250;

/// Whether the product has P153 and P154 (SK CU4/TU4 only).
pub fn has_p153_p154(product: Product) -> bool {
    matches!(
        product,
        Product::Tu4Eip | Product::Cu4Eip | Product::Tu4Pol | Product::Cu4Pol
    )
}

/// P153 [-02] as the CiA 301 PDO inhibit time (sub-index 3 of the PDO communication
/// parameter, in 100 µs): 5 ms → 50. The manual names the value "TxPDO Inhibit Time", the
/// CiA 301 term; the mapping onto 1800h sub 3 is this project's reading. [-01] "TxSDO Inhibit
/// Time" has no CiA 301 object (SDOs have no inhibit time): the simulator's gap between SDOs.
pub fn p153_inhibit_time(ms: i64) -> Result<u16, RangeError> {
    match u16::try_from(ms) {
        Ok(v) if v <= P153_MAX_MS => Ok(v * 10),
        _ => Err(RangeError {
            what: "P153",
            value: ms,
            min: 0,
            max: i64::from(P153_MAX_MS),
        }),
    }
}

#[cfg(test)]
mod tests {

    #[test]
    fn eight_inverters_do_not_fit_a_5_ms_cycle_at_250_kbaud() {
        use super::super::InverterSeries::*;
        // Three values (SK 500E…535E): one 8-byte PDO each way, 270 bits = 1.08 ms per
        // inverter, near BU 2100 §4.3's 1.25 ms per inverter of the SK TU3-EIP.
        assert_eq!(cycle_bus_time_us(Sk500To535e, 1), 220 + 1080);
        // Five values (SK 54xE, SK 5x0P): a second PDO of 4 bytes each way, 1.84 ms each;
        // eight of them need 14.94 ms, three times the 5 ms the manuals allow as the least.
        assert_eq!(cycle_bus_time_us(Sk5x0p, 8), 220 + 8 * 1840);
        assert!(cycle_bus_time_us(Sk5x0p, 8) > 2 * MIN_CYCLE_US.get());
        assert!(cycle_bus_time_us(Sk54xe, 2) < MIN_CYCLE_US.get());
    }

    use super::*;

    #[test]
    fn update_cycles() {
        // BU 2100 §4.3: 8 → 10 ms, 7 → 8.75 ms, 4…1 → 5 ms (6 and 5 corrected).
        let tu3: Vec<_> = (1..=8)
            .map(|n| update_cycle(Product::Tu3Eip, n).unwrap())
            .collect();
        let us = [5000, 5000, 5000, 5000, 6250, 7500, 8750, 10_000].map(UpdateCycle::Table);
        assert_eq!(tu3, us);
        // BU 0620 §2.5.1 / §2.5.3: ≥ 5 ms.
        assert_eq!(
            update_cycle(Product::Sk550p, 8),
            Ok(UpdateCycle::AtLeast(5000))
        );
        assert!(matches!(
            update_cycle(Product::Tu4Eip, 5),
            Err(CanError::NoSuchInverter { max: 4, .. })
        ));
        assert!(matches!(
            update_cycle(Product::Sk550p, 0),
            Err(CanError::Range(_))
        ));
        // P153 [-02] factory 5 ms = the 5 ms floor; as a CiA 301 inhibit time 50 × 100 µs.
        assert_eq!(u32::from(P153_FACTORY_MS[1]) * 1000, MIN_CYCLE_US.get());
        assert_eq!(p153_inhibit_time(5), Ok(50));
        assert_eq!(p153_inhibit_time(250), Ok(2500));
        assert!(p153_inhibit_time(251).is_err() && p153_inhibit_time(-1).is_err());
        assert!(has_p153_p154(Product::Cu4Pol) && !has_p153_p154(Product::Tu3Eip));
    }
}
