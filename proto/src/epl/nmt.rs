//! The codes of POWERLINK network management (EPSG DS 301 §7.1 NMT state machines, §7.3.1 NMT
//! commands, §4.6.1.1.5 SoA requested services, §4.6.1.1.6 ASnd service ids). Open newtypes:
//! a frame may carry any byte, the names say which are defined.

use std::fmt;

macro_rules! open_code {
    ($(#[$m:meta])* $name:ident { $($(#[$cm:meta])* $c:ident = $v:expr, $text:expr;)* }) => {
        $(#[$m])*
        #[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
        pub struct $name(pub u8);

        impl $name {
            $($(#[$cm])* pub const $c: $name = $name($v);)*

            /// Every defined code.
            pub const ALL: &'static [$name] = &[$($name::$c),*];

            /// The code's name as DS 301 prints it, if defined.
            pub fn name(self) -> Option<&'static str> {
                match self {
                    $($name::$c => Some($text),)*
                    _ => None,
                }
            }

            /// The defined code of that name (as [`Self::name`] gives it, any case, `-` or
            /// `_` alike).
            pub fn by_name(name: &str) -> Option<$name> {
                let want = name.replace('-', "_").to_ascii_uppercase();
                $name::ALL.iter().copied().find(|c| {
                    c.name().map(|n| n.replace('-', "_").to_ascii_uppercase()) == Some(want.clone())
                })
            }
        }

        impl fmt::Debug for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                match self.name() {
                    Some(n) => write!(f, "{n}({:02X}h)", self.0),
                    None => write!(f, "{}({:02X}h)", stringify!($name), self.0),
                }
            }
        }

        impl fmt::Display for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                match self.name() {
                    Some(n) => f.write_str(n),
                    None => write!(f, "{:02X}h", self.0),
                }
            }
        }
    };
}

open_code! {
    /// An NMT state as the NMTStatus field of PRes, SoA, IdentResponse and StatusResponse
    /// carries it (DS 301 §7.1.4 table "NMT states"). The CN states of BU 0620 §2.4.4 / BU 2200
    /// §6.2 are the `NMT_CS_*` ones; the manuals call NOT_ACTIVE "Initialisation".
    NmtState {
        /// NMT_GS_OFF.
        OFF = 0x00, "OFF";
        /// NMT_GS_INITIALISING.
        INITIALISING = 0x19, "INITIALISING";
        /// NMT_GS_RESET_APPLICATION.
        RESET_APPLICATION = 0x29, "RESET_APPLICATION";
        /// NMT_GS_RESET_COMMUNICATION.
        RESET_COMMUNICATION = 0x39, "RESET_COMMUNICATION";
        /// NMT_GS_RESET_CONFIGURATION.
        RESET_CONFIGURATION = 0x79, "RESET_CONFIGURATION";
        /// NMT_CS_NOT_ACTIVE (MN: NMT_MS_NOT_ACTIVE): watching for POWERLINK frames.
        NOT_ACTIVE = 0x1C, "NOT_ACTIVE";
        /// NMT_CS_PRE_OPERATIONAL_1: SDO, no process data, waiting for a SoC.
        PRE_OPERATIONAL_1 = 0x1D, "PRE_OPERATIONAL_1";
        /// NMT_CS_PRE_OPERATIONAL_2: cycle running, configured by the MN.
        PRE_OPERATIONAL_2 = 0x5D, "PRE_OPERATIONAL_2";
        /// NMT_CS_READY_TO_OPERATE: PRes sent, PReq data not evaluated.
        READY_TO_OPERATE = 0x6D, "READY_TO_OPERATE";
        /// NMT_CS_OPERATIONAL.
        OPERATIONAL = 0xFD, "OPERATIONAL";
        /// NMT_CS_STOPPED: no process data either way; left only by NMT command.
        STOPPED = 0x4D, "STOPPED";
        /// NMT_CS_BASIC_ETHERNET: no POWERLINK seen within the Basic Ethernet timeout; SDO over
        /// UDP/IP only.
        BASIC_ETHERNET = 0x1E, "BASIC_ETHERNET";
    }
}

