//! The NMT state the MN expects its node's PRes to carry, sans IO: each PRes carries the CN's
//! NMT state (EPSG DS 301 §4.6.1.1.4, PRes field NMTStatus), and a CN changes it in the
//! isochronous phase only on the MN's NMT state commands (§7.1.4, NMT_CS state machine) or,
//! on an error of its own, down to PRE_OPERATIONAL_1, from where the next SoC takes it to
//! PRE_OPERATIONAL_2. A PRes that says another state than the one the node reported in its
//! StatusResponse or was commanded into names a node that misreports its state.

use proto::epl::NmtState;

/// What the MN expects a PRes to say.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) struct StateWatch {
    /// The state the node reported or was last brought into (`None`: unknown, nothing
    /// checked).
    state: Option<NmtState>,
    /// While a command is under way, the state it leads to.
    next: Option<NmtState>,
}

/// A PRes whose NMT state is none the MN expects.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Unexpected {
    /// What the PRes said.
    pub(crate) said: NmtState,
    /// What the MN expected.
    pub(crate) expected: NmtState,
}

/// A state as DS 301 names a CN's (`NMT_CS_OPERATIONAL (FDh)`), or its code.
pub(crate) fn cs(s: NmtState) -> String {
    match s.name() {
        Some(n) => format!("NMT_CS_{n} ({:02X}h)", s.0),
        None => format!("{:02X}h", s.0),
    }
}

impl StateWatch {
    /// The node reported `s` (its StatusResponse or IdentResponse): expected from now on.
    pub(crate) fn reported(&mut self, s: NmtState) {
        *self = StateWatch {
            state: Some(s),
            next: None,
        };
    }

    /// The MN commands the node from `from` (if known) to `to` (if the command leads to one
    /// state): either may show until the node reports again.
    pub(crate) fn commanded(&mut self, from: Option<NmtState>, to: Option<NmtState>) {
        *self = StateWatch {
            state: from.or(self.state),
            next: to,
        };
    }

    /// Nothing is expected until the node reports again (a reset, the MN's own silence).
    pub(crate) fn forget(&mut self) {
        *self = StateWatch::default();
    }

    /// Checks the NMT state a PRes said. The MN's own cycle moves a node on from
    /// NOT_ACTIVE, BASIC_ETHERNET and PRE_OPERATIONAL_1 (its SoC leads to PRE_OPERATIONAL_2,
    /// DS 301 NMT_CT4 and NMT_CT11's way back); a node that fell back to PRE_OPERATIONAL_2
    /// (an error of its own, a loss of SoC while the MN did not cycle) is taken at its word:
    /// the MN boots it again when it needs it higher.
    pub(crate) fn pres(&mut self, said: NmtState) -> Result<(), Unexpected> {
        let Some(expected) = self.state else {
            return Ok(());
        };
        if said == expected || Some(said) == self.next {
            return Ok(());
        }
        let moved_on = said == NmtState::PRE_OPERATIONAL_2
            && matches!(
                expected,
                NmtState::NOT_ACTIVE
                    | NmtState::BASIC_ETHERNET
                    | NmtState::PRE_OPERATIONAL_1
                    | NmtState::READY_TO_OPERATE
                    | NmtState::OPERATIONAL
            );
        if moved_on {
            self.reported(said);
            return Ok(());
        }
        Err(Unexpected { said, expected })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pres_in_the_reported_or_commanded_state_passes_another_does_not() {
        let mut w = StateWatch::default();
        assert_eq!(w.pres(NmtState::STOPPED), Ok(()), "nothing known yet");
        w.reported(NmtState::READY_TO_OPERATE);
        assert_eq!(w.pres(NmtState::READY_TO_OPERATE), Ok(()));
        assert_eq!(
            w.pres(NmtState::STOPPED),
            Err(Unexpected {
                said: NmtState::STOPPED,
                expected: NmtState::READY_TO_OPERATE
            })
        );
        // StartNode under way: the old state or the new one.
        w.commanded(
            Some(NmtState::READY_TO_OPERATE),
            Some(NmtState::OPERATIONAL),
        );
        assert_eq!(w.pres(NmtState::READY_TO_OPERATE), Ok(()));
        assert_eq!(w.pres(NmtState::OPERATIONAL), Ok(()));
        assert!(w.pres(NmtState(0x42)).is_err(), "no state at all");
        w.reported(NmtState::OPERATIONAL);
        assert!(w.pres(NmtState::READY_TO_OPERATE).is_err());
        assert!(w.pres(NmtState::PRE_OPERATIONAL_1).is_err());
        w.forget();
        assert_eq!(w.pres(NmtState::STOPPED), Ok(()));
    }

    #[test]
    fn a_node_the_cycle_moved_on_or_that_fell_back_to_pre_operational_2_is_taken_at_its_word() {
        for from in [
            NmtState::PRE_OPERATIONAL_1,
            NmtState::BASIC_ETHERNET,
            NmtState::OPERATIONAL,
        ] {
            let mut w = StateWatch::default();
            w.reported(from);
            assert_eq!(w.pres(NmtState::PRE_OPERATIONAL_2), Ok(()), "{from}");
            assert!(w.pres(NmtState::OPERATIONAL).is_err(), "not up alone");
        }
    }

    #[test]
    fn states_are_named_as_ds_301_names_a_cns() {
        assert_eq!(cs(NmtState::STOPPED), "NMT_CS_STOPPED (4Dh)");
        assert_eq!(cs(NmtState(0x42)), "42h");
    }
}
