//! CoE emergencies a case did not ask for. ETG.1000.6 lets a slave send an emergency at any
//! time, and the master sets each aside while it waits for its own answer (`master::mailbox`):
//! never mistaken for an SDO response. After each step the binding has them judged against
//! the inverter they name ([`crate::binding::emergency`]): one for an error the inverter does
//! not have fails the step.
//!
//! Any maker's slave (profile `any@ecat`) has no P700 to ask: its emergencies stay in the
//! transcript ("set aside: …") and are not judged.

use proto::ecat::coe::Emergency;
use proto::nord::{addr, Product};

use super::master::{Master, MasterError, Segment};

use crate::binding::emergency::AT_MOST;

/// Checks the emergencies `master` set aside from `from` on (those before were checked after
/// an earlier step) against `station`'s P700/P701. `Ok(Err(text))` names the first that
/// reports an error the inverter does not have; `Ok(Ok(n))`: the emergencies set aside now,
/// all checked. A read that fails is the master's error.
pub(crate) fn check<S: Segment>(
    master: &mut Master<S>,
    station: u16,
    product: Product,
    from: usize,
) -> Result<Result<usize, String>, MasterError> {
    let mut next = from;
    while next < master.pending_emergencies().len() && next < from + AT_MOST {
        let e = master.pending_emergencies()[next];
        next += 1;
        if let Some(spurious) = judge(master, station, product, &e)? {
            return Ok(Err(spurious));
        }
    }
    Ok(Ok(next))
}

/// What is wrong with `e`, if anything ([`crate::binding::emergency::judge`], the inverter
/// read over CoE).
fn judge<S: Segment>(
    master: &mut Master<S>,
    station: u16,
    product: Product,
    e: &Emergency,
) -> Result<Option<String>, MasterError> {
    crate::binding::emergency::judge(e, "CoE emergency", |at| {
        let Ok(object) = addr::coe(product, at) else {
            return Ok(None);
        };
        match master.sdo_upload(station, object.index, object.subindex, false) {
            Ok(d) => Ok(Some(d)),
            Err(e) if e.refusal().is_some() => Ok(None),
            Err(e) => Err(e),
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ecat::master::{EmbeddedSegment, Faulty, MasterConfig};
    use proto::nord::nmt::EcState;
    use proto::nord::Inverter;
    use sim::device::{Device, DeviceConfig};
    use sim::ecat::Slave;

    const STATION: u16 = 0x1001;

    /// A master with the simulated SK 550P in Pre-Operational.
    fn master() -> Master<Faulty<EmbeddedSegment>> {
        let device = Device::new(DeviceConfig::new(Product::Sk550p));
        let segment = Faulty::new(EmbeddedSegment::new(Slave::new(device).unwrap()));
        let mut m = Master::new(segment, MasterConfig::default());
        m.bring_up(EcState::PreOperational).unwrap();
        m
    }

    fn slave(m: &mut Master<Faulty<EmbeddedSegment>>) -> &mut Slave {
        m.segment_mut().inner_mut().slave_mut()
    }

    /// P102 of FI 1 (2066h:01h), a read that meets what waits in the send mailbox.
    fn read_p102(m: &mut Master<Faulty<EmbeddedSegment>>) {
        assert_eq!(m.sdo_upload(STATION, 0x2066, 1, false).unwrap(), [200, 0]);
    }

    #[test]
    fn an_emergency_for_an_error_the_inverter_does_not_have_is_named() {
        let mut m = master();
        slave(&mut m).raise_spurious_emergency().unwrap();
        read_p102(&mut m);
        assert_eq!(
            m.pending_emergencies().len(),
            1,
            "set aside, not the answer"
        );
        let said = check(&mut m, STATION, Product::Sk550p, 0)
            .unwrap()
            .unwrap_err();
        assert_eq!(
            said,
            "CoE emergency 7591h (error register 11h) reports error 102 (P700) on FI 1, but \
             P700 [-01] reads 0 and P701 (the last 5 errors) does not hold it: the device \
             reported an error the inverter does not have (BU 0620 §5.3)"
        );
    }

    #[test]
    fn an_emergency_for_a_real_error_passes_and_is_checked_once() {
        let mut m = master();
        let fi1 = Inverter::new(1).unwrap();
        slave(&mut m)
            .device_mut()
            .inject_fault(fi1, "10.2")
            .unwrap();
        read_p102(&mut m);
        assert_eq!(m.pending_emergencies().len(), 1);
        assert_eq!(check(&mut m, STATION, Product::Sk550p, 0).unwrap(), Ok(1));
        // Gone from P700 (as once acknowledged), but P701 [-01] remembers it.
        let unit = sim::link::Unit::Inverter(fi1);
        slave(&mut m)
            .device_mut()
            .store(unit)
            .unwrap()
            .set_info(700, 1, 0);
        assert_eq!(m.sdo_upload(STATION, 0x22BC, 1, false).unwrap(), [0, 0]);
        assert_eq!(check(&mut m, STATION, Product::Sk550p, 0).unwrap(), Ok(1));
        // From 1 on there is nothing to check: no read goes out.
        m.take_exchanges();
        assert_eq!(check(&mut m, STATION, Product::Sk550p, 1).unwrap(), Ok(1));
        assert!(m.take_exchanges().is_empty());
    }

    #[test]
    fn an_error_reset_and_an_emergency_of_no_inverter_are_told_apart() {
        let mut m = master();
        let reset = Emergency::default();
        assert_eq!(
            judge(&mut m, STATION, Product::Sk550p, &reset).unwrap(),
            None
        );
        let nobody = Emergency {
            code: 0x7591,
            register: 0x11,
            data: [102, 0, 0, 0, 0],
        };
        let said = judge(&mut m, STATION, Product::Sk550p, &nobody).unwrap();
        assert_eq!(
            said.as_deref(),
            Some(
                "CoE emergency 7591h (error register 11h) reports error 102 (P700) on FI 0, an \
                 inverter there is none of"
            )
        );
    }
}
