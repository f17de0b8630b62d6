//! What `harness serve epl --misbehave` can do on POWERLINK ([`crate::net::misbehave`]): no
//! session to close (raw Ethernet frames and SDO over UDP without connections), and the PRes
//! NMT status to send wrong (`corrupt=state`): every PRes says STOPPED (or PRE_OPERATIONAL_1
//! when the node is stopped), a state the node is not in, parsed and emitted anew with
//! [`proto::epl::EplRepr`]. Its spurious emergencies (`alarm=`) are the node's own
//! (`sim::epl::Node::raise_spurious`: an error entry and EN toggled, fetched by the MN).

use proto::epl::frame::Body;
use proto::epl::{EplRepr, NmtState};
use sim::endpoint::Output;

use crate::net::inject::rewrite_payload;
use crate::net::misbehave::{BusFaults, Field};

/// What POWERLINK can do of a spec.
pub(crate) const FAULTS: BusFaults = BusFaults {
    bus: "POWERLINK",
    fields: &[Field::State],
    no_close: Some(
        "has no session to close (raw Ethernet frames, SDO over UDP): use silent= or drop=",
    ),
    no_alarm: None,
};

/// Sets `field` wrong in `out` if it is a PRes; what it changed.
pub(crate) fn corrupt(field: Field, out: &mut Output) -> Option<String> {
    if field != Field::State {
        return None;
    }
    rewrite_payload(out, |payload| {
        let mut repr = EplRepr::parse_bytes(payload).ok()?;
        let Body::Pres(pres) = &mut repr.body else {
            return None;
        };
        let was = pres.state;
        pres.state = if was == NmtState::STOPPED {
            NmtState::PRE_OPERATIONAL_1
        } else {
            NmtState::STOPPED
        };
        let what = format!("PRes NMT status {was} → {}", pres.state);
        Some((repr.emit().ok()?, what))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proto::epl::frame::{Asnd, Pres};
    use proto::epl::ServiceId;
    use proto::eth::{EthernetRepr, MacAddr, ETHERTYPE_POWERLINK};

    /// An Ethernet frame (padded to 60) carrying `body` from node 1 to all (C_ADR_BROADCAST).
    fn frame(body: Body) -> Output {
        let epl = EplRepr {
            dst: 0xFF,
            src: 1,
            body,
        };
        Output::Frame(
            EthernetRepr {
                dst: MacAddr([0x01, 0x11, 0x1E, 0, 0, 0x02]),
                src: MacAddr([0xF0, 0x5F, 0x5A, 0, 0, 1]),
                ethertype: ETHERTYPE_POWERLINK,
            }
            .emit(&epl.emit().unwrap()),
        )
    }

    fn parsed(out: &Output) -> EplRepr {
        let Output::Frame(b) = out else { panic!() };
        EplRepr::parse_bytes(&b[14..]).unwrap()
    }

    #[test]
    fn a_pres_says_a_state_the_node_is_not_in_and_keeps_its_data() {
        let pres = Pres {
            state: NmtState::OPERATIONAL,
            rd: true,
            pdo_version: 0x20,
            payload: vec![1, 2, 3, 4],
            ..Pres::default()
        };
        let mut out = frame(Body::Pres(pres.clone()));
        assert_eq!(
            corrupt(Field::State, &mut out).as_deref(),
            Some("PRes NMT status OPERATIONAL → STOPPED")
        );
        let want = Pres {
            state: NmtState::STOPPED,
            ..pres
        };
        assert_eq!(parsed(&out).body, Body::Pres(want));
    }

    #[test]
    fn other_frames_and_fields_are_left_alone() {
        let asnd = Body::Asnd(Asnd {
            service: ServiceId::SDO,
            payload: vec![0; 8],
        });
        let mut out = frame(asnd.clone());
        assert_eq!(corrupt(Field::State, &mut out), None);
        assert_eq!(out, frame(asnd));
        let mut out = frame(Body::Pres(Pres::default()));
        assert_eq!(corrupt(Field::Wkc, &mut out), None);
    }
}