open_code! {
    /// An NMT command id (DS 301 §7.3.1.2 "NMT state commands", §7.3.2 managing commands,
    /// §7.3.3 info services).
    NmtCommand {
        /// NMTStartNode: READY_TO_OPERATE → OPERATIONAL.
        START_NODE = 0x21, "StartNode";
        /// NMTStopNode: → STOPPED (from PRE_OPERATIONAL_1 up to OPERATIONAL).
        STOP_NODE = 0x22, "StopNode";
        /// NMTEnterPreOperational2: → PRE_OPERATIONAL_2 (from OPERATIONAL and
        /// STOPPED).
        ENTER_PRE_OPERATIONAL_2 = 0x23, "EnterPreOperational2";
        /// NMTEnableReadyToOperate: PRE_OPERATIONAL_2 → READY_TO_OPERATE.
        ENABLE_READY_TO_OPERATE = 0x24, "EnableReadyToOperate";
        /// NMTResetNode: → RESET_APPLICATION.
        RESET_NODE = 0x28, "ResetNode";
        /// NMTResetCommunication: → RESET_COMMUNICATION.
        RESET_COMMUNICATION = 0x29, "ResetCommunication";
        /// NMTResetConfiguration: → RESET_CONFIGURATION.
        RESET_CONFIGURATION = 0x2A, "ResetConfiguration";
        /// NMTSwReset: → INITIALISING (software reset).
        SW_RESET = 0x2B, "SwReset";
        /// NMTStartNodeEx (node list in the command data).
        START_NODE_EX = 0x41, "StartNodeEx";
        /// NMTStopNodeEx.
        STOP_NODE_EX = 0x42, "StopNodeEx";
        /// NMTEnterPreOperational2Ex.
        ENTER_PRE_OPERATIONAL_2_EX = 0x43, "EnterPreOperational2Ex";
        /// NMTEnableReadyToOperateEx.
        ENABLE_READY_TO_OPERATE_EX = 0x44, "EnableReadyToOperateEx";
        /// NMTResetNodeEx.
        RESET_NODE_EX = 0x48, "ResetNodeEx";
        /// NMTResetCommunicationEx.
        RESET_COMMUNICATION_EX = 0x49, "ResetCommunicationEx";
        /// NMTResetConfigurationEx.
        RESET_CONFIGURATION_EX = 0x4A, "ResetConfigurationEx";
        /// NMTSwResetEx.
        SW_RESET_EX = 0x4B, "SwResetEx";
        /// NMTNetHostNameSet.
        NET_HOST_NAME_SET = 0x62, "NetHostNameSet";
        /// NMTFlushArpEntry.
        FLUSH_ARP_ENTRY = 0x63, "FlushArpEntry";
        /// NMTInvalidService.
        INVALID_SERVICE = 0xFF, "InvalidService";
    }
}

impl NmtCommand {
    /// The state an NMT state command leads a CN in `from` to, or `None` when the command
    /// is not valid there (DS 301 §7.1.4.1 CN state transitions and the reset transitions
    /// NMT_GT1..GT4, as openPOWERLINK's CN implements them: StopNode from PRE_OPERATIONAL_1
    /// up to OPERATIONAL, EnterPreOperational2 from OPERATIONAL and STOPPED only, the resets
    /// from every CN state): the CN ignores it and stays.
    pub fn next_state(self, from: NmtState) -> Option<NmtState> {
        use NmtState as S;
        let cn = matches!(
            from,
            S::PRE_OPERATIONAL_1
                | S::PRE_OPERATIONAL_2
                | S::READY_TO_OPERATE
                | S::OPERATIONAL
                | S::STOPPED
                | S::BASIC_ETHERNET
        );
        match self {
            NmtCommand::ENABLE_READY_TO_OPERATE if from == S::PRE_OPERATIONAL_2 => {
                Some(S::READY_TO_OPERATE)
            }
            NmtCommand::START_NODE if from == S::READY_TO_OPERATE => Some(S::OPERATIONAL),
            NmtCommand::STOP_NODE
                if matches!(
                    from,
                    S::PRE_OPERATIONAL_1
                        | S::PRE_OPERATIONAL_2
                        | S::READY_TO_OPERATE
                        | S::OPERATIONAL
                ) =>
            {
                Some(S::STOPPED)
            }
            NmtCommand::ENTER_PRE_OPERATIONAL_2 if matches!(from, S::OPERATIONAL | S::STOPPED) => {
                Some(S::PRE_OPERATIONAL_2)
            }
            NmtCommand::RESET_NODE if cn => Some(S::RESET_APPLICATION),
            NmtCommand::RESET_COMMUNICATION if cn => Some(S::RESET_COMMUNICATION),
            NmtCommand::RESET_CONFIGURATION if cn => Some(S::RESET_CONFIGURATION),
            NmtCommand::SW_RESET if cn => Some(S::INITIALISING),
            _ => None,
        }
    }
}

