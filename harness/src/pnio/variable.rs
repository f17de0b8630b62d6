//! The bytes of PROFINET IO frames whose values a device picks anew for every start, AR or
//! call, masked before transcripts are compared (`--snapshots`, `harness diff`): two runs
//! against the same device differ there without anything having changed.

use std::ops::Range;

use crate::bus::Variable;

/// The registry's entry for the bus.
pub(crate) const VARIABLE: Variable = Variable {
    bytes,
    decoded: str::to_string,
};

/// DCE RPC header (C706 §12.5, IEC 61158-6-10 §4.10.3.2): version 4 first; the activity UUID
/// (whose calls a device's own are), the server boot time and the sequence number.
const RPC_VERSION: u8 = 4;
const RPC_HEADER: usize = 80;
const ACTIVITY_AND_BOOT_TIME: Range<usize> = 40..60;
const SEQUENCE_NUMBER: Range<usize> = 64..68;
/// Frame ids of cyclic RT data (IEC 61158-6-10 Table "FrameID"): RT_CLASS_1/2/3 and UDP.
const CYCLIC: std::ops::RangeInclusive<u16> = 0x0100..=0xFBFF;
/// Frame ids of the acyclic alarm frames (high and low priority).
const ALARMS: [u16; 2] = [0xFC01, 0xFE01];

/// The variable byte ranges of `frame` from its frame id (or RPC header) on.
#[allow(clippy::single_range_in_vec_init)] // one range of bytes, not the bytes of a range
fn bytes(frame: &[u8]) -> Vec<Range<usize>> {
    let len = frame.len();
    let frame_id = frame.get(..2).map(|b| u16::from_be_bytes([b[0], b[1]]));
    if frame.first() == Some(&RPC_VERSION) && len >= RPC_HEADER {
        vec![ACTIVITY_AND_BOOT_TIME, SEQUENCE_NUMBER]
    } else if frame_id.is_some_and(|id| CYCLIC.contains(&id)) && len >= 6 {
        // The provider's cycle counter, before data status and transfer status.
        vec![len - 4..len - 2]
    } else if frame_id.is_some_and(|id| ALARMS.contains(&id)) && len >= 12 {
        // The alarm endpoints and the send/acknowledge sequence numbers of the RTA header.
        vec![2..6, 8..12]
    } else {
        Vec::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rpc_calls_mask_activity_boot_time_and_sequence() {
        let mut rpc = vec![0u8; 100];
        rpc[0] = 4;
        assert_eq!(bytes(&rpc), vec![40..60, 64..68]);
        assert!(
            !bytes(&rpc[..60]).contains(&ACTIVITY_AND_BOOT_TIME),
            "too short for a header"
        );
    }

    #[test]
    fn cyclic_frames_mask_the_cycle_counter_alarms_their_sequence() {
        let cyclic = [0x80, 0x00, 0x0B, 0x31, 0x29, 0x20, 0x35, 0x00];
        assert_eq!(bytes(&cyclic), vec![4..6]);
        let alarm = [0xFC, 0x01, 0, 1, 0, 2, 0x11, 0, 0, 5, 0, 4, 0, 0];
        assert_eq!(bytes(&alarm), vec![2..6, 8..12]);
        let dcp = [0xFE, 0xFE, 5, 0, 0, 0, 0, 0];
        assert_eq!(bytes(&dcp), Vec::<Range<usize>>::new());
    }
}