open_code! {
    /// The service a SoA asks for (DS 301 §4.6.1.1.5 "RequestedServiceID").
    RequestedService {
        /// No asynchronous frame this cycle.
        NO_SERVICE = 0x00, "NoService";
        /// The target answers with an IdentResponse.
        IDENT_REQUEST = 0x01, "IdentRequest";
        /// The target answers with a StatusResponse.
        STATUS_REQUEST = 0x02, "StatusRequest";
        /// The target may send an NMTRequest.
        NMT_REQUEST_INVITE = 0x03, "NMTRequestInvite";
        /// The target may send any ASnd (SDO, …) or a legacy Ethernet frame.
        UNSPECIFIED_INVITE = 0xFF, "UnspecifiedInvite";
    }
}

open_code! {
    /// The service of an ASnd frame (DS 301 §4.6.1.1.6 "ServiceID").
    ServiceId {
        /// IdentResponse.
        IDENT_RESPONSE = 0x01, "IdentResponse";
        /// StatusResponse.
        STATUS_RESPONSE = 0x02, "StatusResponse";
        /// NMTRequest (CN to MN).
        NMT_REQUEST = 0x03, "NMTRequest";
        /// NMTCommand (MN to CN).
        NMT_COMMAND = 0x04, "NMTCommand";
        /// SDO.
        SDO = 0x05, "SDO";
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_codes() {
        assert_eq!(NmtState::PRE_OPERATIONAL_2.0, 0x5D);
        assert_eq!(
            NmtState::by_name("ready-to-operate"),
            Some(NmtState::READY_TO_OPERATE)
        );
        assert_eq!(NmtState(0x42).name(), None);
        assert_eq!(format!("{}", NmtState(0x42)), "42h");
        assert_eq!(
            NmtCommand::by_name("startnode"),
            Some(NmtCommand::START_NODE)
        );
        assert_eq!(
            format!("{:?}", NmtCommand(0x24)),
            "EnableReadyToOperate(24h)"
        );
    }

    #[test]
    fn the_cn_boot_sequence_and_refusals() {
        use NmtCommand as C;
        use NmtState as S;
        let seq = [
            (C::ENABLE_READY_TO_OPERATE, S::READY_TO_OPERATE),
            (C::START_NODE, S::OPERATIONAL),
            (C::STOP_NODE, S::STOPPED),
            (C::ENTER_PRE_OPERATIONAL_2, S::PRE_OPERATIONAL_2),
        ];
        let mut s = S::PRE_OPERATIONAL_2;
        for (c, want) in seq {
            s = c.next_state(s).unwrap();
            assert_eq!(s, want);
        }
        // StartNode straight from PRE_OPERATIONAL_2 or _1 is not a CN transition.
        assert_eq!(C::START_NODE.next_state(S::PRE_OPERATIONAL_2), None);
        assert_eq!(C::START_NODE.next_state(S::PRE_OPERATIONAL_1), None);
        assert_eq!(C::ENABLE_READY_TO_OPERATE.next_state(S::OPERATIONAL), None);
        assert_eq!(
            C::STOP_NODE.next_state(S::PRE_OPERATIONAL_1),
            Some(S::STOPPED)
        );
        assert_eq!(
            C::ENTER_PRE_OPERATIONAL_2.next_state(S::READY_TO_OPERATE),
            None
        );
        assert_eq!(
            C::RESET_NODE.next_state(S::OPERATIONAL),
            Some(S::RESET_APPLICATION)
        );
        assert_eq!(C(0x30).next_state(S::OPERATIONAL), None);
    }
}
